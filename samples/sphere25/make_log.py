"""Write sphere_test.log: the DPRNT log the sample program would print, with known truth.

Run from the repository root:  .venv/bin/python samples/sphere25/make_log.py

Truth planted (also in sphere_test.truth.toml, which this script writes):
  * the sphere's real centre is (0.8, -1.2, 0.35) mm off nominal (the program locates it);
  * its real diameter is 25.0016 mm (the calibrated diameter in the spec is 25.0);
  * the probe's pre-travel (lobing) is d(n) = a0 + a2 * sin(theta)^2 * cos(2 phi) with
    a0 = 1.2 um and a2 = 0.8 um, theta/phi the polar angle and azimuth of the surface normal.

The log is produced by an ideal controller stepping through the planned IR: each touch
moves the ball centre from its start along -n until the ball meets the real sphere, then
travels d(n) further before the trigger registers; positions are printed as a Fanuc
control prints #5061[44] (4 decimals, sign only for negatives).

Expected results, derived by hand: the pattern has no constant-free first harmonic over
the octahedral points, so the least-squares sphere keeps the real centre; its radius is
R - a0; the radial residuals are a0 - d_i, so
  P_FTU = 2 a2 = 0.0016 mm,  D = 25.0016 - 2 a0 = 24.9992 mm,  P_STU = -0.0008 mm,
  effective stylus radius r - (R_cal - R_fit) = 3 - 0.0004 = 2.9996 mm.
(Second-order terms are below 1e-9 mm; printing rounds each coordinate to 5e-5 mm.)
"""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
OFFSET = np.array([0.8, -1.2, 0.35])
DIAMETER = 25.0016
A0, A2 = 0.0012, 0.0008


def pretravel(n: np.ndarray) -> float:
    theta = math.acos(max(-1.0, min(1.0, float(n[2]))))
    phi = math.atan2(float(n[1]), float(n[0]))
    return A0 + A2 * math.sin(theta) ** 2 * math.cos(2.0 * phi)


def fanuc_number(v: float) -> str:
    text = f"{v:.4f}"
    return "0.0000" if text == "-0.0000" else text


def run(program, ball: float, centre: np.ndarray) -> list[str]:  # type: ignore[no-untyped-def]
    from probegen import ir

    values: dict[str, float] = {}

    def val(c: ir.Coord) -> float:
        return values[c.name] + c.offset if isinstance(c, ir.Var) else c

    num, identity = program.setup.program_number, program.setup.identity
    lines = ["%", f"PGSTART O{num:04d} V1 {identity}"]
    for node in ir.walk(program.body):
        if isinstance(node, ir.Assign):
            a = val(node.a)
            values[node.name] = (a + val(node.b)) / 2 if node.b is not None else a + node.offset
        elif isinstance(node, ir.ReportCentre):
            values_xyz = [val(c) for c in node.centre]
            xyz = " ".join(f"{ax}{fanuc_number(v)}"
                           for ax, v in zip("XYZ", values_xyz, strict=True))
            lines.append(f"CTR {node.feature} {xyz}")
        elif isinstance(node, ir.Touch):
            n = np.array(node.normal)
            start = np.array([val(c) for c in node.contact]) + (ball + node.approach) * n
            w = start - centre
            b = float(w @ n)
            s = b - math.sqrt(b * b - (float(w @ w) - (DIAMETER / 2 + ball) ** 2))
            hit = start - (s + pretravel(n)) * n
            hit = np.round(hit, 4)  # the control's skip position in its increment
            for axis, name in enumerate(node.store):
                if name is not None:
                    values[name] = float(hit[axis])
            xyz = " ".join(f"{ax}{fanuc_number(v)}" for ax, v in zip("XYZ", hit, strict=True))
            lines.append(f"{node.role.value} {node.feature} {node.index} {xyz}")
    lines += [f"PGEND O{num:04d}", "%"]
    return lines


def main() -> int:
    os.chdir(REPO)
    from probegen.planning import plan_program
    from probegen.spec.model import load_spec

    spec = load_spec("samples/sphere25/sphere_test.toml")
    planned = plan_program(spec, runtime_variables=True)
    centre = np.array(planned.sphere_tests[0].sphere.centre) + OFFSET
    lines = run(planned.program, spec.machine.probe.ball_radius, centre)
    out = Path("samples/sphere25/sphere_test.log")
    out.write_bytes(("\n".join(lines) + "\n").encode("ascii"))
    truth = Path("samples/sphere25/sphere_test.truth.toml")
    truth.write_text(
        "# Known truth behind sphere_test.log (see make_log.py for the derivation).\n"
        f"centre = [{centre[0]:.4f}, {centre[1]:.4f}, {centre[2]:.4f}]\n"
        f"diameter = {DIAMETER - 2 * A0:.4f}\n"
        f"p_ftu = {2 * A2:.4f}\n"
        f"p_stu = {DIAMETER - 2 * A0 - 25.0:.4f}\n"
        f"effective_radius = {3.0 + (DIAMETER / 2 - A0) - 12.5:.4f}\n",
        encoding="ascii")
    print(f"wrote {out} ({len(lines)} lines) and {truth}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
