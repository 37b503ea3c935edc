"""The ``probegen rotary`` commands (method M4): plan, run on the virtual machine, identify.

::

    probegen rotary plan samples/rotary/m4.toml -o out/
    probegen rotary sim out/m4.nc --spec samples/rotary/m4.toml \\
        --errors samples/machines/five-axis-bc.toml --lobing 0.002 0.001 0 -o run.log
    probegen rotary identify run.log --spec samples/rotary/m4.toml --compensation comp.nc
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from probegen.cli.options import dialect_help
from probegen.cli.plan import _target
from probegen.cli.probe import add_probe_options, probe_from_args
from probegen.errors import ExitCode, ProbegenError
from probegen.files import read_input, write_file


def add_rotary_commands(sub: Any) -> None:
    """Register ``rotary plan|sim|identify`` on the top-level subparsers ``sub``."""
    ro = sub.add_parser("rotary", help="rotary-axis tests of a five-axis machine (B +-90 deg test, "
                                         "pivot calibration)")
    rsub = ro.add_subparsers(dest="rotary_command", required=True,
                             metavar="{plan,sim,identify}")
    p = rsub.add_parser("plan", help="plan a rotary test spec and write its program")
    p.add_argument("spec", help="rotary test spec (TOML), e.g. samples/rotary/m4.toml")
    p.add_argument("-d", "--dialect", default="fanuc",
                   help=f"dialect (default fanuc): {dialect_help(machine_tool=True)}")
    p.add_argument("-o", "--output", default="out",
                   help="output file, folder, or - for stdout (default: out/)")
    p.set_defaults(func=_plan)
    s = rsub.add_parser("sim", help="run a rotary test program on the virtual machine")
    s.add_argument("program", help="the Macro B program")
    s.add_argument("--spec", required=True, help="the spec (the sphere, the pivot length)")
    s.add_argument("--errors", required=True,
                   help="five-axis kinematics and errors (TOML), e.g. five-axis-bc.toml")
    add_probe_options(s)
    s.add_argument("-o", "--output", default="-", help="the DPRNT log (default -)")
    s.set_defaults(func=_sim)
    i = rsub.add_parser("identify", help="the rotary-axis errors from a test's DPRNT log")
    i.add_argument("log", help="the raw DPRNT log")
    i.add_argument("--spec", required=True, help="the spec the program was planned from")
    i.add_argument("--compensation", metavar="FILE",
                   help="write the work-offset update as a Fanuc program")
    i.add_argument("--calibration", metavar="FILE",
                   help="probe calibration (ingest --write-calibration) to compensate with")
    i.set_defaults(func=_identify)


def _plan(args: argparse.Namespace) -> int:
    from probegen.dialects import get_dialect
    from probegen.dialects.split import fit
    from probegen.planning.rotary import plan_rotary
    from probegen.planning.rotary_spec import load_rotary_spec

    spec = load_rotary_spec(args.spec)
    spec.machine.check_program_number(spec.program_number, f"{spec.source}: program.number")
    plan = plan_rotary(spec)
    dialect = get_dialect(args.dialect)
    text = fit(dialect, plan.program, splits=False).main  # O<n+1> is the offset update's
    if args.output == "-":
        sys.stdout.write(text)
        return ExitCode.OK
    target = write_file(_target(args.output, Path(args.spec).stem, dialect.EXTENSION, 1), text,
                        "the rotary test program", encoding="ascii")
    for st in plan.stations:
        print(f"{st.feature:5} B{st.b:7.2f} C{st.c:7.2f}  {len(st.directions):2} touches  "
              f"retract {st.retract:.1f} mm")
    print(f"least spare clearance {plan.clearance:.3f} mm; wrote {target}")
    return ExitCode.OK


def _sim(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from probegen.machine.kinematics import Topology, load_machine
    from probegen.planning.rotary_spec import load_rotary_spec
    from probegen.sim.contact import PlacedPart
    from probegen.sim.vm import VirtualMachine, program_control, run_text

    spec = load_rotary_spec(args.spec)
    machine = load_machine(args.errors)
    if machine.topology is not Topology.FIVE_AXIS_BC:
        raise ProbegenError(f"{args.errors}: expected a five-axis-bc machine, found "
                            f"{machine.topology}")
    if machine.pivot_length == 0.0:
        machine = replace(machine, pivot_length=spec.pivot_length)
    part = PlacedPart.from_spheres([spec.sphere_centre], [spec.sphere_radius])
    probe = probe_from_args(args, spec.machine.probe.ball_radius)
    text = read_input(args.program, "the rotary test program (Macro B)", encoding="ascii")
    result = run_text(text, VirtualMachine(part, probe, machine), kind="macrob",
                      source=args.program, control=program_control(args.program))
    if args.output == "-":
        sys.stdout.write(result.output)
    else:
        write_file(args.output, result.output.encode("ascii", errors="replace"),
                   "the DPRNT log")
        print(f"{result.touches} touches; wrote {args.output}")
    if result.alarm:
        print(f"probegen: alarm {result.alarm}", file=sys.stderr)
        return ExitCode.SIM_ALARM
    return ExitCode.OK


def _identify(args: argparse.Namespace) -> int:
    from probegen.calibrate.rotary import identify_m4, identify_pivot
    from probegen.machine.calibration import UNCALIBRATED, load_calibration
    from probegen.planning.rotary import plan_rotary
    from probegen.planning.rotary_spec import load_rotary_spec
    from probegen.results.dprnt import read_dprnt

    spec = load_rotary_spec(args.spec)
    cal = load_calibration(args.calibration) if args.calibration else None
    plan = plan_rotary(spec)
    log = read_dprnt(args.log)
    for diag in log.diagnostics:
        print(f"diagnostic: {diag}")
    print(f"probe: {UNCALIBRATED if cal is None else cal.describe()}")
    if spec.kind == "m4":
        m4 = identify_m4(plan, log, cal)
        print(m4_table(m4))
        shift = m4.compensation
    else:
        pivot = identify_pivot(plan, log, cal)
        print(pivot_table(pivot))
        shift = pivot.compensation
    if args.compensation:
        _write_compensation(spec, shift, Path(args.compensation))
    return ExitCode.OK


def _write_compensation(spec: Any, shift: tuple[float, float, float], target: Path) -> None:
    from probegen.dialects import get_dialect
    from probegen.planning.rotary import compensation_program

    program = compensation_program(spec, shift)
    spec.machine.check_program_number(program.setup.program_number,
                                      f"{spec.source}: program.number + 1 (the work-offset "
                                      "update's number)")
    text = get_dialect("fanuc").generate(program)
    write_file(target, text, "the work-offset update", encoding="ascii")
    print(f"wrote the work-offset update {target}")


def _um(v: float) -> str:
    return f"{v * 1e3:9.3f} um" if math.isfinite(v) else "      n/a"


def _t95(k: float, dof: int) -> str:
    """How the 95 % intervals were found: Student's t on the repeatability's dof."""
    if not math.isfinite(k):
        return "95 % intervals: none (no degrees of freedom)"
    return f"95 % intervals: +- t*u with Student t = {k:.3f} for {dof} dof"


def m4_table(r: Any) -> str:
    """The seed's test result as text (lengths in mm, errors in um)."""
    k = r.k95
    rows = [
        f"l1 {r.l1:.4f} mm   R1 {r.ball_radius:.4f} mm   r1 = r2 {r.r1:.4f} mm",
        f"x1 (B+90) {r.x1:.4f} mm   x2 (B-90) {r.x2:.4f} mm",
        f"delta rigid     {_um(r.delta_rigid)}  u {_um(r.u_delta_rigid)}  "
        f"95% +-{_um(k * r.u_delta_rigid)}",
        f"delta compliant {_um(r.delta)}  u {_um(r.u_delta)}  95% +-{_um(k * r.u_delta)}",
        f"epsilon         {_um(r.epsilon)}  u {_um(r.u_epsilon)}  "
        f"95% +-{_um(k * r.u_epsilon)}",
        f"touch repeatability {_um(r.sigma)} ({r.dof} dof)",
        _t95(k, r.dof),
        f"compensation: work offset X by {r.compensation[0]:+.4f} mm",
    ]
    return "\n".join(rows)


def pivot_table(r: Any) -> str:
    """The pivot calibration as text: each axis' location errors and station residuals."""
    rows: list[str] = []
    for a in (r.c, r.b):
        rows.append(f"{a.axis} axis ({len(a.angles)} stations, {a.dof} dof, chi2/dof "
                    f"{a.chi2:.2f}, touch sigma {_um(a.sigma).strip()} on {a.sigma_dof} dof)")
        t = a.k95
        for k, (name, v, u) in enumerate(zip(a.names, a.values, a.uncertainties, strict=True)):
            unit = (_um(v), _um(u), _um(t * u)) if k < 2 else (
                f"{v * 1e6:9.3f} urad", f"{u * 1e6:9.3f} urad", f"{t * u * 1e6:9.3f} urad")
            rows.append(f"  {name}  {unit[0]}  u {unit[1]}  95% +-{unit[2]}")
        rows.append(f"  {_t95(t, a.sigma_dof)}")
        rows.append(f"  circle radius {a.circle.radius:.4f} mm, roundness {_um(a.circle.form)}")
        for ang, res in zip(a.angles, a.residuals, strict=True):
            rows.append(f"  {a.axis}{ang:8.2f}  residual " + " ".join(_um(v) for v in res))
    rows.append(f"compensation: work offset X by {r.compensation[0]:+.4f} mm, "
                f"Y by {r.compensation[1]:+.4f} mm (onto the C axis)")
    return "\n".join(rows)
