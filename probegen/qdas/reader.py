"""The Q-DAS AQDEF reader: a DFQ text back into parts, characteristics and values.

It reads what probegen writes (:mod:`probegen.qdas.dfq`) and well-formed files of other
writers:

- one K-field a line, ``Knnnn value`` or ``Knnnn/i value`` (the value may be empty); blank
  lines are skipped; the value's surrounding blanks are dropped;
- ``K0100`` the number of characteristics (required; no characteristic number above it);
- part fields (K1xxx): ``/p`` the part ``p`` (no index: part 1), ``/0`` every part; a part
  field makes its part the current one, and a characteristic belongs to the part that was
  current where its number first appears;
- characteristic fields (K2xxx): ``/i`` characteristic ``i`` (no index: 1), ``/0`` every
  characteristic of the current part (its own field wins);
- value fields (K00xx): ``K0001/i`` starts a new value of characteristic ``i``, the other
  value fields (``K0002`` attribute, ``K0004`` date and time, ``K0006`` batch,
  ``K0014`` part ident, ``K0080`` subgroup, ...) belong to its latest value; ``/0`` means every
  characteristic of the current part;
- value lines (the compact form of the value part: one line per measured part, the
  characteristics separated by the byte 0x0F, the fields of one by 0x14): of each
  characteristic the value, the attribute and the date and time are read, the further
  fields are skipped;
- numbers with a decimal point or a decimal comma; dates ``d.m.yyyy/h:m[:s]`` (a blank for
  the slash and two-digit years accepted).

Other fields (K0101, K5xxx structure, K8xxx, ...) are checked for form and skipped.
Anything else is a :class:`~probegen.errors.ParseError` naming file and line, what was
expected and what was found.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from datetime import datetime

from probegen.errors import Diagnostic, ParseError
from probegen.spc.series import Series, Value

_FIELD = re.compile(r"K(\d{4})(?:/(\d{1,9}))?(?:[ \t](.*))?")
_NUMBER = re.compile(r"[+-]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][+-]?\d{1,4})?")
_INTEGER = re.compile(r"[+-]?\d{1,9}")
_DATE = re.compile(r"(\d{1,2})\.(\d{1,2})\.(\d{4}|\d{2})[/ ](\d{1,2}):(\d{1,2})(?::(\d{1,2}))?")
_NUMERIC = {"K0001", "K2101", "K2110", "K2111", "K2112", "K2113"}
_WHOLE = {"K0002", "K2022"}
_CHAR_SEP = "\x0f"
_FIELD_SEP = "\x14"


@dataclass(frozen=True, slots=True)
class DfqValue:
    """One value of a characteristic (one measured part).

    Attributes:
        measured: the value, None when the field is empty.
        attribute: K0002 (0, a valid value, when not given; 255: a placeholder).
        time: K0004 as ISO 8601 without offset (``2026-11-26T13:48:53``), None if absent.
        fields: every value field as read (``{"K0014": "S-0042"}``), K0001 included.
    """

    measured: float | None
    attribute: int
    time: str | None
    fields: dict[str, str]

    @property
    def missing(self) -> bool:
        """True when there is no usable value: an empty field, or an attribute other than
        0 (valid value): 255 placeholder, 129 invalid, 256 deleted, 290 not plausible."""
        return self.measured is None or self.attribute != 0


@dataclass(frozen=True, slots=True)
class DfqCharacteristic:
    """One characteristic: its number in the file, its fields (K2xxx) and its values.

    Attributes:
        index: the characteristic's number ``i`` in the file (1 to K0100).
        line: the line where it first appears (for messages).
        fields: its own fields and those given for every characteristic (``/0``).
        values: in file order.
    """

    index: int
    line: int
    fields: dict[str, str]
    values: tuple[DfqValue, ...]

    def number(self, key: str) -> float | None:
        """The numeric field ``key`` (K2101, K2110, ...), None when absent or empty."""
        text = self.fields.get(key, "")
        return _to_float(text) if text else None


@dataclass(frozen=True, slots=True)
class DfqPart:
    """One part: its fields (K1xxx) and its characteristics in number order."""

    index: int
    fields: dict[str, str]
    characteristics: tuple[DfqCharacteristic, ...]


@dataclass(frozen=True, slots=True)
class Dfq:
    """A DFQ file read: the declared number of characteristics (K0100) and the parts."""

    count: int
    parts: tuple[DfqPart, ...]


@dataclass(slots=True)
class _Char:
    index: int
    part: int
    line: int
    fields: dict[str, str] = field(default_factory=dict)
    values: list[dict[str, str]] = field(default_factory=list)


class _Reader:
    """The state of one read: see the module docstring for the rules."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.count: int | None = None
        self.count_line = 0
        self.current = 1
        self.parts: dict[int, dict[str, str]] = {}
        self.common_part: dict[str, str] = {}
        self.common_char: dict[int, dict[str, str]] = {}
        self.chars: dict[int, _Char] = {}

    def fail(self, line: int, text: str, message: str) -> ParseError:
        diag = Diagnostic(self.source, line, 0, message, text)
        return ParseError(str(diag), (diag,))

    def check(self, key: str, value: str, number: int, text: str) -> None:
        """Check the form of the value of a field probegen reads (numbers, dates)."""
        if key in _NUMERIC and value:
            if not _NUMBER.fullmatch(value) or not math.isfinite(_to_float(value)):
                raise self.fail(number, text, f"expected a number for {key}, "
                                              f"found {value!r}")
        elif key in _WHOLE and value:
            if not _INTEGER.fullmatch(value):
                raise self.fail(number, text, f"expected a whole number for {key}, "
                                              f"found {value!r}")
        elif key == "K0004" and value and _iso(value) is None:
            raise self.fail(number, text, "expected a date and time dd.mm.yyyy/hh:mm:ss "
                                          f"for K0004, found {value!r}")

    def char(self, index: int, line: int, text: str) -> _Char:
        if self.count is not None and index > self.count:
            raise self.fail(line, text, f"expected a characteristic number from 1 to "
                                        f"{self.count} (K0100), found {index}")
        if index not in self.chars:
            self.chars[index] = _Char(index, self.current, line)
            self.parts.setdefault(self.current, {})
        return self.chars[index]

    def targets(self, index: int | None, line: int, text: str) -> list[_Char]:
        """The characteristics a value field with ``index`` speaks of."""
        if index == 0:
            return [c for c in self.chars.values() if c.part == self.current]
        return [self.char(1 if index is None else index, line, text)]

    def line(self, number: int, text: str) -> None:
        match = _FIELD.fullmatch(text)
        if match is None:
            if _CHAR_SEP in text or _FIELD_SEP in text:
                self.value_line(number, text)
                return
            raise self.fail(number, text, "expected a K-field (Knnnn or Knnnn/i, a blank "
                                          f"and its value), found {text[:40]!r}")
        key = f"K{match[1]}"
        kind = int(match[1])
        index = None if match[2] is None else int(match[2])
        value = (match[3] or "").strip()
        if kind == 100:
            self.set_count(number, text, value)
        elif 1000 <= kind < 2000:
            self.part_field(key, index, value)
        elif 2000 <= kind < 3000:
            self.char_field(key, index, value, number, text)
        elif kind < 100:
            self.value_field(key, index, value, number, text)

    def set_count(self, number: int, text: str, value: str) -> None:
        if not _INTEGER.fullmatch(value) or int(value) < 1:
            raise self.fail(number, text, "expected the number of characteristics (a whole "
                                          f"number from 1), found {value!r}")
        if self.count is not None and int(value) != self.count:
            raise self.fail(number, text, f"expected K0100 once, found {value} after "
                                          f"{self.count} (line {self.count_line})")
        self.count, self.count_line = int(value), number
        above = [c for c in self.chars.values() if c.index > self.count]
        if above:
            raise self.fail(above[0].line, "", f"expected a characteristic number from 1 "
                                               f"to {self.count} (K0100), found "
                                               f"{above[0].index}")

    def part_field(self, key: str, index: int | None, value: str) -> None:
        if index == 0:
            self.common_part[key] = value
            return
        self.current = 1 if index is None else index
        self.parts.setdefault(self.current, {})[key] = value

    def char_field(self, key: str, index: int | None, value: str, number: int,
                   text: str) -> None:
        self.check(key, value, number, text)
        if index == 0:
            self.common_char.setdefault(self.current, {})[key] = value
        else:
            self.char(1 if index is None else index, number, text).fields[key] = value

    def value_field(self, key: str, index: int | None, value: str, number: int,
                    text: str) -> None:
        self.check(key, value, number, text)
        for c in self.targets(index, number, text):
            if key == "K0001":
                c.values.append({key: value})
            elif not c.values:
                raise self.fail(number, text, f"expected K0001/{c.index} (a value) before "
                                              f"{key}/{c.index}, found none")
            else:
                c.values[-1][key] = value

    def value_line(self, number: int, text: str) -> None:
        """A value line: one value of every characteristic, in number order."""
        if self.count is None:
            raise self.fail(number, text, "expected K0100 (the number of characteristics) "
                                          "before the first value line, found none")
        blocks = text.split(_CHAR_SEP)
        if len(blocks) != self.count:
            raise self.fail(number, text, f"expected a value line of {self.count} "
                                          f"characteristics (K0100), found {len(blocks)}")
        for i, block in enumerate(blocks, start=1):
            parts = [p.strip() for p in block.split(_FIELD_SEP)]
            self.value_field("K0001", i, parts[0], number, text)
            for key, part in zip(("K0002", "K0004"), parts[1:3], strict=False):
                if part:
                    self.value_field(key, i, part, number, text)

    def result(self, number: int) -> Dfq:
        if self.count is None:
            raise self.fail(number, "", "expected a K0100 line (the number of "
                                        "characteristics), found none")
        parts = []
        for p in sorted(self.parts):
            common = self.common_char.get(p, {})
            chars = tuple(_freeze(c, common) for _, c in sorted(self.chars.items())
                          if c.part == p)
            parts.append(DfqPart(p, {**self.common_part, **self.parts[p]}, chars))
        return Dfq(self.count, tuple(parts))


def _to_float(text: str) -> float:
    return float(text.replace(",", "."))


def _iso(text: str) -> str | None:
    """An AQDEF date and time as ISO 8601 (no offset), None when it is not one."""
    match = _DATE.fullmatch(text)
    if match is None:
        return None
    day, month, year, hour, minute = (int(g) for g in match.groups()[:5])
    second = int(match[6] or 0)
    if len(match[3]) == 2:
        year += 2000 if year < 70 else 1900
    try:
        return datetime(year, month, day, hour, minute, second).isoformat()
    except ValueError:
        return None


def _freeze(c: _Char, common: dict[str, str]) -> DfqCharacteristic:
    values = []
    for fields in c.values:
        raw = fields.get("K0001", "")
        attribute = fields.get("K0002", "")
        values.append(DfqValue(
            measured=_to_float(raw) if raw else None,
            attribute=int(attribute) if attribute else 0,
            time=_iso(fields["K0004"]) if fields.get("K0004") else None,
            fields=dict(fields)))
    return DfqCharacteristic(c.index, c.line, {**common, **c.fields}, tuple(values))


def read_dfq(text: str, source: str = "<dfq>") -> Dfq:
    """Read the AQDEF (DFQ) ``text``; ``source`` names it in messages.

    Raises:
        ParseError: a line that is not a K-field or a value line, a number, whole number
            or date that does not read, a characteristic number above K0100, a value
            field before its K0001, no K0100; the message says file:line, what was
            expected and what was found.
    """
    reader = _Reader(source)
    lines = text.split("\n")
    for number, raw in enumerate(lines, start=1):
        line = raw.rstrip("\r")
        if line.strip():
            reader.line(number, line.strip(" \t"))
    return reader.result(len(lines))


def decode_dfq(data: bytes) -> str:
    """The text of DFQ file bytes: UTF-8 when they are (a byte order mark or valid UTF-8
    beyond ASCII), else Windows-1252 (what Q-DAS software writes); undecodable bytes are
    replaced and then fail where they stand."""
    if data.startswith(b"\xef\xbb\xbf"):
        return data[3:].decode("utf-8", errors="replace")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("cp1252", errors="replace")


UNITS_READ = {"°": "deg", "deg": "deg", "grd": "deg", "mm": "mm"}
"""K2142 texts read back as a Series unit (others are kept as they are)."""


def dfq_series(dfq: Dfq, source: str = "<dfq>") -> list[Series]:
    """The characteristics of ``dfq`` as :class:`Series`, part by part, in number order.

    What a DFQ file does not carry is filled plainly, never guessed: the run key is the
    value's position (``"1"``, ``"2"``, ...), the uncertainty is None, the time is the
    K0004 wall clock without offset (``""`` when absent), the serial is K0014, the
    subgroup K0080, and the status is derived from the value and the limits as read
    (NOT EVALUATED for a missing value, see :attr:`DfqValue.missing`; ``-`` without
    limits; ``OK`` within them, limits included; else ``NOT OK``).  The feature and
    characteristic are the description (K2002, else K2001) split at its first blank
    (probegen's feature ids hold none).

    Raises:
        ParseError: a part without K1001 (part number) or a characteristic without K2101
            (nominal).
    """
    out = []
    for part in dfq.parts:
        number = part.fields.get("K1001", "")
        if not number:
            raise ParseError(f"{source}: expected K1001 (the part number) of part "
                             f"{part.index}, found none")
        out += [_series(number, c, source) for c in part.characteristics]
    return out


def _series(part: str, c: DfqCharacteristic, source: str) -> Series:
    where = f"{source}:{c.line}: characteristic {c.index}"
    nominal = c.number("K2101")
    if nominal is None:
        raise ParseError(f"{where}: expected K2101/{c.index} (its nominal), found none")
    lsl, usl = c.number("K2110"), c.number("K2111")
    lower = c.number("K2112")
    upper = c.number("K2113")
    lower = lower if lower is not None or lsl is None else lsl - nominal
    upper = upper if upper is not None or usl is None else usl - nominal
    text = c.fields.get("K2002") or c.fields.get("K2001") or str(c.index)
    feature, _, name = text.partition(" ")
    unit = c.fields.get("K2142", "")
    values = tuple(_value(str(n), v, lsl, usl) for n, v in enumerate(c.values, start=1))
    return Series(part, feature, name, nominal, lower, upper, UNITS_READ.get(unit, unit),
                  values)


def _value(run: str, v: DfqValue, lsl: float | None, usl: float | None) -> Value:
    measured = None if v.missing else v.measured
    if measured is None:
        status = "NOT EVALUATED"
    elif lsl is None and usl is None:
        status = "-"
    else:
        ok = (lsl is None or lsl <= measured) and (usl is None or measured <= usl)
        status = "OK" if ok else "NOT OK"
    return Value(run, v.time or "", v.fields.get("K0014") or None, measured, None, status,
                 v.fields.get("K0080") or None)
