"""The results commands of the command line: ``ingest``, ``capture``, ``qif`` and
``report`` (registered by :func:`probegen.cli.app.build_parser`)."""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from probegen.errors import ExitCode, ProbegenError, ResultsParseError
from probegen.files import read_input, updating, write_file

if TYPE_CHECKING:
    from probegen.evaluate.ingest import Ingested
    from probegen.evaluate.run_identity import IdentityOptions
    from probegen.machine.calibration import ProbeCalibration
    from probegen.spc.series import Series
    from probegen.spec.model import Spec

DMIS_OUTPUT_SUFFIXES = (".dms", ".dmi", ".dmis")
"""``probegen ingest`` reads a file with one of these suffixes as DMIS output (the virtual
CMM's and a CMM's results), any other as a DPRNT log."""


def add_log_options(p: argparse.ArgumentParser) -> None:
    """``--run`` and ``--ignore-identity``: which run of a DPRNT log, and whether its
    program identity is checked (``docs/results.md``, "Log identity")."""
    p.add_argument("--run", type=int, metavar="N",
                   help="use run N of a log holding several (1-based, in log order; "
                        "default: the last complete run)")
    p.add_argument("--ignore-identity", action="store_true",
                   help="read a log whose program number or identity differs from the "
                        "spec's (a warning goes into every output)")


def add_identity_options(p: argparse.ArgumentParser) -> None:
    """The run's identity (``docs/results.md``, "The run"): part number, serial, operator,
    time, batch."""
    p.add_argument("--part-number", metavar="TEXT",
                   help="the part number (default: the spec's [part] number)")
    p.add_argument("--serial", metavar="TEXT",
                   help="the part's serial number (default: the log's PGSERIAL line)")
    p.add_argument("--operator", metavar="TEXT", help="who measured")
    p.add_argument("--time", metavar="ISO8601",
                   help="when the part was measured, with its UTC offset "
                        "(2026-11-26T13:48:53+01:00; default: the log file's "
                        "modification time, never the clock)")
    p.add_argument("--batch", metavar="TEXT", help="the batch or subgroup of the part")


def identity_options(args: argparse.Namespace) -> IdentityOptions:
    """The identity options of ``add_identity_options``."""
    from probegen.evaluate.run_identity import IdentityOptions

    return IdentityOptions(part_number=args.part_number, serial=args.serial,
                           operator=args.operator, time=args.time, batch=args.batch)


def _ingest(args: argparse.Namespace) -> int:
    from probegen.evaluate.ingest import identified
    from probegen.evaluate.outputs import to_table, write_outputs
    from probegen.evaluate.setups import ingest_setups
    from probegen.machine.calibration import check_date, load_calibration
    from probegen.spec.model import load_spec

    spec = load_spec(args.spec)
    cal = load_calibration(args.calibration) if args.calibration else None
    date = check_date(args.calibration_date, "--calibration-date") \
        if args.calibration_date else ""
    dmis = [log for log in args.log if Path(log).suffix.lower() in DMIS_OUTPUT_SUFFIXES]
    if dmis:
        result = _ingest_dmis(args, spec)
        if cal is not None:  # the CMM compensated its touches with its own probe data
            result = replace(result, notes=(*result.notes, "--calibration is not applied "
                                            "to a DMIS output: the CMM compensated its "
                                            "touches itself"))
    else:
        result = ingest_setups(args.log, spec, calibration=cal, with_path=True,
                               decision_rule=args.decision_rule, run=args.run,
                               ignore_identity=args.ignore_identity)
    result = identified(result, spec, identity_options(args))
    js, cs = write_outputs(result, Path(args.output))
    sys.stdout.write(to_table(result))
    for note in result.notes:
        print(f"note: {note}")
    for diag in result.log.diagnostics:
        print(f"diagnostic: {diag}")
    print(f"wrote {js} and {cs}")
    if args.write_calibration:
        if not result.results:
            skipped = [f"{n.feature} ({n.reason})" for n in result.not_evaluated
                       if n.kind == "sphere_test"]
            raise ProbegenError("--write-calibration: expected an evaluated sphere test, "
                                f"found {'none' if not skipped else 'only NOT EVALUATED '}"
                                f"{', '.join(skipped)}")
        refuse_incomplete_calibration(result)
        target, written = write_calibration(Path(args.write_calibration), tuple(
            r.calibration(str(args.log[0]), date) for r in result.results))
        print(f"wrote the probe calibration {target} ({written.fingerprint}"
              f"{'' if date else ', undated: give --calibration-date'})")
    if args.store:
        store_run(result, args.store)
    return verdict_code(result.status)


def _ingest_dmis(args: argparse.Namespace, spec: Spec) -> Ingested:
    """``ingest`` of DMIS output files: with setups in the machine profile, one output per
    setup program, every feature in part coordinates
    (:func:`probegen.evaluate.setups_dmis.ingest_dmis_setups`); without, one file, its
    free-form features (:func:`probegen.evaluate.ingest.ingest_dmis`)."""
    from probegen.evaluate.ingest import ingest_dmis

    others = [log for log in args.log if Path(log).suffix.lower() not in DMIS_OUTPUT_SUFFIXES]
    if others:
        raise ProbegenError(f"ingest {' '.join(args.log)}: expected DMIS output files only "
                            f"(suffix {', '.join(DMIS_OUTPUT_SUFFIXES)}) or DPRNT logs only, "
                            f"found both ({', '.join(others)})")
    if spec.machine.setups:
        from probegen.evaluate.setups_dmis import ingest_dmis_setups

        return ingest_dmis_setups(args.log, spec, decision_rule=args.decision_rule)
    if len(args.log) > 1:
        raise ProbegenError(f"ingest {' '.join(args.log)}: expected one DMIS output file "
                            f"(the machine profile has no [[setup]]: one program), found "
                            f"{len(args.log)} files")
    return ingest_dmis(args.log[0], spec, decision_rule=args.decision_rule)


def write_calibration(target: Path, entries: tuple[ProbeCalibration, ...]
                      ) -> tuple[Path, ProbeCalibration]:
    """Write the sphere tests' calibration ``entries`` to ``target``, over the entries of
    other styli an existing calibration file there holds
    (:func:`probegen.machine.calibration.combined`); say which were kept."""
    from probegen.machine.calibration import calibration_toml, combined, load_calibration

    old = None
    if target.is_file():
        try:
            with updating(target):
                old = load_calibration(target)
        except ProbegenError:
            old = None  # not a calibration file: replaced, as it always was
    written, kept = combined(entries, old, "--write-calibration")
    path = write_file(target, calibration_toml(written), "the probe calibration")
    if kept:
        print(f"kept the entries of {', '.join(_pair(e) for e in kept)} from {target}")
    return path, written


def _pair(entry: ProbeCalibration) -> str:
    return f"{entry.stylus} {entry.orientation or 'vertical'}"


def store_run(result: Ingested, url: str) -> None:
    """Record an identified run in the store at ``url`` and say so (``docs/store.md``)."""
    from probegen.store import open_store

    assert result.run is not None, "identified() first"
    store = open_store(url)
    try:
        key, new = store.add_run(result, result.run)
    finally:
        store.close()
    print(f"stored run {key} in {store.url}" if new else f"run {key} already in {store.url}")


def verdict_code(status: str) -> ExitCode:
    """The exit code of a run's status (:mod:`probegen.errors`)."""
    from probegen.evaluate.characteristics import NOT_EVALUATED, NOT_OK

    return {NOT_OK: ExitCode.NOT_OK, NOT_EVALUATED: ExitCode.INCOMPLETE}.get(status,
                                                                         ExitCode.OK)


def refuse_incomplete_calibration(result: Ingested) -> None:
    """Refuse to write a calibration from a sphere test that is not whole: a run cut
    short, or a log read with its identity ignored (a sphere test with a touch missing
    or removed as implausible is NOT EVALUATED and never reaches here).

    Raises:
        ProbegenError: naming why.
    """
    why = ("the log's run did not finish (no PGEND)" if not result.log.complete else
           "the log's identity was not checked (--ignore-identity)"
           if any(n.startswith("WARNING: identity") for n in result.notes) else "")
    if why:
        raise ProbegenError(f"--write-calibration: expected a complete sphere test of this "
                            f"program, found that {why}; no calibration written")


_PARITY = {"N": "N", "E": "E", "O": "O", "M": "M", "S": "S"}


def _capture(args: argparse.Namespace) -> int:
    from probegen.results.capture import capture

    where = (f"appending to {args.out}" if args.append and Path(args.out).is_file()
             else f"into {args.out}")
    print(f"capturing from {args.port} {where} ({args.baud} baud, {args.bits}"
          f"{args.parity}{args.stop_bits:g}, xon/xoff {'on' if args.xonxoff else 'off'}); "
          "start the program now, Ctrl-C stops", file=sys.stderr)
    from probegen.cli.progress import Bar

    with Bar("capturing", unit="bytes") as bar:
        res = capture(args.port, args.out, baudrate=args.baud, bytesize=args.bits,
                      parity=_PARITY[args.parity], stopbits=args.stop_bits,
                      xonxoff=args.xonxoff, timeout_s=args.timeout, append=args.append,
                      progress=lambda _total, chunk: bar(len(chunk)))
    why = {"end-marker": "the program's end marker arrived",
           "timeout": f"nothing arrived for {args.timeout:g} s",
           "interrupted": "stopped by the user",
           "disconnected": f"the port went away ({res.detail})"}[res.reason]
    kept = (f"{res.bytes} bytes added to {res.path} after its {res.offset} earlier bytes"
            if res.offset else f"{res.bytes} bytes kept in {res.path}")
    print(f"capture ended: {why}; {kept}")
    return ExitCode.OK if res.reason == "end-marker" else ExitCode.CAPTURE_INCOMPLETE


def _qif(args: argparse.Namespace) -> int:
    from probegen.qif.export import dmis_output_to_qif, ingested_to_qif, write_qif
    from probegen.sim.vm import program_kind

    if program_kind(args.input) == "dmis":
        from probegen.qif.dmis_output import read_dmis_tolerances
        from probegen.results import read_dmis_output

        limits = None
        if args.program:
            from probegen.dmis.reader import read_dmis_text

            read_input(args.program, "the DMIS program")  # its checks and messages
            text = read_dmis_text(args.program)
            limits = read_dmis_tolerances(text, source=args.program)
        out = read_dmis_output(args.input, strict=args.strict)
        if not out.features and not out.tolerances:
            unread = len(out.diagnostics)
            raise ResultsParseError(
                f"{args.input}: expected DMIS output with feature or tolerance actuals (FA, "
                f"TA), found none ({unread} statement{'s' if unread != 1 else ''} could not "
                "be read)", out.diagnostics)
        export = dmis_output_to_qif(out, tolerances=limits)
        text, notes = export.text, export.notes
    else:
        from probegen.evaluate.ingest import identified
        from probegen.evaluate.setups import ingest_setups
        from probegen.machine.calibration import load_calibration
        from probegen.spec.model import load_spec

        if not args.spec:
            raise ProbegenError(f"qif {args.input}: a DPRNT log needs --spec, found none")
        spec = load_spec(args.spec)
        cal = load_calibration(args.calibration) if args.calibration else None
        ingested = ingest_setups([args.input], spec, calibration=cal,
                                 decision_rule=args.decision_rule, run=args.run,
                                 ignore_identity=args.ignore_identity)
        ingested = identified(ingested, spec, identity_options(args))
        text, notes = ingested_to_qif(ingested, spec=spec), ingested.notes
        print(f"probe: {ingested.calibration_text}")
    path = write_qif(args.output, text, schema=args.schema, validate=args.validate)
    for note in notes:
        print(f"note: {note}")
    print(f"wrote {path}{' (valid against the QIF 3 schema)' if args.validate else ''}")
    return ExitCode.OK


def _report(args: argparse.Namespace) -> int:
    from probegen.report import write_report

    history = report_history(args.results, args.store) if args.store else ()
    out = write_report(args.results, args.output, title=args.title, history=history)
    print(f"wrote the report {out}"
          f"{f' with the history of {len(history)} characteristics' if history else ''}")
    return ExitCode.OK


def report_history(results_path: str, url: str) -> list[Series]:
    """The stored series of the part the results belong to (the part its ``run`` block
    is filed under in the store: its part number, else its program number), or of every
    part when the results have no ``run`` block."""
    import json

    from probegen.cli.history import store_series

    try:
        doc = json.loads(read_input(results_path, "results.json"))
    except (ProbegenError, json.JSONDecodeError):
        return []  # the report itself names what is wrong with the results
    from probegen.evaluate.run_identity import RunIdentity
    from probegen.store.records import part_of

    run = doc.get("run") if isinstance(doc, dict) else None
    part = part_of(RunIdentity.from_json(run)) if isinstance(run, dict) else None
    return store_series(url, part=part)
