"""The planning commands of the command line: ``compile``, ``features``, ``plan`` and
``sphere-points`` (registered by :func:`probegen.cli.app.build_parser`)."""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from probegen.errors import ExitCode, ProbegenError
from probegen.files import write_file

if TYPE_CHECKING:
    from probegen.cad import Part


def _compile(args: argparse.Namespace) -> int:
    from probegen.cli.progress import Bar
    from probegen.dialects import get_dialect
    from probegen.planning import check_options, part_of
    from probegen.planning.setups import plan_setups, setup_file
    from probegen.planning.well_posed import for_dialect
    from probegen.spec.model import load_spec

    spec = with_calibration(load_spec(args.spec), args.calibration)
    spec.machine.check_program_number(spec.program_number, f"{spec.source}: program.number")
    check_options(spec)
    names = args.dialect or [spec.dialect]
    if args.compact and args.output == "-":
        raise ProbegenError("compile --compact -o -: expected a folder or file for -o, found "
                            "stdout; the program calls the macro library, which is written "
                            "beside it (or write it with probegen macros -o DIR)")
    part: Part | None = None
    outputs = []
    written: dict[Path, str] = {}
    for name in names:
        dialect = get_dialect(name)
        if part is None:
            part = part_of(spec)  # loaded once, for every dialect
        with Bar(f"planning for {name}", unit="steps") as bar:
            setups = plan_setups(for_dialect(spec, name),
                                 runtime_variables=dialect.RUNTIME_VARIABLES,
                                 progress=bar, part=part)
        target = None
        if args.output == "-" and len(setups) > 1:
            raise ProbegenError(f"compile -o -: expected a folder or file for -o, found "
                                f"stdout; the spec's features are measured in "
                                f"{len(setups)} setups "
                                f"({', '.join(sp.name for sp, _ in setups)}), one program "
                                "each")
        if args.output != "-":
            target = _target(args.output, Path(args.spec).stem, dialect.EXTENSION, len(names))
        for k, (sp, planned) in enumerate(setups):
            path = None if target is None else Path(setup_file(str(target), sp, k == 0))
            outputs += _compile_one(args, name, dialect, sp.spec, planned, path, written,
                                    sp.name if len(setups) > 1 else "", sp.features)
    _print_compiled(spec, outputs)
    return ExitCode.OK


def _compile_one(args: argparse.Namespace, name: str, dialect: Any, spec: Any, planned: Any,
                 target: Path | None, written: dict[Path, str], setup: str,
                 features: tuple[str, ...]) -> list[tuple[Path, Any, bool, str]]:
    """Write one planned program of ``compile`` (a setup's, or the only one) to ``target``
    (None: stdout); the (file, plan, runs on the control, setup text) to print."""
    from probegen.dialects import get_dialect
    from probegen.dialects.split import fit

    dialect = get_dialect(name)  # one instance per program: its labels start afresh
    compact = args.compact or (args.compact is None and dialect.COMPACT_DEFAULT
                               and args.output != "-")  # stdout: self-contained
    dialect.compact = bool(compact) and dialect.MACRO_LIBRARY  # DMIS: inline
    if dialect.COMPACT_DEFAULT and args.compact is None and args.output == "-":
        print(f"note: the {name} program on stdout is the inline form (every skip move "
              "in it); with -o FOLDER compile writes the compact form and its macro "
              "library", file=sys.stderr)
    library = checked_library(dialect, spec.machine) if dialect.compact else {}
    fitted = fit(dialect, planned.program, library)
    check_part_numbers(fitted, spec, library)
    if target is None:
        if fitted.parts:
            raise ProbegenError(f"compile -o -: expected a folder or file for -o, found "
                                f"stdout; the {name} program is split into "
                                f"{len(fitted.parts)} parts, written beside it")
        sys.stdout.write(fitted.main)
        return []
    write_file(target, fitted.main, f"the {name} program", encoding="ascii")
    write_parts(target, fitted, written)
    fresh = {name: text for name, text in library.items()
             if target.parent / name not in written}  # once for the setups' programs
    written.update({target.parent / name: text for name, text in fresh.items()})
    write_library(target.parent, fresh)
    text = f"  setup {setup}: {' '.join(features)}" if setup else ""
    return [(target, planned, dialect.RUNTIME_VARIABLES, text)]


def _print_compiled(spec: Any, outputs: list[tuple[Path, Any, bool, str]]) -> None:
    """What ``compile`` says of each program it wrote."""
    from probegen.machine.calibration import UNCALIBRATED

    cal = spec.machine.calibration
    for target, planned, on_control, setup in outputs:
        print(f"wrote {target}")
        if setup:
            print(setup)
        if cal is not None and not on_control:
            print("  probe: the calibration is not baked in (a CMM compensates with its own "
                  "probe qualification)")
        else:
            print(f"  probe: {UNCALIBRATED if cal is None else cal.describe()}")
        for p in planned.sphere_tests:
            print(f"  {p.feature.id}: {len(p.directions)} points ({p.feature.layout}), "
                  f"largest step {math.degrees(p.alpha):.2f} deg, retract {p.retract:.3f} mm "
                  f"(safe minimum {p.min_retract:.3f} mm)")
        _print_freeform(planned, "  ")
        print(f"  collision check: {len(planned.clearance.segments)} segments, smallest "
              f"clearance above the margin {planned.clearance.minimum:.3f} mm")


def check_part_numbers(fitted: Any, spec: Any, library: dict[str, str]) -> None:
    """Refuse a split program's part numbers outside the machine's range or among the
    macro library's.

    Raises:
        SpecError: names the part, the number and the keys.
    """
    from probegen.errors import SpecError

    taken = {name.removesuffix(".nc") for name in library}
    for k, p in enumerate(fitted.parts, start=1):
        where = (f"{spec.source}: program.number: part {k} of the split program "
                 f"(O{spec.program_number:04d} + {k})")
        spec.machine.check_program_number(p.number, where)
        if f"O{p.number:04d}" in taken:
            raise SpecError(f"{where}: expected a number apart from the macro library's, "
                            f"found O{p.number:04d} ({spec.machine.source}: "
                            "controller.library_number); give the program a number further "
                            "from the library's")


def write_parts(target: Path, fitted: Any, written: dict[Path, str]) -> None:
    """Write a split program's parts beside its driver ``target`` and say so; a part
    file another dialect of the same compile wrote with other text is refused.

    Raises:
        ProbegenError: two dialects' parts would share a file.
    """
    for p in fitted.parts:
        path = target.parent / p.file_name
        if written.get(path, p.text) != p.text:
            raise ProbegenError(f"compile: {path}: expected one text per part file, found two "
                                "dialects' parts of a split program with the same name; "
                                "compile each dialect into its own folder")
        written[path] = p.text
        write_file(path, p.text, "a part of a split program", encoding="ascii")
    if fitted.parts:
        largest = max(len(p.text) for p in fitted.parts)
        print(f"split {target.name} into a driver and {len(fitted.parts)} parts (largest "
              f"{largest} bytes): wrote {', '.join(p.file_name for p in fitted.parts)} in "
              f"{target.parent}; run {target.name}, it calls them with M98")


def checked_library(dialect: Any, machine: Any) -> dict[str, str]:
    """The macro library files ``dialect`` writes for ``machine`` (a profile), each
    program number checked against its ``[controller] program_numbers`` where the
    library's subprograms are numbered (``dialect.NUMBERED_LIBRARY``).

    Raises:
        UnsupportedError: the dialect has no library.
        SpecError: a number is outside the machine's range.
    """
    c = machine.controller
    files: dict[str, str] = dialect.library_files(c.library_number, c.variable_base,
                                                  machine.units, c.options)
    numbers = range(c.library_number, c.library_number + len(files))
    for number in numbers if dialect.NUMBERED_LIBRARY else ():
        machine.check_program_number(
            number, f"{machine.source}: controller.library_number (O{number})")
    return files


def write_library(folder: Path, files: dict[str, str]) -> None:
    """Write the macro library's files into ``folder`` and say so."""
    for name, text in files.items():
        write_file(folder / name, text, "a macro library subprogram", encoding="ascii")
    if files:
        print(f"wrote the macro library {', '.join(files)} in {folder}")


def _macros(args: argparse.Namespace) -> int:
    from probegen.dialects import get_dialect
    from probegen.machine.profile import DEFAULT_OPTIONS, load_profile

    dialect = get_dialect(args.dialect)
    if args.machine:
        files = checked_library(dialect, load_profile(args.machine))
    else:  # a profile that says nothing: the dialect's standard options
        files = dialect.library_files(8000, 100, "mm", DEFAULT_OPTIONS.get(dialect.NAME, ()))
    write_library(Path(args.output), files)
    return ExitCode.OK


def with_calibration(spec: Any, path: str | None) -> Any:
    """``spec`` with the probe calibration of ``--calibration`` (it overrides the spec's
    ``[machine] calibration``); unchanged without one."""
    if not path:
        return spec
    from dataclasses import replace

    from probegen.machine.calibration import for_stylus, load_calibration

    cal = for_stylus(load_calibration(path), spec.machine.probe.ball_radius, "--calibration")
    return replace(spec, machine=replace(spec.machine, calibration=cal))


def _print_freeform(planned: Any, indent: str) -> None:
    from probegen.planning.freeform_spec import summary_lines

    for p in planned.freeform:
        for line in summary_lines(p):
            print(indent + line)


def _target(output: str, stem: str, ext: str, count: int) -> Path:
    """The program file ``-o output`` names: ``output`` itself when it is a file name (it has
    a suffix, one program is written, and it is neither an existing folder nor ends in
    ``/``), else ``output/<stem><ext>``."""
    out = Path(output)
    if out.suffix and count == 1 and not out.is_dir() and not output.endswith(("/", os.sep)):
        return out
    return out / f"{stem}{ext}"


def _features(args: argparse.Namespace) -> int:
    from probegen import cad

    part = cad.load_part(args.model)
    if args.revolved:
        from probegen.cad.revolved import revolved_features, revolved_table

        table = revolved_table(revolved_features(part))
    else:
        table = cad.features_table(part.model)
    sys.stdout.write(table if table.endswith("\n") else table + "\n")
    return ExitCode.OK


def _plan(args: argparse.Namespace) -> int:
    from probegen import ir
    from probegen.dialects import get_dialect
    from probegen.planning import part_of, plan_program
    from probegen.planning.revolved_spec import metrics_table
    from probegen.planning.setups import all_revolved_setups
    from probegen.spec.model import load_spec

    if args.dialect and not args.output:
        raise ProbegenError("plan -d: expected -o FOLDER to write the programs into, found "
                            "none")
    for name in args.dialect or ():
        get_dialect(name)  # an unknown name is refused before the planning
    notes: tuple[str, ...] = ()
    part: Part | None
    if args.all_revolved:
        from probegen.cad import load_part
        from probegen.machine.profile import load_profile
        from probegen.planning.well_posed import strictest, with_dialect

        if not args.machine:
            raise ProbegenError("plan --all-revolved: expected --machine PROFILE, found none")
        # the features every program of -d can evaluate (well_posed.strictest)
        loaded = load_profile(args.machine)
        machine = with_dialect(loaded, strictest(args.dialect or (), loaded.dialect))
        part = load_part(args.input, raised=args.raised)
        spec, notes = all_revolved_setups(part, machine)
        spec = dataclasses.replace(spec, raised=args.raised)
    else:
        spec = load_spec(args.input)
        part = part_of(spec)
    if spec.machine.setups:
        return _plan_setups(args, spec, part, notes)
    planned = plan_program(spec, runtime_variables=True, part=part)
    if planned.revolved or not planned.freeform:
        sys.stdout.write(metrics_table(planned.revolved, spec.machine, planned.oriented))
    for p in planned.sphere_tests:
        print(f"{p.feature.id}: sphere probing test (ISO 10360-5), {len(p.directions)} points: "
              "not compared")
    _print_freeform(planned, "")
    if planned.tour is not None:
        toured = {r.spec.id for r in planned.revolved} | {f.spec.id for f in planned.freeform}
        order = [n.feature.id for n in planned.program.body
                 if isinstance(n, ir.FeatureBlock) and n.feature.id in toured]
        print(f"order: {' '.join(order)}; travel (straight or "
              f"at a local height where clear, else at z = {spec.clearance_z:.1f}): "
              f"{planned.tour.length:.1f} mm (nearest neighbour "
              f"{planned.tour.nearest_length:.1f} mm)")
    if planned.figures is not None:
        f = planned.figures
        print(f"tour with travel: {f.plan.length:.1f} mm {f.plan.time:.1f} s; baseline "
              f"{f.baseline.length:.1f} mm {f.baseline.time:.1f} s; lower bound "
              f"{f.lower_bound.length:.1f} mm {f.lower_bound.time:.1f} s")
    if planned.stylus_changes or planned.orientation_changes:
        print(f"changes: {planned.stylus_changes} of stylus, {planned.orientation_changes} "
              "of orientation (the returns to the first stylus and the vertical included)")
    print(f"collision check: {len(planned.clearance.segments)} segments, smallest "
          f"clearance above the margin {planned.clearance.minimum:.3f} mm")
    for r in planned.revolved:
        for line in r.notes:
            print(f"rerouted: {r.spec.id}: {line}")
    return _left_out_and_write(args, spec, part, notes, bool(planned.revolved))


def _plan_setups(args: argparse.Namespace, spec: Any, part: Part | None,
                 notes: tuple[str, ...]) -> int:
    """``plan`` of a spec whose machine profile has setups: one table of the revolved
    features with a setup column, then per setup program its number, features, changes
    and collision check; the features left out; ``-o``: one program per setup."""
    from probegen.planning.revolved_spec import metrics_table
    from probegen.planning.setups import plan_setups

    setups = plan_setups(spec, runtime_variables=True, part=part)
    names = {o.plan.spec.id: sp.name for sp, p in setups for o in p.oriented}
    revolved = tuple(r for _, p in setups for r in p.revolved)
    oriented = tuple(o for _, p in setups for o in p.oriented)
    rows = metrics_table(revolved, spec.machine, oriented).splitlines()
    print(f"{rows[0]}  setup")
    for r, row in zip(revolved, rows[1:-1], strict=True):
        print(f"{row}  {names.get(r.spec.id, '-')}")
    print(rows[-1])
    for sp, p in setups:
        print(f"setup {sp.name}: program O{sp.spec.program_number:04d}, features "
              f"{' '.join(sp.features) or 'none'}; changes: {p.stylus_changes} of stylus, "
              f"{p.orientation_changes} of orientation; collision check: "
              f"{len(p.clearance.segments)} segments, smallest clearance above the margin "
              f"{p.clearance.minimum:.3f} mm")
    return _left_out_and_write(args, spec, part, notes, bool(revolved))


def _left_out_and_write(args: argparse.Namespace, spec: Any, part: Part | None,
                        notes: tuple[str, ...], any_revolved: bool) -> int:
    """The end of ``plan``'s report: that nothing could be measured (``--all-revolved``
    without a revolved feature planned), the features left out with their reasons; with
    ``-o`` the programs."""
    if args.all_revolved and not any_revolved:
        print(f"no revolved feature of {args.input} can be measured safely: the list below "
              "says why")
    if notes:
        print(f"left out ({len(notes)} recognised features; the reason and what would make "
              "each measurable):")
        for note in notes:
            print(f"  {note}")
    if args.output:
        _write_programs(args, spec, part, notes)
    return ExitCode.OK


def _write_programs(args: argparse.Namespace, spec: Any, part: Part | None,
                    left_out: tuple[str, ...]) -> None:
    """``plan -o``: the planned program in each dialect of ``-d`` (default: the spec's),
    written as ``compile`` writes it (inline), into ``-o``; the features left out are
    listed with their reasons in a comment block at its head."""
    from probegen.dialects import get_dialect
    from probegen.planning.setups import plan_setups, setup_file
    from probegen.planning.well_posed import for_dialect

    names = args.dialect or [spec.dialect]
    spec.machine.check_program_number(spec.program_number, f"{args.input}: program number")
    stem = Path(args.input).stem
    for name in names:
        dialect = get_dialect(name)
        setups = plan_setups(for_dialect(spec, name), runtime_variables=dialect.RUNTIME_VARIABLES,
                             part=part)
        first = _target(args.output, stem, dialect.EXTENSION, len(names))
        for k, (sp, planned) in enumerate(setups):
            target = Path(setup_file(str(first), sp, k == 0))
            write_file(target, program_text(name, planned, left_out), f"the {name} program",
                       encoding="ascii")
            print(f"wrote {target}" + (f" (setup {sp.name}: {' '.join(sp.features)})"
                                       if len(setups) > 1 else ""))
    if args.all_revolved:
        target = spec_file(_target(args.output, stem, ".nc", len(names)))
        write_file(target, all_revolved_spec_text(spec, target, args.input, args.machine),
                   "the spec of --all-revolved")
        print(f"wrote {target} (the spec of these programs: give it to ingest with --spec)")


def spec_file(first: Path) -> Path:
    """The spec ``plan --all-revolved -o`` writes beside its first program ``first``:
    ``<stem>_all_revolved.toml`` (never the ``<model>.toml`` ``probegen init`` writes)."""
    return first.with_name(f"{first.stem}_all_revolved.toml")


def all_revolved_spec_text(spec: Any, target: Path, model: str, profile: str) -> str:
    """The TOML text of the spec ``plan --all-revolved`` planned, for the file ``target``
    (``model`` and ``profile`` as given on the command line, written relative to it): the
    program's number, name and clearance plane, every feature with its kind, face and
    points, and the setup of those a ``[[setup]]`` measures; ``ingest --spec`` of it plans
    the same programs again (edited, it plans others: their logs no longer match)."""
    from probegen.cli.init import spec_head, toml_string
    from probegen.planning.setups import AS_LOADED

    folder = target.parent
    lines = [
        f"# The spec of the programs probegen plan --all-revolved wrote for "
        f"{Path(model).name}",
        "# with the machine profile " + Path(profile).name + ": give it to probegen "
        "ingest --spec with their",
        "# logs or DMIS outputs (one per setup program). Tolerances may be added; any other",
        "# change plans other programs, whose logs these are not.",
        "",
        *spec_head(model, profile, folder, spec.raised),
        f"clearance_z = {spec.clearance_z!r}",
        "",
        "[program]",
        f"number = {spec.program_number}",
        f"name = {toml_string(spec.program_name)}",
    ]
    for f in spec.features:
        lines += ["", "[[feature]]", f"id = {toml_string(f.id)}",
                  f"kind = {toml_string(f.kind)}", f"face = {f.face}", f"points = {f.points}"]
        if f.setup is not None and f.setup != AS_LOADED:
            lines.append(f"setup = {toml_string(f.setup)}")
    return "\n".join(lines) + "\n"


def program_text(name: str, planned: Any, left_out: tuple[str, ...]) -> str:
    """The text of one planned program (a setup's) as ``plan -o`` writes it in dialect
    ``name``: the features left out, with their reasons, in a comment block at its head;
    a fresh dialect instance per program (its labels start afresh).  Also
    benchmarks/bench_real_parts.py's."""
    from probegen import ir
    from probegen.dialects import get_dialect
    from probegen.planning.left_out import header_comments

    program = planned.program
    program = ir.Program(program.setup, (*header_comments(left_out), *program.body))
    return str(get_dialect(name).generate(program))


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
