
"""Method M5 end to end: grating programs, the virtual grating, identification, outputs.

The glue between planning (:mod:`probegen.planning.grating`), the dialects, the virtual
machine (:mod:`probegen.sim.grating`) and the identification
(:mod:`probegen.calibrate`), and the ``probegen grating`` commands.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from probegen import ir
from probegen.calibrate.grating_io import GratingReading, format_readings, read_level, read_readings
from probegen.calibrate.identify import Identification
from probegen.calibrate.identify_model import VolumetricModel
from probegen.cli import options as cli_types
from probegen.errors import CalibrationError, ExitCode, ProbegenError, UnsupportedError
from probegen.files import output_folder, write_file
from probegen.machine.kinematics import PLANES, Machine
from probegen.planning.grating import (
    GratingSpec,
    SetupPlan,
    build_program,
    load_grating_spec,
    plan_setup,
    setups,
)

DIALECTS = ("fanuc", "haas")
"""Dialects that can express a sampling stop (``G4``)."""


@dataclass(frozen=True)
class GratingProgram:
    """One setup's plan, IR and program text."""

    plan: SetupPlan
    program: ir.Program
    text: str
    file_name: str


def grating_programs(spec: GratingSpec, *, second_offset: bool = False,
                     second_head: bool = False, dialect: str = "fanuc") -> list[GratingProgram]:
    """One program per setup (see :mod:`probegen.planning.grating`).

    Raises:
        UnsupportedError: a dialect without sampling stops (DMIS, LinuxCNC: not done).
    """
    from probegen.dialects import get_dialect

    if dialect not in DIALECTS:
        raise UnsupportedError(f"grating programs: dialect {dialect!r} is not supported, "
                               f"expected one of {', '.join(DIALECTS)}")
    out = []
    for k, s in enumerate(setups(spec, second_offset=second_offset, second_head=second_head)):
        plan = plan_setup(spec, s)
        number = spec.program_number + k
        program = build_program(spec, plan, number)
        d = get_dialect(dialect)
        extra = ("_riser" if s.riser else "") + (f"_head{s.head_length:g}" if s.head_index
                                                 else "")
        name = f"O{number:04d}_{s.plane}{extra}{d.EXTENSION}"
        out.append(GratingProgram(plan, program, d.generate(program), name))
    return out


def readings_of(plan: SetupPlan, stops: Sequence[tuple[tuple[float, float, float], float,
                                                        float]]) -> list[GratingReading]:
    """Pair a run's stops (point, du, dv) with the plan's stops and lines.

    Raises:
        ProbegenError: the run's stops are not the plan's (count or position).
    """
    if len(stops) != len(plan.stops):
        raise ProbegenError(f"grating {plan.setup.label}: expected {len(plan.stops)} "
                            f"sampling stops, found {len(stops)}")
    for k, (point, _, _) in enumerate(stops):
        if not np.allclose(point, plan.stops[k], atol=1e-4, rtol=0.0):
            raise ProbegenError(f"grating {plan.setup.label}: stop {k}: expected "
                                f"{tuple(plan.stops[k])}, found {point}")
    s = plan.setup
    out = []
    for line, indices in plan.lines:
        for j, i in enumerate(indices):
            b = plan.base[i]
            out.append(GratingReading(s.plane, line, j, (float(b[0]), float(b[1]),
                                                          float(b[2])),
                                      s.riser, s.head_length, stops[i][1], stops[i][2]))
    return out


def simulate_readings(spec: GratingSpec, kinematics: Machine, *, second_offset: bool = False,
                      second_head: bool = False, noise: float = 0.0,
                      seed: int = 0) -> list[GratingReading]:
    """Run every setup's Fanuc program on the virtual grating; the readings, in order."""
    from probegen.sim.grating import VirtualGrating, run_grating

    out: list[GratingReading] = []
    for k, prog in enumerate(grating_programs(spec, second_offset=second_offset,
                                              second_head=second_head)):
        s = prog.plan.setup
        grating = VirtualGrating(kinematics, s.plane, s.w, s.head_length, noise, seed + k)
        stops = run_grating(prog.text, grating, tool=spec.tool, source=prog.file_name)
        out += readings_of(prog.plan, [(st.point, st.du, st.dv) for st in stops])
    return out


# ------------------------------------------------------------------------------ CLI


def _spec(args: argparse.Namespace) -> GratingSpec:
    return load_grating_spec(args.spec) if args.spec else GratingSpec()


def _plan(args: argparse.Namespace) -> int:
    out = output_folder(args.output, "the grating programs")
    for prog in grating_programs(_spec(args), second_offset=args.second_offset,
                                 second_head=args.second_head, dialect=args.dialect):
        write_file(out / prog.file_name, prog.text, "a grating program", encoding="ascii")
        print(f"wrote {out / prog.file_name} ({prog.plan.setup.label}, "
              f"{len(prog.plan.stops)} stops)")
    return ExitCode.OK


def _simulate(args: argparse.Namespace) -> int:
    from probegen.machine.kinematics import load_machine

    readings = simulate_readings(_spec(args), load_machine(args.errors),
                                 second_offset=args.second_offset,
                                 second_head=args.second_head, noise=args.noise,
                                 seed=args.seed)
    write_file(args.output, format_readings(readings), "the grating readings", encoding="ascii")
    print(f"wrote {args.output} ({len(readings)} readings)")
    return ExitCode.OK


def write_outputs(out: Path, result: Identification, stepwise: Identification | None,
                  head: float) -> list[str]:
    """Write the summary, tables, maps and plots into ``out``; the lines to print."""
    from probegen.calibrate.grating_out import (
        axis_table,
        fanuc_pitch_table,
        summary,
        volumetric_map,
    )

    output_folder(out, "the identification's files")
    text = summary(result, stepwise)
    if stepwise is not None:
        text += [""] + summary(stepwise)
    files = {"summary.txt": "\n".join(text) + "\n",
             "volumetric_map.csv": volumetric_map(result, head)}
    for axis, name in enumerate("xyz"):
        files[f"errors_{name}.csv"] = axis_table(result, axis)
        files[f"pitch_{name}_fanuc.csv"] = fanuc_pitch_table(result, axis)
    files.update(_plots(result, head))
    for name, content in files.items():
        write_file(out / name, content, "an identification file")
    return text + [f"wrote {len(files)} files into {out}"]


def _plots(result: Identification, head: float) -> dict[str, str]:
    """SVG files: each determined function against position; the error map per plane."""
    from probegen.calibrate.grating_out import reported_parameters
    from probegen.geometry.orthopoly import evaluate
    from probegen.report.plots import line_plot

    files = {}
    for f in result.functions:
        if f.coefficients is None:
            continue
        q = np.linspace(f.range.lo, f.range.hi, 41)
        v = evaluate(f.range, q, f.coefficients, f.function.lowest)
        band = f.band(q, result.k95)
        svg = line_plot(list(q), list(v), title=f"{f.function.name} ({f.function.kind})",
                        x_label=f"{'XYZ'[f.function.axis]} axis position, mm",
                        y_label=f.function.unit + ("" if band is None else ", 95 % band"),
                        band=None if band is None else list(band))
        files[f"plot_{f.function.name}.svg"] = _standalone(svg)
    ranges = tuple(result.functions[k].range for k in (0, 6, 12))
    model = VolumetricModel(ranges, result.degree)
    params = reported_parameters(result, model)
    for plane, axes in PLANES.items():
        files[f"map_{plane}.svg"] = _standalone(_quiver(model, params, plane, axes, head))
    return files


def _quiver(model: VolumetricModel, p: np.ndarray, plane: str, axes: tuple[int, int, int],
            head: float) -> str:
    """Arrows (from a dot at the nominal point) of the in-plane error on an 11 × 11 grid
    at mid-range of the third axis; the longest arrow is 0.9 of a grid cell."""
    from probegen.report.svg import Frame, line, nice_ticks, px, svg_open
    from probegen.report.svg import axes as draw_axes

    u, v, n = axes
    ranges = model.ranges
    gu, gv = np.meshgrid(np.linspace(ranges[u].lo, ranges[u].hi, 11),
                         np.linspace(ranges[v].lo, ranges[v].hi, 11), indexing="ij")
    q = np.zeros((gu.size, 3))
    q[:, u], q[:, v] = gu.ravel(), gv.ravel()
    q[:, n] = (ranges[n].lo + ranges[n].hi) / 2.0
    e = model.sensitivity(q, np.tile([0.0, 0.0, -head], (len(q), 1))) @ p
    biggest = float(np.max(np.hypot(e[:, u], e[:, v]))) or 1.0
    k = 0.9 * (ranges[u].hi - ranges[u].lo) / 10.0 / biggest  # longest arrow: 0.9 cell
    xt, yt = nice_ticks(ranges[u].lo, ranges[u].hi), nice_ticks(ranges[v].lo, ranges[v].hi)
    frame = Frame(480.0, 480.0, (xt[0][0], xt[0][-1]), (yt[0][0], yt[0][-1]))
    title = (f"{plane} error map at {'XYZ'[n]} = {q[0, n]:g} mm (longest arrow "
             f"{biggest:.3f} um)")
    out = [svg_open(480.0, 480.0, title)]
    out += draw_axes(frame, xt, yt, title=title, x_label=f"{'XYZ'[u]}, mm",
                     y_label=f"{'XYZ'[v]}, mm")
    for (a, b), (da, db) in zip(q[:, [u, v]], e[:, [u, v]], strict=True):
        out.append(f'<circle cx="{px(frame.x(a))}" cy="{px(frame.y(b))}" r="2" '
                   'fill="#1f5fa8"/>')  # the arrow's foot: the nominal point
        out.append(line(frame.x(a), frame.y(b), frame.x(a + k * da), frame.y(b + k * db),
                        "#1f5fa8", width=1.5))
    out.append("</svg>")
    return "\n".join(out)


def _standalone(svg: str) -> str:
    """An inline-HTML SVG as a file a browser opens (with the SVG namespace)."""
    return svg.replace("<svg ", '<svg xmlns="http://www.w3.org/2000/svg" ', 1) + "\n"


def _identify(args: argparse.Namespace) -> int:
    from probegen.calibrate.identify import identify_global
    from probegen.calibrate.identify_stepwise import identify_stepwise

    readings = read_readings(args.readings)
    level = read_level(args.roll) if args.roll else []
    result = identify_global(readings, level, degree=args.degree)
    try:
        stepwise: Identification | None = identify_stepwise(
            readings, level, max_degree=max(result.degree, 2))
    except CalibrationError as exc:  # not the seed's lines: the global fit stands alone
        print(f"stepwise identification skipped: {exc}")
        stepwise = None
    for line in write_outputs(Path(args.output), result, stepwise, readings[0].head):
        print(line)
    return ExitCode.OK


def add_grating_commands(sub: argparse._SubParsersAction) -> None:
    """Add ``probegen grating plan|simulate|identify`` to the CLI's subparsers."""
    g = sub.add_parser("grating", help="the 21 geometric errors of a three-axis machine "
                                         "from planar-grating readings")
    gs = g.add_subparsers(dest="grating_command", required=True,
                           metavar="{plan,simulate,identify}")
    p = gs.add_parser("plan", help="write the grating programs (one per setup)")
    p.add_argument("--spec", help="grating plan (TOML, see samples/grating/grating.toml)")
    p.add_argument("--second-offset", action="store_true",
                   help="add each plane's riser setup (separates the rolls)")
    p.add_argument("--second-head", action="store_true",
                   help="add each plane with the second (longer) head: separates the Z "
                        "axis' pitch and yaw from its straightness")
    p.add_argument("-d", "--dialect", default="fanuc",
                   help=f"dialect: {' or '.join(DIALECTS)} (default fanuc)")
    p.add_argument("-o", "--output", default="grating", help="output folder")
    p.set_defaults(func=_plan)
    s = gs.add_parser("simulate", help="run the programs on the virtual machine: readings")
    s.add_argument("--spec", help="grating plan (TOML)")
    s.add_argument("--errors", required=True, help="machine kinematics and errors (TOML)")
    s.add_argument("--second-offset", action="store_true", help="include the riser setups")
    s.add_argument("--second-head", action="store_true", help="include the second-head setups")
    s.add_argument("--noise", type=cli_types.non_negative, default=0.0,
                   help="reading noise sigma, um")
    s.add_argument("--seed", type=cli_types.seed, default=0, help="noise seed")
    s.add_argument("-o", "--output", default="readings.csv", help="readings CSV")
    s.set_defaults(func=_simulate)
    i = gs.add_parser("identify", help="identify the errors from grating readings")
    i.add_argument("readings", help="grating readings CSV (docs/m5.md)")
    i.add_argument("--roll", help="electronic-level roll readings CSV (X, Y)")
    i.add_argument("--degree", type=int, help="Legendre degree (default: cross-validated)")
    i.add_argument("-o", "--output", default="m5", help="output folder")
    i.set_defaults(func=_identify)
