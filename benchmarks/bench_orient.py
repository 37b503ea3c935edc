"""Benchmark: revolved features in every orientation a machine reaches (issue 17, item 2).

Run:  .venv/bin/python benchmarks/bench_orient.py [MODEL.stp ...]

Without arguments: NIST FTC 9 (every axis horizontal) and CTC 2.  Per model and per
machine (the VMC sample as it is; with a CMM head ``Head()`` to DMIS; with a five-axis
tilt ``Tilt()``; both with a rack of 1, 2, 3 and 6 mm styli): the code path of ``plan
--all-revolved`` (``all_revolved_spec`` + ``plan_program``, the whole program's collision
check included): features planned and left out (the reasons, numbers masked, most
frequent first), stylus and orientation changes of the program, and the times.  First,
the cost of ``Part.turned`` (one rotation: turned face records with their exact boxes,
the moved shape) against the load and the tessellation it does not repeat.
"""

from __future__ import annotations

import re
import sys
import time
from collections import Counter
from dataclasses import replace
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

MACHINE = REPO / "samples/machines/vmc-fanuc.toml"
NIST = Path("/work/shared/ref/nist-step")
MODELS = [NIST / "nist_ftc_09_asme1_rd.stp", NIST / "nist_ctc_02_asme1_rc.stp"]


def profiles() -> dict[str, object]:
    from probegen.machine.profile import Head, Stylus, Tilt, load_profile

    rack = (Stylus("D1", 1.0, 0.7, 20.0, 21), Stylus("D2", 2.0, 1.4, 30.0, 22),
            Stylus("D3", 3.0, 2.0, 40.0, 23), Stylus("D6", 6.0, 4.5, 50.0, 20))
    base = load_profile(MACHINE)
    return {"vertical": base,
            "head": replace(base, dialect="dmis", head=Head(), rack=rack),
            "tilt": replace(base, tilt=Tilt(), rack=rack)}


def turned_cost(model: Path) -> None:
    from probegen import cad
    from probegen.ir import frames

    t = time.perf_counter()
    part = cad.load_part(model)
    load = time.perf_counter() - t
    t = time.perf_counter()
    part.mesh()
    mesh = time.perf_counter() - t
    t = time.perf_counter()
    turned = part.turned(frames.frame_for((1.0, 0.0, 0.0)))
    turn = time.perf_counter() - t
    t = time.perf_counter()
    turned.mesh()
    turned_mesh = time.perf_counter() - t
    print(f"{model.name}: {len(part.faces)} faces; load {load:.2f} s, tessellation "
          f"{mesh:.2f} s, turned {turn:.3f} s, its mesh {turned_mesh:.4f} s")


def run(model: Path, name: str, machine: object) -> None:
    from probegen import cad
    from probegen.planning import plan_program
    from probegen.planning.revolved_spec import all_revolved_spec

    part = cad.load_part(model)
    t = time.perf_counter()
    spec, notes = all_revolved_spec(part, machine)  # type: ignore[arg-type]
    choose = time.perf_counter() - t
    t = time.perf_counter()
    planned = plan_program(spec, runtime_variables=name != "head", part=part)
    program = time.perf_counter() - t
    print(f"{model.name} {name}: planned {len(spec.features)}, left out {len(notes)}; "
          f"changes: {planned.stylus_changes} stylus, {planned.orientation_changes} "
          f"orientation; all-revolved {choose:.1f} s, program {program:.1f} s")
    reasons = Counter(re.sub(r"-?[\d.]+", "#", n.split(": ", 1)[1].split(" [")[0])[:100]
                      for n in notes)
    for reason, count in reasons.most_common(8):
        print(f"  {count:>4}  {reason}")


def main() -> None:
    models = [Path(a) for a in sys.argv[1:]] or MODELS
    turned_cost(models[-1])
    for model in models:
        for name, machine in profiles().items():
            run(model, name, machine)


if __name__ == "__main__":
    main()
