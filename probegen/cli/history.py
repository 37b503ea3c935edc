"""The history commands of the command line: ``spc`` and ``export`` (registered by
:func:`probegen.cli.app.build_parser`), and the history a report draws from a store.

Each reads the series of a results store (:mod:`probegen.store`, filled by ``probegen
ingest --store``) and hands them to the room that turns them into text:
:mod:`probegen.spc` (capability, control limits, run rules) and :mod:`probegen.qdas`
(Q-DAS AQDEF and CSV exports).
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

from probegen.errors import ExitCode, ProbegenError
from probegen.files import write_file

if TYPE_CHECKING:
    from probegen.spc.series import Series

STORE_HELP = ("a results store: a SQLite file (a path or sqlite:///PATH) or a PostgreSQL "
              "database (postgresql://USER:PASSWORD@HOST/DB; docs/store.md)")
"""What ``--store URL`` names, for every command that takes it."""


def add_history_commands(sub: Any) -> None:
    """Register ``spc`` and ``export``."""
    s = sub.add_parser("spc", help="process capability (Cp, Cpk) and control limits of every "
                                   "characteristic kept in a results store")
    s.add_argument("--store", required=True, metavar="URL", help=STORE_HELP)
    _filters(s)
    s.add_argument("--format", choices=("table", "csv"), default="table",
                   help="table (for reading, default) or csv (columns feature, "
                        "characteristic, n, mean, sigma, cp, cpk, then more)")
    s.add_argument("-o", "--output", help="write to this file (default: print)")
    s.set_defaults(func=_spc)

    e = sub.add_parser("export", help="the measured values kept in a results store, for an "
                                      "SPC system: Q-DAS AQDEF (.dfq) or CSV")
    e.add_argument("--store", required=True, metavar="URL", help=STORE_HELP)
    e.add_argument("--format", choices=("dfq", "csv"), required=True,
                   help="dfq (Q-DAS AQDEF, one part number per file) or csv (one row per "
                        "run and characteristic)")
    _filters(e)
    e.add_argument("-o", "--output", required=True, help="the file to write")
    e.set_defaults(func=_export)


def _filters(p: argparse.ArgumentParser) -> None:
    p.add_argument("--part", help="only this part number")
    p.add_argument("--feature", help="only this feature id")
    p.add_argument("--characteristic", help="only this characteristic (D, X, P_FTU, ...)")


def store_series(url: str, *, part: str | None = None, feature: str | None = None,
                 characteristic: str | None = None) -> list[Series]:
    """The series of the store at ``url`` that pass the filters (opened and closed here)."""
    from probegen.store import open_store

    store = open_store(url)
    try:
        return store.series(part=part, feature=feature, characteristic=characteristic)
    finally:
        store.close()


def _selected(args: argparse.Namespace) -> list[Series]:
    series = store_series(args.store, part=args.part, feature=args.feature,
                          characteristic=args.characteristic)
    if not series:
        wanted = ", ".join(f"{k} {v!r}" for k, v in (("part", args.part),
                                                      ("feature", args.feature),
                                                      ("characteristic", args.characteristic))
                           if v)
        raise ProbegenError(f"{args.store}: expected stored runs"
                            f"{' of ' + wanted if wanted else ''}, found none "
                            "(record runs with probegen ingest --store)")
    return series


def _spc(args: argparse.Namespace) -> int:
    from probegen.spc import spc_csv, spc_table

    series = _selected(args)
    text = spc_csv(series) if args.format == "csv" else spc_table(series)
    if args.output:
        out = write_file(args.output, text, "the SPC table")
        print(f"wrote {out} ({len(series)} characteristics)")
    else:
        sys.stdout.write(text)
    return ExitCode.OK


def _export(args: argparse.Namespace) -> int:
    from probegen.qdas import DFQ_ENCODING, to_csv, to_dfq

    series = _selected(args)
    if args.format == "dfq":
        out = write_file(args.output, to_dfq(series), "the DFQ export", encoding=DFQ_ENCODING)
    else:
        out = write_file(args.output, to_csv(series), "the CSV export")
    runs = len({v.run for s in series for v in s.values})
    print(f"wrote {out} ({len(series)} characteristics, {runs} run{'' if runs == 1 else 's'})")
    return ExitCode.OK
