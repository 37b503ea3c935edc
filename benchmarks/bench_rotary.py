"""Method M4 on the virtual machine: recovery of planted rotary errors, with and without
trigger noise, and how well the reported standard uncertainties match the scatter.

Run: ``PYTHONPATH=. python benchmarks/bench_rotary.py [--seeds 20]``
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from probegen.calibrate.rotary import identify_m4, identify_pivot
from probegen.dialects import get_dialect
from probegen.machine.errors_model import ErrorModel, RotaryErrors
from probegen.machine.kinematics import Machine, Topology
from probegen.machine.probe_model import Lobing, ProbeModel
from probegen.planning.rotary import RotaryPlan, plan_rotary
from probegen.planning.rotary_spec import load_rotary_spec
from probegen.results.dprnt import parse_dprnt
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import VirtualMachine, run_text

REPO = Path(__file__).resolve().parents[1]
UM, URAD = 1e-3, 1e-6
ERRORS = ErrorModel(
    b=RotaryErrors(np.array([6.0, 0.0, -8.0]) * UM, np.array([12.0, 0.0, -20.0]) * URAD),
    c=RotaryErrors(np.array([-12.0, -4.0, 0.0]) * UM, np.array([10.0, -15.0, 0.0]) * URAD))
TRUTH = {"EX0C": -12.0 * UM, "EY0C": -4.0 * UM, "EA0C": 10.0 * URAD, "EB0C": -15.0 * URAD,
         "EX0B": 6.0 * UM, "EZ0B": -8.0 * UM, "EA0B": 12.0 * URAD, "EC0B": -20.0 * URAD}
LOBING = Lobing(lateral=0.004, axial=0.0015)
"""M4: anisotropic pre-travel (its epsilon); the pivot test gets an isotropic one (an
anisotropic pre-travel moves every cap's centre along the stylus: an apparent EZ0B)."""
ISOTROPIC = Lobing(lateral=0.003, axial=0.003)


def log_of(plan: RotaryPlan, noise: float, seed: int) -> str:
    spec = plan.spec
    lobing = LOBING if spec.kind == "m4" else ISOTROPIC
    vm = VirtualMachine(
        PlacedPart.from_spheres([spec.sphere_centre], [spec.sphere_radius]),
        ProbeModel(spec.machine.probe.ball_radius, lobing, noise_sigma=noise, seed=seed),
        Machine(Topology.FIVE_AXIS_BC, ERRORS, spec.pivot_length))
    res = run_text(get_dialect("fanuc").generate(plan.program), vm, kind="macrob")
    assert res.alarm is None, res.alarm
    return res.output


def m4_row(plan: RotaryPlan, noise: float, seed: int) -> tuple[float, float, float, float]:
    r = identify_m4(plan, parse_dprnt(log_of(plan, noise, seed), strict=True))
    delta = TRUTH["EX0B"] - TRUTH["EX0C"]
    epsilon = LOBING.lateral - LOBING.axial + TRUTH["EZ0B"]
    return r.delta - delta, r.u_delta, r.epsilon - epsilon, r.u_epsilon


def pivot_row(plan: RotaryPlan, noise: float, seed: int) -> dict[str, tuple[float, float]]:
    r = identify_pivot(plan, parse_dprnt(log_of(plan, noise, seed), strict=True))
    return {n: (v - TRUTH[n], u) for a in (r.c, r.b)
            for n, v, u in zip(a.names, a.values, a.uncertainties, strict=True)}


def fmt(name: str, v: float) -> str:
    return f"{v / UM:8.4f} um" if name[1] in "XYZ" else f"{v / URAD:8.4f} urad"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--noise", type=float, default=0.001, help="trigger sigma, mm")
    args = parser.parse_args()
    m4 = plan_rotary(load_rotary_spec(REPO / "samples/rotary/m4.toml"))
    pivot = plan_rotary(load_rotary_spec(REPO / "samples/rotary/pivot.toml"))
    t0 = time.perf_counter()
    d, _, e, _ = m4_row(m4, 0.0, 0)
    print(f"noise-free M4: delta error {fmt('EX', d)}, epsilon error {fmt('EX', e)}")
    for name, (err, _) in pivot_row(pivot, 0.0, 0).items():
        print(f"noise-free pivot: {name} error {fmt(name, err)}")
    print(f"\nwith trigger noise sigma {args.noise / UM:g} um, {args.seeds} seeds: "
          f"observed RMS error vs mean reported u (ratio ~1 when consistent)")
    rows = [m4_row(m4, args.noise, s) for s in range(args.seeds)]
    for label, k in (("delta", 0), ("epsilon", 2)):
        rms = math.sqrt(np.mean([r[k] ** 2 for r in rows]))
        u = float(np.mean([r[k + 1] for r in rows]))
        print(f"M4 {label:8} RMS error {fmt('EX', rms)}  mean u {fmt('EX', u)}  "
              f"ratio {rms / u:.2f}")
    prows = [pivot_row(pivot, args.noise, s) for s in range(args.seeds)]
    z = []
    for name in TRUTH:
        rms = math.sqrt(np.mean([r[name][0] ** 2 for r in prows]))
        u = float(np.mean([r[name][1] for r in prows]))
        z += [r[name][0] / r[name][1] for r in prows]
        print(f"pivot {name} RMS error {fmt(name, rms)}  mean u {fmt(name, u)}  "
              f"ratio {rms / u:.2f}")
    print(f"pivot: RMS of (error / u) over all values and seeds "
          f"{math.sqrt(np.mean(np.square(z))):.2f}")
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
