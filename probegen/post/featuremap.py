"""The feature map: what evaluating a posted program's log needs (``<program>.features.json``).

``probegen post`` writes it next to the program; ``probegen post-ingest`` reads it.  It
holds (format in ``docs/post.md``):

* the DMIS program *as posted* (``dmis.text``): the source text, every statement the
  post left out although the interpreter runs it (a sensor the machine lacks) turned
  into a ``$$`` comment so line numbers stay; its file name and the SHA-256 of the
  original file;
* the posted program: dialect, number, units (of the log), ball diameter (mm);
* every touch in program order: DMIS feature name, the id the log prints, index,
  PTMEAS line, approach point, probing direction and reach (work coordinates, mm), so
  each logged point is matched to its PTMEAS and checked to lie on its probing line.

JSON, keys sorted, two-space indent, ``\\n`` line ends: byte-for-byte repeatable.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from probegen.dmis.reader import logical_statements
from probegen.errors import ResultsParseError
from probegen.post.posted import PostedProgram, PostTouch
from probegen.sim.cmm.interpreter import SkippedStatement

FORMAT = "probegen-post-features"
VERSION = 1


@dataclass(frozen=True, slots=True)
class FeatureMap:
    """A read feature map (see the module docstring); lengths in mm."""

    source: str
    sha256: str
    text: str
    dialect: str
    number: int
    units: str
    ball_diameter: float
    touches: tuple[PostTouch, ...]
    skipped: tuple[tuple[int, str, str], ...] = ()
    notes: tuple[tuple[int, str, str], ...] = ()
    answers: tuple[tuple[str, str | int | float], ...] = ()


def as_posted(text: str, dropped: tuple[int, ...]) -> str:
    """``text`` with the statements starting on ``dropped`` lines made ``$$`` comments."""
    out: list[str] = []
    for first, chunk in logical_statements(text):
        lines = chunk.split("\n")
        if first in dropped:
            lines = ["$$ (left out by probegen post) " + line for line in lines]
        out += lines
    return "\n".join(out)


def feature_map(posted: PostedProgram, data: str | bytes, source: str,
                dialect: str) -> FeatureMap:
    """The feature map of ``posted``, posted from the DMIS file ``source`` whose content is
    ``data`` (bytes as read: UTF-8, else Latin-1, as ``probegen.dmis.reader.read_dmis`` reads)."""
    raw = data.encode() if isinstance(data, str) else data
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    setup = posted.program.setup
    return FeatureMap(Path(source).name, hashlib.sha256(raw).hexdigest(),
                      as_posted(text, posted.dropped_lines), dialect,
                      setup.program_number, setup.units, setup.ball_diameter,
                      posted.touches, _rows(posted.skipped), _rows(posted.notes),
                      posted.answers)


def _rows(items: tuple[SkippedStatement, ...]) -> tuple[tuple[int, str, str], ...]:
    """(line, statement, reason) rows of skipped or noted statements."""
    return tuple((s.line, s.text, s.reason) for s in items)


def dumps(fmap: FeatureMap) -> str:
    """The JSON text of ``fmap``."""
    data = {
        "format": FORMAT, "version": VERSION,
        "dmis": {"source": fmap.source, "sha256": fmap.sha256, "text": fmap.text}
        | ({"answers": dict(fmap.answers)} if fmap.answers else {}),
        "program": {"dialect": fmap.dialect, "number": fmap.number, "units": fmap.units,
                    "ball_diameter": fmap.ball_diameter},
        "touches": [{"feature": t.feature, "id": t.id, "index": t.index, "line": t.line,
                     "start": _plain(t.start), "direction": _plain(t.direction),
                     "reach": t.reach} for t in fmap.touches],
        "statements": {
            "skipped": [{"line": n, "statement": t, "reason": r} for n, t, r in fmap.skipped],
            "notes": [{"line": n, "statement": t, "note": r} for n, t, r in fmap.notes],
        },
    }
    return json.dumps(data, indent=2, sort_keys=True) + "\n"


def _plain(v: tuple[float, float, float]) -> list[float]:
    """A vector for JSON, ``-0.0`` written as ``0.0``."""
    return [x + 0.0 for x in v]


def read_feature_map(path: str | Path) -> FeatureMap:
    """Read and check a feature map.

    Raises:
        ResultsParseError: unreadable, not JSON, or a key missing or of the wrong type
            (the message names the file and the key path).
    """
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        raise ResultsParseError(f"{path}: expected the feature map (JSON) that probegen post "
                                "wrote, found no such file") from None
    except OSError as exc:
        raise ResultsParseError(f"{path}: cannot read the feature map: {exc.strerror}") from None
    return parse_feature_map(data, source=str(path))


def parse_feature_map(text: str | bytes, *, source: str = "<string>") -> FeatureMap:
    """Parse and check feature-map JSON text (see :func:`read_feature_map`)."""
    where = source
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ResultsParseError(f"{where}:{exc.lineno}:{exc.colno}: expected the JSON feature "
                                f"map that probegen post wrote, found invalid JSON "
                                f"({exc.msg})") from None
    except (UnicodeDecodeError, RecursionError) as exc:
        raise ResultsParseError(f"{where}: not a JSON feature map: {exc}") from None
    r = _Reader(where)
    if r.get(data, "format", str) != FORMAT or r.get(data, "version", int) != VERSION:
        raise ResultsParseError(f"{where}: expected format {FORMAT!r} version {VERSION}")
    dmis, program = r.get(data, "dmis", dict), r.get(data, "program", dict)
    touches = tuple(r.touch(item, f"touches[{k}]")
                    for k, item in enumerate(r.get(data, "touches", list)))
    return FeatureMap(r.get(dmis, "source", str, "dmis"), r.get(dmis, "sha256", str, "dmis"),
                      r.get(dmis, "text", str, "dmis"),
                      r.get(program, "dialect", str, "program"),
                      r.get(program, "number", int, "program"),
                      r.get(program, "units", str, "program"),
                      r.number(program, "ball_diameter", "program"), touches,
                      *_statement_rows(r, data.get("statements", {"skipped": [], "notes": []})),
                      answers=_answers(r, dmis.get("answers", {})))


def _answers(r: _Reader, table: Any) -> tuple[tuple[str, str | int | float], ...]:
    """The answers the program's TEXT/QUERY statements were posted with (name, value)."""
    if not isinstance(table, dict):
        raise r.fail("dmis.answers", "a table", table)
    for key, value in table.items():
        if not isinstance(value, str | int | float) or isinstance(value, bool):
            raise r.fail(f"dmis.answers.{key}", "a string or a number", value)
    return tuple(sorted(table.items()))


Rows = tuple[tuple[int, str, str], ...]


def _statement_rows(r: _Reader, table: Any) -> tuple[Rows, Rows]:
    """The skipped and noted statements of a map (maps before them have none)."""
    out = []
    for key, why in (("skipped", "reason"), ("notes", "note")):
        rows = r.get(table, key, list, "statements")
        out.append(tuple((r.get(row, "line", int, f"statements.{key}[{k}]"),
                          r.get(row, "statement", str, f"statements.{key}[{k}]"),
                          r.get(row, why, str, f"statements.{key}[{k}]"))
                         for k, row in enumerate(rows)))
    return out[0], out[1]


class _Reader:
    """Typed access to the JSON with key paths in the errors."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, key: str, expected: str, found: Any) -> ResultsParseError:
        return ResultsParseError(f"{self.source}: key '{key}': expected {expected}, "
                                 f"found {found!r}"[:300])

    def get(self, table: Any, key: str, kind: type, prefix: str = "") -> Any:
        path = f"{prefix}.{key}" if prefix else key
        if not isinstance(table, dict):
            raise self.fail(prefix or "(top)", "a table", table)
        if key not in table:
            raise ResultsParseError(f"{self.source}: key '{path}': expected {kind.__name__}, "
                                    "found nothing (the key is missing; is this a feature map "
                                    "written by probegen post?)")
        value = table[key]
        if not isinstance(value, kind) or isinstance(value, bool):
            raise self.fail(path, kind.__name__, value)
        return value

    def number(self, table: Any, key: str, prefix: str) -> float:
        if not isinstance(table, dict):
            raise self.fail(prefix, "a table", table)
        value = table.get(key)
        if not isinstance(value, int | float) or isinstance(value, bool) or \
                not math.isfinite(value):
            raise self.fail(f"{prefix}.{key}", "a finite number", value)
        return float(value)

    def vector(self, table: Any, key: str, prefix: str) -> tuple[float, float, float]:
        value = self.get(table, key, list, prefix)
        if len(value) != 3:
            raise self.fail(f"{prefix}.{key}", "3 numbers", value)
        x, y, z = (self.number({"v": v}, "v", f"{prefix}.{key}") for v in value)
        return (x, y, z)

    def touch(self, item: Any, prefix: str) -> PostTouch:
        return PostTouch(self.get(item, "feature", str, prefix), self.get(item, "id", str, prefix),
                         self.get(item, "index", int, prefix), self.get(item, "line", int, prefix),
                         self.vector(item, "start", prefix), self.vector(item, "direction", prefix),
                         self.number(item, "reach", prefix))
