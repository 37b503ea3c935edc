"""The thin command line.  User errors print one message and exit non-zero; no traceback.

Exit codes (``ExitCode``): 0 ok, 1 other probegen error, 2 spec, 3 model, 4 planning or
collision, 5 unsupported by the dialect, 6 parse error, 7 calibration, 8 a feature out of
tolerance, 9 capture ended without the end marker, 64 usage.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from enum import IntEnum
from pathlib import Path

from probegen import __version__
from probegen.errors import ProbegenError


class ExitCode(IntEnum):
    """Process exit codes."""

    OK = 0
    ERROR = 1
    SPEC = 2
    MODEL = 3
    PLANNING = 4
    UNSUPPORTED = 5
    PARSE = 6
    CALIBRATION = 7
    NOT_OK = 8
    CAPTURE_INCOMPLETE = 9
    USAGE = 64


def _compile(args: argparse.Namespace) -> int:
    from probegen.dialects import get_dialect
    from probegen.planning import plan_program
    from probegen.spec import load_spec

    spec = load_spec(args.spec)
    names = args.dialect or [spec.dialect]
    outputs = []
    for name in names:
        dialect = get_dialect(name)
        planned = plan_program(spec, runtime_variables=dialect.RUNTIME_VARIABLES)
        text = dialect.generate(planned.program)
        if args.output == "-":
            sys.stdout.write(text)
            continue
        target = _target(Path(args.output), Path(args.spec).stem, dialect.EXTENSION, len(names))
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(text.encode("ascii"))
        outputs.append((target, planned))
    for target, planned in outputs:
        print(f"wrote {target}")
        for p in planned.sphere_tests:
            print(f"  {p.feature.id}: {len(p.directions)} points ({p.feature.layout}), "
                  f"largest step {math.degrees(p.alpha):.2f} deg, retract {p.retract:.3f} mm "
                  f"(safe minimum {p.min_retract:.3f} mm)")
        print(f"  collision check: {len(planned.clearance.segments)} segments, smallest "
              f"clearance above the margin {planned.clearance.minimum:.3f} mm")
    return ExitCode.OK


def _target(out: Path, stem: str, ext: str, count: int) -> Path:
    if out.suffix and count == 1:
        return out
    return out / f"{stem}{ext}"


def _features(args: argparse.Namespace) -> int:
    from probegen import cad

    table = cad.features_table(cad.load_step(args.model))
    sys.stdout.write(table if table.endswith("\n") else table + "\n")
    return ExitCode.OK


def _sphere_points(args: argparse.Namespace) -> int:
    from probegen.geometry import sphere_layout as sl

    if not 3 <= args.points <= 500 or not 0.0 < args.max_polar_angle <= 150.0:
        raise ProbegenError(f"sphere-points: expected 3-500 points and a polar angle in "
                            f"(0, 150] deg, found {args.points} and {args.max_polar_angle:g}")
    pts = sl.layout(args.layout, args.points, args.max_polar_angle)
    band = None if args.layout != "cap" else 2.0 * math.asin(
        sl.uniformity(pts).min_distance / 2.0)
    order = sl.zigzag_order(pts, band=band)
    u = sl.uniformity(pts)
    alpha = sl.max_step_angle(pts, order)
    print(f"layout {args.layout}: {len(pts)} points")
    print(f"min d / R     {u.min_distance:.3f}")
    print(f"min d / max d {u.ratio:.3f}")
    print(f"largest step  {math.degrees(alpha):.2f} deg (zigzag order)")
    print(f"{'k':>3} {'theta':>8} {'phi':>8} {'x':>9} {'y':>9} {'z':>9}")
    for k, i in enumerate(order, start=1):
        x, y, z = pts[i]
        theta = math.degrees(math.acos(max(-1.0, min(1.0, z))))
        phi = math.degrees(math.atan2(y, x)) % 360.0
        row = f"{k:>3} {theta:8.3f} {phi:8.3f} {x:9.5f} {y:9.5f} {z:9.5f}"
        print(row.replace("-0.00000", " 0.00000"))
    return ExitCode.OK


def _ingest(args: argparse.Namespace) -> int:
    from probegen.compensate import calibration_toml, load_calibration
    from probegen.ingest import ingest, to_table, write_outputs
    from probegen.spec import load_spec

    spec = load_spec(args.spec)
    cal = load_calibration(args.calibration) if args.calibration else None
    result = ingest(args.log, spec, calibration=cal)
    js, cs = write_outputs(result, Path(args.output))
    sys.stdout.write(to_table(result))
    for note in result.notes:
        print(f"note: {note}")
    for diag in result.log.diagnostics:
        print(f"diagnostic: {diag}")
    print(f"wrote {js} and {cs}")
    if args.write_calibration:
        target = Path(args.write_calibration)
        target.write_text(calibration_toml(result.results[0].calibration(str(args.log))),
                          encoding="utf-8", newline="\n")
        print(f"wrote the probe calibration {target}")
    failed = any(r.ok is False for r in result.results)
    return ExitCode.NOT_OK if failed else ExitCode.OK


_PARITY = {"N": "N", "E": "E", "O": "O", "M": "M", "S": "S"}


def _capture(args: argparse.Namespace) -> int:
    from probegen.results.capture import capture

    print(f"capturing from {args.port} into {args.out} ({args.baud} baud, {args.bits}"
          f"{args.parity}{args.stop_bits:g}, xon/xoff {'on' if args.xonxoff else 'off'}); "
          "start the program now, Ctrl-C stops", file=sys.stderr)
    res = capture(args.port, args.out, baudrate=args.baud, bytesize=args.bits,
                  parity=_PARITY[args.parity], stopbits=args.stop_bits,
                  xonxoff=args.xonxoff, timeout_s=args.timeout, append=args.append)
    why = {"end-marker": "the program's end marker arrived",
           "timeout": f"nothing arrived for {args.timeout:g} s",
           "interrupted": "stopped by the user",
           "disconnected": f"the port went away ({res.detail})"}[res.reason]
    print(f"capture ended: {why}; {res.bytes} bytes kept in {res.path}")
    return ExitCode.OK if res.reason == "end-marker" else ExitCode.CAPTURE_INCOMPLETE


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for tests and docs)."""
    parser = argparse.ArgumentParser(
        prog="probegen",
        description="Compile measuring programs for CNC machine tools and CMMs.")
    parser.add_argument("--version", action="version", version=f"probegen {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    c = sub.add_parser("compile", help="plan a spec and write the measuring program(s)")
    c.add_argument("spec", help="feature spec (TOML)")
    c.add_argument("-d", "--dialect", action="append",
                   help="dialect to emit (repeatable; default: the spec's)")
    c.add_argument("-o", "--output", default="out",
                   help="output file, folder, or - for stdout (default: out/)")
    c.set_defaults(func=_compile)

    f = sub.add_parser("features", help="list the faces of a STEP model")
    f.add_argument("model", help="STEP file")
    f.set_defaults(func=_features)

    s = sub.add_parser("sphere-points", help="show a sphere-test layout and its figures")
    s.add_argument("--layout", choices=("iso", "octahedral", "cap"), default="octahedral")
    s.add_argument("--points", type=int, default=25, help="number of points (cap only)")
    s.add_argument("--max-polar-angle", type=float, default=90.0,
                   help="largest polar angle in degrees (cap only)")
    s.set_defaults(func=_sphere_points)

    i = sub.add_parser("ingest", help="evaluate a returned log (DPRNT) against a spec")
    i.add_argument("log", help="the raw log as captured")
    i.add_argument("--spec", required=True, help="the spec the program was compiled from")
    i.add_argument("-o", "--output", default="out",
                   help="folder for results.json and results.csv (default: out/)")
    i.add_argument("--calibration", help="probe calibration file to compensate with")
    i.add_argument("--write-calibration", metavar="FILE",
                   help="write the probe calibration a sphere test measured")
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
    cp.add_argument("--timeout", type=float, default=60.0,
                    help="stop after this many idle seconds (60)")
    cp.add_argument("--append", action="store_true", help="append to an existing log")
    cp.set_defaults(func=_capture)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return ExitCode.OK if exc.code == 0 else ExitCode.USAGE
    try:
        return int(args.func(args))
    except ProbegenError as exc:
        print(f"probegen: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("probegen: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into e.g. head: not an error
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - silence the flush at exit
        return ExitCode.OK


if __name__ == "__main__":
    sys.exit(main())
