"""Benchmark: planted form errors recovered through the whole loop (method M2).

Run:  .venv/bin/python benchmarks/bench_forms.py

Compiles ``samples/bore_block`` and ``samples/revolved_block`` for Fanuc, runs them on the
virtual machine with the part 0.3 / -0.2 mm off and form errors planted on its faces
(``probegen.sim.form``), ingests the DPRNT log and prints every characteristic with its
deviation from nominal, after a line with what was planted.  No pre-travel, no noise:
what differs from the planted values is the 4-decimal log and, for the lobes, their
sampling at 8 points per section (a 3-lobe of amplitude a sampled at 8 points spans
from 2a·cos(π/8) to 2a, depending on its phase).  The exact truth per touch is
checked in ``tests/test_closed_loop_forms.py``.
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from probegen import cad  # noqa: E402
from probegen.dialects import get_dialect  # noqa: E402
from probegen.evaluate.ingest import ingest  # noqa: E402
from probegen.evaluate.outputs import to_table  # noqa: E402
from probegen.machine.probe_model import ProbeModel  # noqa: E402
from probegen.planning import plan_program  # noqa: E402
from probegen.sim.contact import PlacedPart  # noqa: E402
from probegen.sim.form import FormError, Lobe  # noqa: E402
from probegen.sim.vm import VirtualMachine, run_text  # noqa: E402
from probegen.spec.model import load_spec  # noqa: E402

RUNS = {
    "samples/bore_block/bore_block.toml": (
        FormError(8, offset=0.004, taper=2e-4, lobes=(Lobe(3, 0.004, math.radians(20.0)),)),
        FormError(7, offset=-0.006)),
    "samples/revolved_block/revolved_block.toml": (
        FormError(7, offset=0.003, lobes=(Lobe(3, 0.004, 0.3),)),
        FormError(8, offset=0.005, lobes=(Lobe(4, 0.002, 0.2),)),
        FormError(6, offset=-0.002)),
}


def main() -> None:
    fanuc = get_dialect("fanuc")
    for path, forms in RUNS.items():
        spec = load_spec(ROOT / path)
        text = fanuc.generate(plan_program(spec, runtime_variables=True).program)
        assert spec.model is not None
        part = PlacedPart.from_model(cad.load_step(spec.model), translation=(0.3, -0.2, 0.0),
                                     forms=forms)
        vm = VirtualMachine(part, ProbeModel(3.0))
        res = run_text(text, vm, kind="macrob")
        print(f"{path}: {res.touches} touches, alarm {res.alarm}")
        for f in forms:
            lobes = ", ".join(f"{lb.k} lobes {lb.amplitude}" for lb in f.lobes) or "-"
            print(f"  planted on face {f.face}: offset {f.offset:+.4f}, taper {f.taper:g} "
                  f"mm/mm, {lobes}")
        with tempfile.TemporaryDirectory() as tmp:
            log = Path(tmp) / "run.log"
            log.write_text(res.output)
            print(to_table(ingest(log, spec)))


if __name__ == "__main__":
    main()
