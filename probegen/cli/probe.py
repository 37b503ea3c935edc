"""The virtual machine's probe options, shared by ``probegen sim`` and ``probegen rotary sim``."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from probegen.cli import options as cli_types

if TYPE_CHECKING:
    from probegen.machine.probe_model import ProbeModel


def add_probe_options(parser: argparse.ArgumentParser) -> None:
    """``--lobing``, ``--noise`` and ``--seed``: the simulated probe's pre-travel and noise."""
    parser.add_argument("--lobing", type=cli_types.finite, nargs=3, default=(0.0, 0.0, 0.0),
                        metavar=("LATERAL", "AXIAL", "LOBE"), help="probe pre-travel, mm")
    parser.add_argument("--noise", type=cli_types.non_negative, default=0.0,
                        help="trigger noise sigma, mm")
    parser.add_argument("--seed", type=cli_types.seed, default=0, help="noise seed")


def probe_from_args(args: argparse.Namespace, ball_radius: float) -> ProbeModel:
    """The probe model of :func:`add_probe_options`' options for a ball of ``ball_radius`` mm
    (numpy is imported here, not when the command line starts)."""
    from probegen.machine.probe_model import Lobing, ProbeModel

    return ProbeModel(ball_radius, Lobing(*args.lobing), noise_sigma=args.noise,
                      seed=args.seed)
