"""Benchmark: how well the in-process decisions set a part up (docs/actions.md).

Run:  .venv/bin/python benchmarks/bench_actions.py [--noise 0.0002] [--seed 7]

Compiles samples/bore_block/bore_block_actions.toml for Fanuc, runs it on the virtual
machine against the bore_block placed at G54 + shift, turned by an angle, for a few
placements (noise-free, then with the probe's lobing and ``--noise`` mm of seeded
trigger noise), and prints per run:

* ``frame um``: the largest distance, over the part's 8 bounding-box corners, between
  where the program's final frame (G54 + G68) puts the part and where it really is;
* ``angle urad``: the G68 angle's error;
* ``wear um``: the D wear written for tool 12 minus the planted bore's half oversize;
* ``agree``: the largest |offline - machine| of the ``RES`` values, in units of each
  value's agreement limit (<= 1 means every value agrees; ``probegen ingest``).
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from probegen import cad  # noqa: E402
from probegen.dialects import get_dialect  # noqa: E402
from probegen.evaluate.ingest import ingest  # noqa: E402
from probegen.machine.probe_model import Lobing, ProbeModel  # noqa: E402
from probegen.planning import plan_program  # noqa: E402
from probegen.sim.contact import PlacedPart  # noqa: E402
from probegen.sim.vm import VirtualMachine, run_text  # noqa: E402
from probegen.spec.model import load_spec  # noqa: E402

SPEC = REPO / "samples/bore_block/bore_block_actions.toml"
WORK = np.array([300.0, 200.0, -100.0])
PLACEMENTS = (((1.234, -0.8, 0.3), 0.5), ((-1.5, 1.2, -0.4), -0.8), ((0.0, 0.0, 0.0), 0.0),
              ((0.6, 1.2, 0.0), 0.25))
OVERSIZE = 0.03


def rot_z(degrees: float) -> np.ndarray:
    a = math.radians(degrees)
    return np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0],
                     [0.0, 0.0, 1.0]])


def run_once(text: str, model: cad.Model, shift: np.ndarray, degrees: float,
             probe: ProbeModel, tmp: Path) -> tuple[float, float, float, float]:
    part = PlacedPart.from_model(model, rotation=rot_z(degrees), translation=WORK + shift)
    res = run_text(text, VirtualMachine(part, probe), kind="macrob", work_offset=tuple(WORK))
    if res.alarm is not None or res.rotation is None:
        raise SystemExit(f"run stopped: {res.alarm}")
    g54 = np.array([res.variables.get(5221 + i, 0.0) for i in range(3)])
    cx, cy, r = res.rotation
    c = np.array([cx, cy, 0.0])
    corners = np.array(list(itertools.product((0.0, 100.0), (0.0, 100.0), (0.0, 70.0))))
    programmed = (rot_z(r) @ (corners - c).T).T + c + g54
    real = (rot_z(degrees) @ corners.T).T + WORK + shift
    frame = float(np.max(np.linalg.norm(programmed - real, axis=1)))
    wear = res.variables.get(12012, 0.0) - OVERSIZE / 2.0
    log = tmp / "run.log"
    log.write_text(res.output)
    decisions = ingest(log, load_spec(SPEC)).decisions
    agree = max(abs(d.offline - d.machine) / d.limit for d in decisions
                if d.offline is not None and d.machine is not None and d.limit > 0)
    return frame * 1e3, math.radians(r - degrees) * 1e6, wear * 1e3, agree


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--noise", type=float, default=0.0002, help="trigger noise, mm")
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args()
    spec = load_spec(SPEC)
    text = get_dialect("fanuc").generate(plan_program(spec, runtime_variables=True).program)
    sys.path.insert(0, str(REPO / "samples/bore_block"))
    import make_model  # type: ignore[import-not-found]

    with tempfile.TemporaryDirectory() as name:
        tmp = Path(name)
        step = make_model.main(tmp / "bore.step", bore_diameter=50.0 + OVERSIZE)
        model = cad.load_step(step)
        probes = (("noise-free", ProbeModel(3.0)),
                  (f"lobing + {args.noise} mm noise",
                   ProbeModel(3.0, Lobing(0.0012, 0.0008, 0.0005), noise_sigma=args.noise,
                              seed=args.seed)))
        print(f"{'probe':<26} {'shift mm':<22} {'deg':>6} {'frame um':>9} "
              f"{'angle urad':>10} {'wear um':>8} {'agree':>6}")
        for (label, probe), (shift, degrees) in itertools.product(probes, PLACEMENTS):
            f, a, w, g = run_once(text, model, np.array(shift), degrees, probe, tmp)
            print(f"{label:<26} {str(shift):<22} {degrees:>6.2f} {f:>9.4f} {a:>10.4f} "
                  f"{w:>8.4f} {g:>6.2f}")


if __name__ == "__main__":
    main()
