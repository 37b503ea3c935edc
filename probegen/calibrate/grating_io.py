"""Planar-grating readings and electronic-level roll readings as CSV (method M5).

Grating readings (``readings.csv``), one row per sampling stop and line; ``#`` lines and
blank lines are comments; the first other line is the header, columns in any order::

    plane,line,index,x_mm,y_mm,z_mm,head_mm,du_um,dv_um[,offset_mm]
    XY,L10,0,-100.0000,-100.0000,-200.0000,100.0000,0.12345,-0.04321

* ``plane``: ``XY``, ``XZ`` or ``YZ``; ``du``/``dv`` are along the plane's first and
  second axis (XY: x, y; XZ: x, z; YZ: y, z).
* ``line``, ``index``: the path line (``L10``..``L34``, seed naming) and the stop's index
  on it (a corner stop is listed under both lines it joins).
* ``x_mm``, ``y_mm``, ``z_mm``: the nominal read point, work coordinates, mm, *without*
  the riser; ``offset_mm`` (optional, default 0): the riser height under the grating,
  mm, ≥ 0; the read point is moved that far along the plane's outward normal (towards
  the head: +Z for XY, −Y for XZ, −X for YZ).
* ``head_mm``: the reading head's length below the spindle gauge point (tool length), mm.
* ``du_um``, ``dv_um``: measured deviation, actual − nominal, µm.

Roll readings (``level.csv``), electronic level on the moving body::

    axis,position_mm,roll_urad
    X,-100.0,1.25

``axis`` is ``X`` or ``Y`` (a level senses tilt about horizontal axes only; the roll of
the vertical Z axis is a turn about the vertical and no level sees it).

Readers never modify their file; bad input raises :class:`CalibrationDataError` with
``file:line``, what was expected and what was found.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from probegen.errors import ProbegenError
from probegen.machine.kinematics import PLANE_OUTWARD as OUTWARD
from probegen.machine.kinematics import PLANES as PLANE_AXES

REQUIRED = ("plane", "line", "index", "x_mm", "y_mm", "z_mm", "head_mm", "du_um", "dv_um")
OPTIONAL = ("offset_mm",)
LEVEL_COLUMNS = ("axis", "position_mm", "roll_urad")
LIMIT = 1e6
"""Largest magnitude accepted for any number (mm or µm): beyond it a value is a typo."""


class CalibrationDataError(ProbegenError):
    """Calibration readings that do not follow their format (file:line, expected, found)."""

    exit_code = 6


@dataclass(frozen=True)
class GratingReading:
    """One reading at one stop.

    Attributes:
        plane: ``XY``, ``XZ`` or ``YZ``.
        line: path line name.
        index: stop index on the line.
        base: nominal read point without the riser, work mm.
        offset: riser height, mm.
        head: reading-head length, mm.
        du, dv: deviation along the plane's axes, µm.
        where: ``file:line`` of the row.
    """

    plane: str
    line: str
    index: int
    base: tuple[float, float, float]
    offset: float
    head: float
    du: float
    dv: float
    where: str = ""

    @property
    def point(self) -> tuple[float, float, float]:
        """The nominal read point with the riser applied, work mm."""
        n = PLANE_AXES[self.plane][2]
        p = list(self.base)
        p[n] += OUTWARD[self.plane] * self.offset
        return (p[0], p[1], p[2])


@dataclass(frozen=True)
class LevelReading:
    """A roll reading: axis ``X``/``Y``, position mm, roll µrad."""

    axis: str
    position: float
    roll: float
    where: str = ""


def _rows(path: str | Path) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """Header and data rows (with 1-based line numbers) of a CSV, comments skipped."""
    source = str(path)
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        raise CalibrationDataError(f"{source}: expected a CSV file, found no such file") from None
    except IsADirectoryError:
        raise CalibrationDataError(f"{source}: expected a CSV file, found a folder") from None
    except OSError as exc:
        raise CalibrationDataError(f"{source}: expected a CSV file, cannot read it: "
                                   f"{exc.strerror}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise CalibrationDataError(f"{source}: expected UTF-8 text, found the byte "
                                   f"0x{data[exc.start]:02x} at offset {exc.start}") from None
    header: list[str] | None = None
    rows: list[tuple[int, list[str]]] = []
    try:
        for number, row in enumerate(csv.reader(io.StringIO(text, newline="")), start=1):
            if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
                continue
            cells = [c.strip() for c in row]
            if header is None:
                header = [c.lower() for c in cells]
            else:
                rows.append((number, cells))
    except csv.Error as exc:
        raise CalibrationDataError(f"{source}: expected CSV, found {exc}") from exc
    if header is None:
        raise CalibrationDataError(f"{source}:1: expected a header row, found no data")
    return header, rows


def _columns(source: str, header: list[str], required: Sequence[str],
             optional: Sequence[str]) -> dict[str, int]:
    missing = [c for c in required if c not in header]
    unknown = [c for c in header if c not in required and c not in optional]
    if missing or unknown or len(set(header)) != len(header):
        raise CalibrationDataError(
            f"{source}: header: expected columns {','.join(required)} "
            f"(optional {','.join(optional) or '-'}), found {','.join(header)}")
    return {c: header.index(c) for c in header}


def _number(where: str, column: str, text: str, *, minimum: float | None = None) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or abs(value) > LIMIT or (minimum is not None
                                                           and value < minimum):
        bound = f" >= {minimum:g}" if minimum is not None else ""
        raise CalibrationDataError(f"{where}: {column}: expected a finite number{bound} "
                                   f"(|value| <= {LIMIT:g}), found {text!r}")
    return value


def read_readings(path: str | Path) -> list[GratingReading]:
    """Read a grating readings CSV (format in the module docstring).

    Raises:
        CalibrationDataError: unreadable file, bad header, a bad value, a duplicate
            (setup, line, index), or no rows.
    """
    source = str(path)
    header, rows = _rows(path)
    col = _columns(source, header, REQUIRED, OPTIONAL)
    out: list[GratingReading] = []
    seen: dict[tuple[object, ...], str] = {}
    for number, cells in rows:
        where = f"{source}:{number}"
        if len(cells) != len(header):
            raise CalibrationDataError(f"{where}: expected {len(header)} fields, "
                                       f"found {len(cells)}")
        get = {c: cells[i] for c, i in col.items()}
        plane = get["plane"].upper()
        if plane not in PLANE_AXES:
            raise CalibrationDataError(f"{where}: plane: expected XY, XZ or YZ, "
                                       f"found {get['plane']!r}")
        line = get["line"]
        if not (line.isascii() and line.isalnum()) or len(line) > 16:
            raise CalibrationDataError(f"{where}: line: expected a name of letters and "
                                       f"digits (e.g. L10), found {line!r}")
        if not get["index"].isdigit():
            raise CalibrationDataError(f"{where}: index: expected an integer >= 0, "
                                       f"found {get['index']!r}")
        base = tuple(_number(where, c, get[c]) for c in ("x_mm", "y_mm", "z_mm"))
        offset = _number(where, "offset_mm", get["offset_mm"], minimum=0.0) \
            if "offset_mm" in get else 0.0
        reading = GratingReading(
            plane, line, int(get["index"]), base, offset,  # type: ignore[arg-type]
            _number(where, "head_mm", get["head_mm"]), _number(where, "du_um", get["du_um"]),
            _number(where, "dv_um", get["dv_um"]), where)
        key = (plane, offset, reading.head, base[PLANE_AXES[plane][2]], line, reading.index)
        if key in seen:
            raise CalibrationDataError(f"{where}: expected one row per setup, line and index, "
                                       f"found {plane} {line} {reading.index} again "
                                       f"(first at {seen[key]})")
        seen[key] = where
        out.append(reading)
    if not out:
        raise CalibrationDataError(f"{source}: expected at least one reading, found none")
    return out


def format_readings(readings: Sequence[GratingReading]) -> str:
    """The CSV text of ``readings`` (the ``offset_mm`` column always written)."""
    lines = ["# probegen grating readings (M5): deviations actual - nominal, um; "
             "positions work mm",
             ",".join(REQUIRED + OPTIONAL)]
    for r in readings:
        lines.append(",".join([r.plane, r.line, str(r.index)]
                              + [f"{v:.4f}" for v in r.base] + [f"{r.head:.4f}"]
                              + [f"{r.du:.5f}", f"{r.dv:.5f}", f"{r.offset:.4f}"]))
    return "\n".join(lines) + "\n"


def read_level(path: str | Path) -> list[LevelReading]:
    """Read an electronic-level roll CSV (format in the module docstring).

    Raises:
        CalibrationDataError: as :func:`read_readings`; also a Z axis.
    """
    source = str(path)
    header, rows = _rows(path)
    col = _columns(source, header, LEVEL_COLUMNS, ())
    out = []
    for number, cells in rows:
        where = f"{source}:{number}"
        if len(cells) != len(header):
            raise CalibrationDataError(f"{where}: expected {len(header)} fields, "
                                       f"found {len(cells)}")
        axis = cells[col["axis"]].upper()
        if axis not in ("X", "Y"):
            raise CalibrationDataError(
                f"{where}: axis: expected X or Y (a level cannot sense the roll of the "
                f"vertical Z axis), found {cells[col['axis']]!r}")
        out.append(LevelReading(axis, _number(where, "position_mm", cells[col["position_mm"]]),
                                _number(where, "roll_urad", cells[col["roll_urad"]]), where))
    if not out:
        raise CalibrationDataError(f"{source}: expected at least one roll reading, found none")
    return out


def format_level(readings: Sequence[LevelReading]) -> str:
    """The CSV text of roll readings."""
    rows = [",".join(LEVEL_COLUMNS)] + [f"{r.axis},{r.position:.4f},{r.roll:.5f}"
                                        for r in readings]
    return "\n".join(rows) + "\n"
