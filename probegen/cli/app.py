"""The thin command line.  User errors print one message and exit non-zero; no traceback.

Exit codes (``ExitCode``): 0 ok, 1 other probegen error, 2 spec, 3 model, 4 planning or
collision, 5 unsupported by the dialect, 6 parse error, 7 calibration, 8 a feature out of
tolerance (``ingest``: not accepted under the ISO 14253-1 decision rule, see
``docs/results.md``), 9 capture ended without the end marker, 10 the simulated program
alarmed, 11 incomplete: a feature or toleranced characteristic NOT EVALUATED or the run did
not finish (``ingest``, ``post-ingest``; 8 wins when something is also out of tolerance, see
``probegen.errors``), 64 usage, 70 internal error (a bug: one line asking for a report;
``--debug`` shows the traceback), 73 an output file or folder cannot be written
(:mod:`probegen.files`), 130 interrupted.

``-q``/``--quiet`` and ``--debug`` are accepted anywhere on the command line, before or
after the command and its arguments.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from pathlib import Path
from typing import Any, NoReturn

from probegen import __version__
from probegen.cli.history import STORE_HELP
from probegen.cli.options import RAISED_HELP, dialect_help, finite, non_negative, positive
from probegen.cli.plan import _compile, _features, _macros, _plan, _sphere_points, _target
from probegen.cli.probe import add_probe_options, probe_from_args
from probegen.cli.results import (
    _PARITY,
    _capture,
    _ingest,
    _qif,
    _report,
    add_identity_options,
    add_log_options,
)
from probegen.errors import ExitCode, ModelWarning, ProbegenError
from probegen.files import inputs_protected, read_input, write_file
from probegen.geometry.uncertainty import DECISION_RULES
from probegen.sim.macrob.base import CONTROLS


def _sim(args: argparse.Namespace) -> int:
    if not args.pty:
        return _simulate(args, None)
    from probegen.sim.serial_play import PtyLink

    with PtyLink(args.pty) as link:
        print(f"virtual machine serial port: {args.pty}", file=sys.stderr)
        return _simulate(args, link)


def _simulate(args: argparse.Namespace, link: object | None) -> int:
    import numpy as np

    from probegen.machine.kinematics import load_machine
    from probegen.sim.contact import PlacedPart
    from probegen.sim.serial_play import PtyLink
    from probegen.sim.vm import (
        HOME,
        VirtualMachine,
        control_state,
        program_control,
        program_kind,
        run_text,
    )

    part, profile = _sim_part(args)
    ball, rack = profile.probe.ball_radius, profile.styli() if profile.rack else ()
    # a trunnion (a profile with [tilt]): machine Z0 (G53 Z0) at the start height, the work
    # origin and the table pivot HOME below it (docs/sim.md)
    tilt = profile.tilt if program_kind(args.program) != "dmis" else None
    work = (0.0, 0.0, -HOME[2]) if tilt is not None else (0.0, 0.0, 0.0)
    options = {} if tilt is None else {"pivot": work, "tilt_axis": tilt.tilt_axis,
                                       "tilt_range": tilt.tilt_range}
    options["head"] = profile.head  # a CMM's indexable head: SNSDEF angles on its indices
    c, s = np.cos(np.radians(args.rotate_z)), np.sin(np.radians(args.rotate_z))
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    if args.setup:
        rotation = rotation @ _setup_rotation(args)
    if isinstance(part, tuple):
        if args.form:
            raise ProbegenError(f"sim --form {args.form}: expected a part model (--part, or "
                                f"a spec with [part] model), found analytic spheres only")
        placed = PlacedPart.from_spheres(part[0], part[1], rotation=rotation,
                                         translation=np.add(args.offset, work))
    else:
        from probegen.sim.form import load_forms

        forms = load_forms(args.form) if args.form else ()
        placed = PlacedPart.from_model(part, rotation=rotation,
                                       translation=np.add(args.offset, work), forms=forms)
    probe = probe_from_args(args, ball)
    kin = load_machine(args.errors) if args.errors else None
    from probegen.cli.progress import Bar

    text = _program_text(args.program)
    probes = sum(text.upper().count(word) for word in ("G31", "PTMEAS", "G38."))
    with Bar("simulating", probes, unit="touches") as bar:
        vm = VirtualMachine(placed, probe, kin, on_touch=bar, rack=rack, start=profile.stylus,
                            body=(profile.probe.body_diameter, profile.probe.body_length),
                            **options)
        result = run_text(text, vm, kind=program_kind(args.program), source=args.program,
                          work_offset=work, home=(HOME[0], HOME[1], HOME[2] + work[2]),
                          control=args.control or program_control(args.program),
                          feed_override=args.feed_override,
                          program_dir=Path(args.library or Path(args.program).parent),
                          answers=_answers(args))
    data = result.output.encode("ascii", errors="replace")
    if isinstance(link, PtyLink):
        print(f"playing {len(data)} bytes over {args.pty}", file=sys.stderr)
        link.play(data, delay=args.pty_delay)
    elif args.output == "-":
        sys.stdout.write(result.output)
    else:
        write_file(args.output, data, "what the machine sends")
        print(f"wrote {args.output} ({result.touches} touches)", file=sys.stderr)
    for line in control_state(result):  # offsets and rotation the program left
        print(f"  control: {line}", file=sys.stderr)
    for line in result.report:  # DMIS statements skipped or noted, with the reason
        print(f"probegen: {line.replace(' ', f' {args.program}:', 1)}", file=sys.stderr)
    if result.alarm:
        print(f"probegen: the program stopped on alarm {result.alarm}", file=sys.stderr)
        if result.alarm.startswith("76 ") or "Unable to open file for subroutine" in result.alarm:
            print(f"  a called subprogram is neither in the program nor in "
                  f"{args.library or Path(args.program).parent}/ (a compact program's macro "
                  f"library: probegen macros -d DIALECT -o DIR, then sim --library DIR)",
                  file=sys.stderr)
        return ExitCode.SIM_ALARM
    return ExitCode.OK


def _setup_rotation(args: argparse.Namespace) -> Any:
    """``sim --setup NAME``: the setup's rotation (part to table) from the profile of
    ``--spec`` or ``--machine``.

    Raises:
        SpecError: the profile has no setup of that name, or it has an origin.
    """
    import numpy as np

    from probegen.machine.profile import load_profile
    from probegen.planning.setups import check_origin, setup_named
    from probegen.spec.model import load_spec

    if not (args.spec or args.machine):
        raise ProbegenError("sim --setup: expected --spec or --machine (the profile that "
                            "names the setup), found neither")
    machine = load_spec(args.spec).machine if args.spec else load_profile(args.machine)
    k, setup = setup_named(machine, args.setup)
    check_origin(machine, k, setup)
    return np.asarray(setup.rotation, dtype=np.float64)


def _sim_part(args: argparse.Namespace) -> tuple[Any, Any]:
    """The part (a loaded model or analytic spheres) and the machine profile."""
    from probegen import cad
    from probegen.machine.profile import load_profile

    if args.spec:
        from probegen.spec.model import SphereTest, load_spec

        spec = load_spec(args.spec)
        if args.part or spec.model is not None:
            return cad.load_part(args.part or str(spec.model), raised=spec.raised), spec.machine
        spheres = [f for f in spec.features if isinstance(f, SphereTest) and f.centre]
        centres = [f.centre for f in spheres]
        radii = [(f.diameter or 0.0) / 2.0 for f in spheres]
        return (centres, radii), spec.machine
    if not (args.part and args.machine):
        raise ProbegenError("sim: expected --spec, or --part and --machine, found neither")
    return cad.load_part(args.part), load_profile(args.machine)


def _answers(args: argparse.Namespace) -> dict[str, str | int | float] | None:
    """The answers to a DMIS program's TEXT/QUERY statements (``--answers FILE``)."""
    from probegen.dmis.execute import load_answers

    return load_answers(args.answers) if args.answers else None


def _program_text(path: str) -> str:
    """The text of a program to run: a DMIS file as every command reads it (UTF-8 with or
    without BOM, else Latin-1), a Macro B program as ASCII."""
    from probegen.sim.vm import program_kind

    what = "the program to run (Macro B, LinuxCNC or DMIS)"
    if program_kind(path) == "dmis":
        from probegen.dmis.reader import read_dmis_text

        read_input(path, what)  # its checks and messages (missing, a folder)
        return read_dmis_text(path)
    return read_input(path, what, encoding="ascii")


def _post(args: argparse.Namespace) -> int:
    from probegen.cad import load_part
    from probegen.dialects import get_dialect
    from probegen.machine.profile import load_profile
    from probegen.post.files import post_file, write_post

    machine = load_profile(args.machine)
    out = post_file(args.program, machine, load_part(args.model, raised=args.raised),
                    dialect=args.dialect, offset=tuple(args.model_offset),
                    skip_unsupported=args.skip_unsupported, reroute=args.reroute,
                    number=args.number, answers=_answers(args))
    target = _target(args.output, Path(args.program).stem,
                     get_dialect(args.dialect).EXTENSION, 1)
    map_path = write_post(out, target)
    posted = out.posted
    for s in posted.skipped:
        print(f"probegen: skipped {args.program}:{s.line}: {s.text} ({s.reason})",
              file=sys.stderr)
    for s in posted.notes:
        print(f"probegen: note {args.program}:{s.line}: {s.text} ({s.reason})",
              file=sys.stderr)
    print(f"wrote {target} and {map_path}: {len(posted.touches)} touches")
    if posted.rerouted:
        print(f"  rerouted over the clearance plane: lines "
              f"{', '.join(str(n) for n in posted.rerouted)}")
    print(f"  collision check: {len(posted.segments)} segments, smallest clearance of a "
          f"positioning move above the margin {posted.move_clearance:.3f} mm")
    return ExitCode.OK


def _post_ingest(args: argparse.Namespace) -> int:
    from probegen.cli.results import verdict_code
    from probegen.machine.calibration import UNCALIBRATED, load_calibration
    from probegen.post.evaluate import ingest_file, results_table, run_status

    cal = load_calibration(args.calibration) if args.calibration else None
    log, result, notes = ingest_file(args.log, args.features, cal, run=args.run,
                                     ignore_identity=args.ignore_identity)
    write_file(args.output, result.output, "the DMIS output file", encoding="ascii")
    print(f"probe: {UNCALIBRATED if cal is None else cal.describe()}")
    sys.stdout.write(results_table(result))
    for note in notes:
        print(f"note: {note}")
    status = run_status(log, result)
    print(f"status: {status}{'' if log.complete else ' (the run did not finish)'}")
    print(f"wrote {args.output}")
    return verdict_code(status)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for tests and docs)."""
    parser = _Parser(
        prog="probegen",
        description="Compile measuring programs for CNC machine tools and CMMs.")
    parser.add_argument("--version", action="version", version=f"probegen {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    c = sub.add_parser("compile", help="plan a spec and write the measuring program(s)")
    c.add_argument("spec", help="feature spec (TOML)")
    c.add_argument("-d", "--dialect", action="append",
                   help="dialect to emit (repeatable; default: the spec's): "
                        f"{dialect_help()}")
    c.add_argument("-o", "--output", default="out",
                   help="output file, folder, or - for stdout (default: out/)")
    c.add_argument("--calibration", metavar="FILE",
                   help="probe calibration (from ingest --write-calibration) baked into "
                        "the in-process actions; overrides the spec's [machine] calibration")
    form = c.add_mutually_exclusive_group()
    form.add_argument("--compact", action="store_true", default=None,
                      help="Fanuc/Haas: call probegen's macro library (G65) for every skip "
                           "move and write the library beside the program (O8000.nc ...); "
                           "the default for Fanuc and Haas, but on stdout (-o -); LinuxCNC "
                           "(opt-in): o<pg_move>/o<pg_touch> calls, pg_move.ngc ...; DMIS is "
                           "written inline")
    form.add_argument("--inline", dest="compact", action="store_false",
                      help="every skip move spelt out in the program, self-contained (the "
                           "form -o - prints)")
    c.set_defaults(func=_compile)

    mc = sub.add_parser("macros", help="write probegen's Macro B subprogram library (the "
                                       "programs a compact program calls)")
    mc.add_argument("-d", "--dialect", default="fanuc",
                    help="fanuc, haas or linuxcnc (o-word subroutine files; default fanuc)")
    mc.add_argument("-o", "--output", default="out", help="output folder (default: out/)")
    mc.add_argument("--machine", help="machine profile (TOML): units, variable base, "
                                      "[controller] library_number and options (default: "
                                      "8000, mm, #100, the dialect's standard options)")
    mc.set_defaults(func=_macros)

    from probegen.cli.init import add_init_command

    add_init_command(sub)
    f = sub.add_parser("features", help="list the faces of a STEP model")
    f.add_argument("model", help="STEP file")
    f.add_argument("--revolved", action="store_true",
                   help="list the revolved features (cylinders, cones, spheres, tori) instead")
    f.set_defaults(func=_features)

    pl = sub.add_parser("plan", help="plan a spec (or every revolved feature of a model) "
                                     "and compare the path's length and time with a "
                                     "baseline and a lower bound")
    pl.add_argument("input", help="feature spec (TOML), or a STEP model with --all-revolved")
    pl.add_argument("--all-revolved", action="store_true",
                    help="plan every accessible revolved feature of the model (default "
                         "sections, 8 points)")
    pl.add_argument("--machine", help="machine profile (TOML), with --all-revolved")
    pl.add_argument("--raised", type=non_negative, default=0.0, metavar="MM",
                    help="with --all-revolved: " + RAISED_HELP)
    pl.add_argument("-d", "--dialect", action="append",
                    help="with -o: dialect of a program to write (repeatable; default: the "
                         f"spec's or the profile's): {dialect_help()}")
    pl.add_argument("-o", "--output",
                    help="also write the planned program, one per dialect, into this folder "
                         "(or file, for one dialect)")
    pl.set_defaults(func=_plan)

    s = sub.add_parser("sphere-points", help="show a point layout of the sphere probing "
                                             "test (ISO 10360-5) and its figures")
    s.add_argument("--layout", choices=("iso", "octahedral", "cap"), default="octahedral",
                   help="iso: the 25 points ISO 10360-5 recommends; octahedral: 25 nearly "
                        "even points; cap: --points points on a spherical cap (default "
                        "octahedral)")
    s.add_argument("--points", type=int, default=25, help="number of points (cap only)")
    s.add_argument("--max-polar-angle", type=finite, default=90.0,
                   help="largest polar angle in degrees (cap only)")
    s.set_defaults(func=_sphere_points)

    i = sub.add_parser("ingest", help="evaluate a returned log (DPRNT) or a DMIS output "
                                      "file (free-form features) against a spec")
    i.add_argument("log", nargs="+",
                   help="the raw log as captured (one per setup program of the spec, paired "
                        "by the program number each prints), or a DMIS output file (.dms, "
                        ".dmi)")
    i.add_argument("--spec", required=True, help="the spec the program was compiled from")
    i.add_argument("-o", "--output", default="out",
                   help="folder for results.json and results.csv (default: out/)")
    i.add_argument("--calibration", help="probe calibration file to compensate with")
    i.add_argument("--write-calibration", metavar="FILE",
                   help="write the probe calibration a sphere test measured")
    i.add_argument("--calibration-date", metavar="DATE",
                   help="the date written into --write-calibration (ISO 8601, e.g. "
                        "2026-11-26; never taken from the clock)")
    i.add_argument("--decision-rule", choices=DECISION_RULES,
                   help="ISO 14253-1 decision rule: simple acceptance or guard_band by U "
                        "(default: the spec's [evaluation] decision_rule, else simple)")
    add_log_options(i)
    add_identity_options(i)
    i.add_argument("--store", metavar="URL", help=f"also record the run in {STORE_HELP}")
    i.set_defaults(func=_ingest)

    cp = sub.add_parser("capture", help="record what the machine sends on a serial port")
    cp.add_argument("--port", required=True,
                    help="serial device (/dev/ttyUSB0, COM3) or a pyserial URL")
    cp.add_argument("--out", required=True, help="raw log file (never overwritten)")
    cp.add_argument("--baud", type=int, default=9600, help="baud rate (default 9600)")
    cp.add_argument("--bits", type=int, choices=(7, 8), default=7, help="data bits (7)")
    cp.add_argument("--parity", choices=sorted(_PARITY), default="E", help="parity (E)")
    cp.add_argument("--stop-bits", type=float, choices=(1, 1.5, 2), default=2,
                    help="stop bits (2)")
    cp.add_argument("--xonxoff", action=argparse.BooleanOptionalAction, default=True,
                    help="software flow control (on)")
    cp.add_argument("--timeout", type=positive, default=60.0,
                    help="stop after this many idle seconds (60)")
    cp.add_argument("--append", action="store_true",
                    help="add to an existing raw log (a resumed program) instead of refusing it")
    cp.set_defaults(func=_capture)

    sm = sub.add_parser("sim", help="run a program on the virtual machine")
    sm.add_argument("program", help="program text: .nc (Macro B), .ngc (LinuxCNC) or "
                                    ".dmi/.dms (DMIS)")
    sm.add_argument("--spec", help="take the part and the machine profile from a spec")
    sm.add_argument("--answers", metavar="FILE", help=ANSWERS_HELP)
    sm.add_argument("--part", help="the part model (STEP)")
    sm.add_argument("--machine", help="machine profile (TOML)")
    sm.add_argument("--errors", help="machine kinematics and geometric errors (TOML)")
    sm.add_argument("--control", choices=(*CONTROLS, "linuxcnc"),
                    help="the control (default: linuxcnc for a .ngc file, haas for a .haas.nc "
                         "file, else fanuc); linuxcnc writes what the program's (LOG,...) "
                         "comments log")
    sm.add_argument("--feed-override", type=positive, default=100.0, metavar="PCT",
                    help="the operator's feed override, percent (Macro B: G1 and G31 feeds, "
                         "except while #3004 holds it at 100)")
    sm.add_argument("--library", metavar="DIR",
                    help="where called subprograms O<n>.nc (LinuxCNC: <name>.ngc) are (a "
                         "compact program's macro library; default: the program's folder)")
    sm.add_argument("--offset", type=finite, nargs=3, default=(0.0, 0.0, 0.0),
                    metavar=("DX", "DY", "DZ"), help="where the part really is, mm")
    sm.add_argument("--rotate-z", type=finite, default=0.0, metavar="DEG",
                    help="part rotation about Z, degrees")
    sm.add_argument("--setup", metavar="NAME",
                    help="the part lies turned as the machine profile's [[setup]] NAME says "
                         "(a setup's program; needs --spec or --machine)")
    sm.add_argument("--form", metavar="FILE",
                    help="planted form errors of revolved faces (TOML, docs/sim.md)")
    add_probe_options(sm)
    sm.add_argument("-o", "--output", default="-", help="what the machine sends (default -)")
    sm.add_argument("--pty", metavar="LINK",
                    help="play the output over a pseudo-terminal linked at LINK")
    sm.add_argument("--pty-delay", type=non_negative, default=1.0,
                    help="seconds to wait for the reader before sending (1)")
    sm.set_defaults(func=_sim)

    q = sub.add_parser("qif", help="QIF 3 results from a DPRNT log or a DMIS output file")
    q.add_argument("input", help="DPRNT log (with --spec) or DMIS output (.dms/.dmi)")
    q.add_argument("--spec", help="the spec a DPRNT log's program was compiled from")
    q.add_argument("--calibration", help="probe calibration to compensate with")
    q.add_argument("--program", help="the DMIS program, for its T() tolerance limits")
    q.add_argument("--decision-rule", choices=DECISION_RULES,
                   help="ISO 14253-1 decision rule of a DPRNT log's results (as ingest)")
    q.add_argument("--strict", action="store_true", help="refuse output with diagnostics")
    q.add_argument("--validate", action="store_true", help="validate against the schema")
    q.add_argument("--schema", help="QIFDocument.xsd (default: $PROBEGEN_QIF_SCHEMA)")
    q.add_argument("-o", "--output", default="results.qif", help="the QIF file")
    add_log_options(q)
    add_identity_options(q)
    q.set_defaults(func=_qif)

    rp = sub.add_parser("report", help="one self-contained HTML report from results.json")
    rp.add_argument("results", help="results.json written by probegen ingest")
    rp.add_argument("-o", "--output", default="report.html", help="the HTML file")
    rp.add_argument("--title", help="title of the report")
    rp.add_argument("--store", metavar="URL",
                    help="add trend charts (tolerance, control limits) of the part's "
                         f"characteristics from {STORE_HELP}")
    rp.set_defaults(func=_report)
    _post_parsers(sub)

    from probegen.cli.rotary import add_rotary_commands

    add_rotary_commands(sub)
    from probegen.cli.grating import add_grating_commands  # M5: probegen grating ...

    add_grating_commands(sub)
    from probegen.cli.history import add_history_commands

    add_history_commands(sub)
    _add_global_flags(parser, top=True)
    return parser


class _Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors read ``probegen: error: <command>: ...`` (one
    line, like every other error) and exit with ``ExitCode.USAGE``; its subparsers too."""

    def error(self, message: str) -> NoReturn:
        self.print_usage(sys.stderr)
        command = self.prog.removeprefix("probegen").strip()
        where = f"{command}: " if command else ""
        self.exit(ExitCode.USAGE, f"probegen: error: {where}{message}\n")


def _add_global_flags(parser: argparse.ArgumentParser, *, top: bool) -> None:
    """``-q``/``--quiet`` and ``--debug`` on ``parser`` and on every (nested) subcommand, so
    they may stand anywhere on the line; below the top they default to "not given" and
    leave the top level's value alone."""
    default: Any = False if top else argparse.SUPPRESS
    parser.add_argument("-q", "--quiet", action="store_true", default=default,
                        help="no progress bars (they only draw on a terminal anyway)")
    parser.add_argument("--debug", action="store_true", default=default,
                        help="show the traceback of an error (for a bug report)")
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in dict.fromkeys(action.choices.values()):
                _add_global_flags(sub, top=False)


ANSWERS_HELP = ("a DMIS program's answers to its TEXT/QUERY statements: a TOML file of "
                "NAME = value lines (never a prompt; without one, the statement's default)")


def _post_parsers(sub: Any) -> None:
    """The ``post`` and ``post-ingest`` commands (docs/post.md)."""
    po = sub.add_parser("post", help="post-process a DMIS program into a machine-tool "
                                     "probing program (and its feature map)")
    po.add_argument("program", help="the DMIS program (.dmi, .dms)")
    po.add_argument("-d", "--dialect", default="fanuc",
                    help=f"dialect (default fanuc): {dialect_help(machine_tool=True)}")
    po.add_argument("--machine", required=True,
                    help="machine profile (TOML); its stylus must be the program's sensor")
    po.add_argument("--model", required=True,
                    help="the part (STEP), to check every move for collisions")
    po.add_argument("--model-offset", type=finite, nargs=3, default=(0.0, 0.0, 0.0),
                    metavar=("X", "Y", "Z"),
                    help="where the model's origin is in the program's coordinates, mm")
    po.add_argument("--raised", type=non_negative, default=0.0, metavar="MM",
                    help=RAISED_HELP)
    po.add_argument("--skip-unsupported", action="store_true",
                    help="leave out (and list) statements that cannot be translated, "
                         "never a measuring move (MEAS, PTMEAS)")
    po.add_argument("--reroute", action="store_true",
                    help="lift colliding positioning moves over the clearance plane "
                         "instead of failing")
    po.add_argument("--number", type=int, default=1001, help="program number (1001)")
    po.add_argument("--answers", metavar="FILE", help=ANSWERS_HELP)
    po.add_argument("-o", "--output", default="out",
                    help="program file or folder (default out/); the feature map is "
                         "written next to it")
    po.set_defaults(func=_post)

    pi = sub.add_parser("post-ingest", help="evaluate a posted program's DPRNT log: the "
                                            "DMIS features, tolerances and output file")
    pi.add_argument("log", help="the DPRNT log as captured")
    pi.add_argument("--features", required=True,
                    help="the feature map written by probegen post")
    pi.add_argument("-o", "--output", default="results.dmo",
                    help="the DMIS output file (default results.dmo)")
    pi.add_argument("--calibration", metavar="FILE",
                    help="probe calibration (ingest --write-calibration) to compensate with")
    add_log_options(pi)
    pi.set_defaults(func=_post_ingest)


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code.  No exception escapes: a
    ``ProbegenError`` prints its one-line message, a usage error its usage and one line,
    any other exception is a bug and prints one line asking for a report (the traceback
    only with ``--debug``)."""
    words = sys.argv[1:] if argv is None else argv
    debug = "--debug" in words  # before the line is parsed (a bug in the parser itself)
    try:
        try:
            args = build_parser().parse_args(words)
        except SystemExit as exc:  # --help, --version, or a usage error (printed)
            return ExitCode.OK if exc.code in (0, None) else ExitCode.USAGE
        debug = args.debug
        with warnings.catch_warnings():
            if not debug:
                warnings.showwarning = _one_line_warning
            return _run(args)
    except KeyboardInterrupt:
        print("probegen: interrupted", file=sys.stderr)
        return ExitCode.INTERRUPTED
    except BrokenPipeError:  # output piped into e.g. head: not an error
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - silence the flush at exit
        return ExitCode.OK
    except Exception as exc:  # noqa: BLE001 - the guard: a bug, never a user error
        _traceback(debug)
        message = " ".join(str(exc).split()) or "(no message)"
        print(f"probegen: internal error: {type(exc).__name__}: {message} (please report "
              f"this at the project's issue tracker; run again with --debug for the "
              f"traceback)", file=sys.stderr)
        return ExitCode.INTERNAL


def _run(args: argparse.Namespace) -> int:
    """Run the parsed command; a ``ProbegenError`` is its one-line message."""
    import probegen.cli.progress

    enabled = probegen.cli.progress.ENABLED
    probegen.cli.progress.ENABLED = not args.quiet  # for this command only
    try:
        with inputs_protected(_inputs(args)):
            return int(args.func(args))
    except ProbegenError as exc:
        _traceback(args.debug)
        print(f"probegen: error: {exc}", file=sys.stderr)
        return exc.exit_code
    finally:
        probegen.cli.progress.ENABLED = enabled


_OUTPUT_OPTIONS = frozenset({"output", "out", "write_calibration", "compensation", "pty"})
"""The options that name what a command writes (everything else it is given it reads)."""


def _inputs(args: argparse.Namespace) -> list[str]:
    """The file names a command reads: every string argument but its outputs, and every
    string of a list argument (``ingest LOG [LOG ...]``)."""
    values = [w for k, v in vars(args).items() if k not in _OUTPUT_OPTIONS
              for w in (v if isinstance(v, list) else [v])]
    return [v for v in values if isinstance(v, str) and v not in ("", "-")]


def _one_line_warning(message: Warning | str, category: type[Warning], filename: str,
                      lineno: int, file: Any = None, line: str | None = None) -> None:
    """A Python warning (numpy's, a library's) as one line, without the source line that
    looks like part of a traceback (``--debug`` shows warnings as Python prints them);
    probegen's own (:class:`~probegen.errors.ModelWarning`) without the class name."""
    text = " ".join(str(message).split())
    kind = "" if issubclass(category, ModelWarning) else f"{category.__name__}: "
    print(f"probegen: warning: {kind}{text}", file=sys.stderr)


def _traceback(debug: bool) -> None:
    """Print the exception being handled with its traceback when ``--debug`` was given."""
    if debug:
        import traceback

        traceback.print_exc(file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
