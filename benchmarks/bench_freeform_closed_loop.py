"""Closed loop of method M3 on the virtual machine: recovered normal deviations per method.

Run:  .venv/bin/python benchmarks/bench_freeform_closed_loop.py

``samples/freeform/freeform.toml`` (8 guide points on the B-spline top face) with each
method; the Fanuc program runs on the virtual machine (DPRNT log, 4 decimals) and the
DMIS program on the virtual CMM (output file, 5 decimals); perfect probe, 3 mm ball.
Placements: nominal, and the part moved by (0.02, -0.03, 0.05) mm.  Prints per method,
dialect and placement the largest |e − e_expected| (µm; expected: 0, or the shift along
the nominal normal ``offset · n``) and the largest |e| (µm).
"""

from __future__ import annotations

import dataclasses
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

OFFSETS = ((0.0, 0.0, 0.0), (0.02, -0.03, 0.05))
METHODS = ("vertical", "vertical2d", "microplane", "vector")


def main() -> None:
    from probegen import cad
    from probegen.dialects import get_dialect
    from probegen.evaluate.ingest import ingest, ingest_dmis_freeform
    from probegen.machine.probe_model import ProbeModel
    from probegen.planning import plan_program
    from probegen.results import parse_dmis_output
    from probegen.sim.contact import PlacedPart
    from probegen.sim.vm import VirtualMachine, run_text
    from probegen.spec.model import load_spec

    spec = load_spec(REPO / "samples/freeform/freeform.toml")
    model = cad.load_step(REPO / "samples/freeform/freeform.step")
    print(f"{'method':<11} {'dialect':<6} {'offset':<18} {'points':>6} "
          f"{'max|e-exp| um':>14} {'max|e| um':>10}")
    with tempfile.TemporaryDirectory() as tmp:
        for offset in OFFSETS:
            for method in METHODS:
                f = dataclasses.replace(spec.features[0], method=method)
                s = dataclasses.replace(spec, features=(f,))
                for name in ("fanuc", "dmis"):
                    d = get_dialect(name)
                    planned = plan_program(s, runtime_variables=d.RUNTIME_VARIABLES)
                    vm = VirtualMachine(PlacedPart.from_model(
                        model, translation=np.array(offset)), ProbeModel(3.0))
                    res = run_text(d.generate(planned.program), vm,
                                   kind="macrob" if name == "fanuc" else "dmis")
                    if name == "fanuc":
                        log = Path(tmp) / "run.log"
                        log.write_text(res.output)
                        r = ingest(log, s).freeform[0]
                    else:
                        r = ingest_dmis_freeform(parse_dmis_output(res.output), s)[0][0]
                    e = np.array(r.residuals)
                    exp = np.array(r.directions) @ np.array(offset)
                    print(f"{method:<11} {name:<6} {str(offset):<18} {len(e):>6} "
                          f"{1e3 * np.abs(e - exp).max():>14.2f} {1e3 * np.abs(e).max():>10.2f}")


if __name__ == "__main__":
    main()
