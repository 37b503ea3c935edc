"""The Q-DAS AQDEF writer: the history of one part number as a ``.dfq`` file.

A DFQ file is a description part (the part: K1xxx; each characteristic: K2xxx) and a value
part (K0xxx), one K-field a line: ``Knnnn/i value``, where ``i`` is the characteristic's
number (1 to K0100) or, for the part fields, the part's number.  The fields written and
why are in docs/exports.md; in short:

- ``K0100`` the number of characteristics; ``K1001/1`` the part number, ``K1002/1`` the
  part description (when given);
- per characteristic ``i``: ``K2001/i`` its number, a code that stays the same from one
  export to the next (``BORE.D``; a running number would move when a characteristic is
  added, and an SPC system that keys its history on K2001 would file values under the
  wrong characteristic), ``K2002/i`` its description ``FEATURE CHARACTERISTIC``
  (``BORE D``), ``K2022/i`` the decimal places, ``K2101/i`` the
  nominal, ``K2110/i``/``K2111/i`` the lower/upper specification limits (values:
  nominal + deviation) and ``K2112/i``/``K2113/i`` the deviations themselves, each only
  where toleranced, ``K2142/i`` the unit (``mm`` or ``°``);
- per run and characteristic: ``K0001/i`` the value (empty, with the attribute
  ``K0002/i 255``, a placeholder, when NOT EVALUATED: the value is marked missing, never
  invented), ``K0004/i`` the date and time (``dd.mm.yyyy/hh:mm:ss``, the wall clock of the
  stored time), ``K0014/i`` the part ident (the serial number), ``K0080/i`` the subgroup
  and ``K0081/i`` the run's position in it.

The text is repeatable (no clock, fixed decimals), has Windows line ends (CRLF) and holds
only characters of Windows-1252 (:data:`DFQ_ENCODING`), the code page Q-DAS software reads.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from probegen.errors import ProbegenError
from probegen.qdas.runs import Run, aligned, by_part, parse_time, part_runs
from probegen.spc.series import Series, Value

DFQ_ENCODING = "cp1252"
"""The encoding of a DFQ file (Windows-1252, "ANSI" to Q-DAS software)."""

NEWLINE = "\r\n"

ATTRIBUTE_EMPTY = 255
"""K0002 attribute "placeholder" (the value is not shown): a NOT EVALUATED value."""

UNITS = {"mm": "mm", "deg": "°"}
"""Series units and the K2142 text written for them (other units are written as they are)."""


def to_dfq(series: Sequence[Series], *, part_description: str | None = None,
           decimals: int = 4) -> str:
    """The AQDEF (DFQ) text of ``series``, the characteristics of one part number.

    Args:
        series: the characteristics in the order they are written (``/1``, ``/2``, ...),
            each with its values; all of one part number (one DFQ file holds one).
        part_description: written as ``K1002`` when given.
        decimals: decimal places of nominals, limits and values (also written as K2022).

    Returns:
        The file's text with CRLF line ends; encode it with :data:`DFQ_ENCODING` (every
        character is checked to have a Windows-1252 byte).

    Raises:
        ProbegenError: no series, series of several part numbers, a characteristic twice,
            ``decimals`` outside 0..10, a time that is not ISO 8601, a number that is not
            finite, or a text (part number, description, serial, subgroup) that holds a
            control character or a character Windows-1252 lacks.
    """
    if not series:
        raise ProbegenError("DFQ export: expected at least one characteristic, found none "
                            "(is the store empty, or does the filter match nothing?)")
    parts = by_part(series)
    if len(parts) > 1:
        names = ", ".join(group[0].part for group in parts)
        raise ProbegenError(f"DFQ export: expected the characteristics of one part number "
                            f"(a DFQ file holds one), found {len(parts)}: {names}; "
                            "export each part number to its own file")
    if not 0 <= decimals <= 10:
        raise ProbegenError(f"DFQ export: expected 0 to 10 decimal places, found {decimals}")
    lines = [f"K0100 {len(series)}", f"K1001/1 {text_field('K1001/1', series[0].part)}"]
    if part_description is not None:
        lines.append(f"K1002/1 {text_field('K1002/1', part_description)}")
    for i, s in enumerate(series, start=1):
        lines += _characteristic(i, s, decimals)
    runs = part_runs(series)
    columns = [aligned(s, runs) for s in series]
    positions = subgroup_positions(runs)
    for n, run in enumerate(runs):
        for i, values in enumerate(columns, start=1):
            lines += _value(i, values[n], run, positions[n], decimals)
    return NEWLINE.join(lines) + NEWLINE


def subgroup_positions(runs: Sequence[Run]) -> list[int]:
    """Each run's position in its subgroup (1, 2, ... in run order; 0 without one)."""
    seen: dict[str, int] = {}
    out = []
    for run in runs:
        if run.subgroup is None:
            out.append(0)
        else:
            seen[run.subgroup] = seen.get(run.subgroup, 0) + 1
            out.append(seen[run.subgroup])
    return out


def _characteristic(i: int, s: Series, decimals: int) -> list[str]:
    """The description fields (K2xxx) of characteristic number ``i``."""
    where = f"characteristic {i} ({s.feature} {s.characteristic})"
    code = f"{s.feature}.{s.characteristic}" if s.characteristic else s.feature
    lines = [f"K2001/{i} {text_field(f'K2001/{i}', code)}",
             f"K2002/{i} {text_field(f'K2002/{i}', f'{s.feature} {s.characteristic}')}",
             f"K2022/{i} {decimals}",
             f"K2101/{i} {fixed(s.nominal, decimals, where)}"]
    if s.lsl is not None:
        lines.append(f"K2110/{i} {fixed(s.lsl, decimals, where)}")
    if s.usl is not None:
        lines.append(f"K2111/{i} {fixed(s.usl, decimals, where)}")
    if s.lower is not None:
        lines.append(f"K2112/{i} {fixed(s.lower, decimals, where)}")
    if s.upper is not None:
        lines.append(f"K2113/{i} {fixed(s.upper, decimals, where)}")
    if s.unit:
        unit = UNITS.get(s.unit, s.unit)
        lines.append(f"K2142/{i} {text_field(f'K2142/{i}', unit)}")
    return lines


def _value(i: int, v: Value, run: Run, position: int, decimals: int) -> list[str]:
    """The value fields (K0xxx) of characteristic ``i`` in one run: its value, or an empty
    field marked as a placeholder; and the run's date and time, part ident (serial) and
    subgroup (the same for every characteristic: one run measures one part)."""
    where = f"characteristic {i}, run {run.key}"
    if v.measured is None:
        lines = [f"K0001/{i}", f"K0002/{i} {ATTRIBUTE_EMPTY}"]
    else:
        lines = [f"K0001/{i} {fixed(v.measured, decimals, where)}"]
    lines.append(f"K0004/{i} {dfq_time(run.time, where)}")
    if run.serial is not None:
        lines.append(f"K0014/{i} {text_field(f'K0014/{i}', run.serial)}")
    if run.subgroup is not None:
        lines.append(f"K0080/{i} {text_field(f'K0080/{i}', run.subgroup)}")
        lines.append(f"K0081/{i} {position}")
    return lines


def fixed(x: float, decimals: int, where: str) -> str:
    """``x`` with ``decimals`` decimal places (a point, no exponent, never ``-0``)."""
    if not math.isfinite(x):
        raise ProbegenError(f"DFQ export: {where}: expected a finite number, found {x}")
    text = f"{x:.{decimals}f}"
    return text[1:] if text.lstrip("-0.") == "" and text.startswith("-") else text


def dfq_time(iso: str, where: str) -> str:
    """An ISO 8601 time as AQDEF's ``dd.mm.yyyy/hh:mm:ss``: the wall clock of the time's
    own UTC offset (the shop's local time when the store recorded it so), whole seconds
    (fractions dropped)."""
    moment = parse_time(iso, f"DFQ export: {where}")
    m = moment
    return (f"{m.day:02d}.{m.month:02d}.{m.year:04d}/"
            f"{m.hour:02d}:{m.minute:02d}:{m.second:02d}")


def text_field(key: str, text: str) -> str:
    """``text`` as a K-field value: stripped, one line, Windows-1252.

    Raises:
        ProbegenError: ``text`` is empty, holds a control character (a line break would
            start a new K-field) or a character Windows-1252 lacks.
    """
    value = text.strip()
    if not value:
        raise ProbegenError(f"DFQ export: {key}: expected a text, found an empty one")
    for ch in value:
        if ord(ch) < 32 or ord(ch) == 127:
            raise ProbegenError(f"DFQ export: {key}: expected one line of text, found the "
                                f"control character U+{ord(ch):04X} in {value!r}")
        try:
            ch.encode(DFQ_ENCODING)
        except UnicodeEncodeError:
            raise ProbegenError(f"DFQ export: {key}: expected characters of Windows-1252 "
                                f"(Q-DAS reads DFQ files in it), found {ch!r} "
                                f"(U+{ord(ch):04X}) in {value!r}") from None
    return value
