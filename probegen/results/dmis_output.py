"""Read DMIS output files: feature actuals, tolerance actuals and measured points.

A DMIS measuring program writes its results as DMIS statements (``OUTPUT/FA(C1)``
gives ``FA(C1)=FEAT/CIRCLE,...``).  This reader keeps what a report needs:

* **feature actuals** ``FA(name)=FEAT/<type>,...`` for POINT, PLANE, LINE, CIRCLE,
  SPHERE, CYLNDR, CONE and TORUS, decoded into :class:`FeatureActual` (see ``LAYOUTS``);
* **tolerance actuals** ``TA(name)=TOL/<kind>,...,INTOL|OUTOL`` as
  :class:`ToleranceActual`;
* **measured points** as :class:`MeasuredPoint`: ``PTMEAS/CART|POL,...`` lines echoed
  in the output (named after the enclosing ``MEAS/<type>,F(name),n`` ... ``ENDMES``
  block) and every ``FA(name)=FEAT/POINT`` actual (also listed as a feature).

Lengths are returned in mm whatever ``UNITS/MM|CM|METER|INCH|FEET`` says (the setting
in force at each statement; mm before the first), angles in degrees (``ANGDEC`` or
``ANGRAD``).  ``POL`` positions ``(r, angle, z)`` become Cartesian.  Direction vectors
are returned as unit vectors; a vector of three direction *angles* in degrees, as some
vendors write it (``179.99, 90.01, 90.0``), is recognised and turned into cosines.
Nominals (``F(name)=FEAT/...``), datums, sensors and every other statement are read
past.

Robustness is statement by statement (:func:`probegen.dmis.reader.parse_dmis_recovering`): a
statement that does not parse, or a feature or tolerance whose parameters do not fit
its type, becomes a :class:`~probegen.errors.Diagnostic` (line, column, what was
expected, what was found, caret) and every good statement is still returned.
``strict=True`` turns any diagnostic into a :class:`~probegen.errors.ResultsParseError`.

Example:
    >>> out = parse_dmis_output("FA(C1)=FEAT/CIRCLE,INNER,CART,1,2,3,0,0,1,10\\n")
    >>> out.features[0].position, out.features[0].diameter
    ((1.0, 2.0, 3.0), 10.0)
"""

from __future__ import annotations

import os
from collections.abc import Iterator

from probegen.dmis.reader import Label, Param, Statement, parse_dmis_recovering
from probegen.errors import Diagnostic, ProbegenError, strict_error
from probegen.results.dmis_decode import (
    DEGREES_PER_UNIT,
    FEATURE_TYPES,
    LAYOUTS,
    MM_PER_UNIT,
    _decode_feature,
    _decode_point,
    _decode_tolerance,
    _DecodeError,
    _Units,
    _update_units,
)
from probegen.results.dmis_records import (
    DmisOutput,
    FeatureActual,
    MeasuredPoint,
    ToleranceActual,
    Vec3,
)

__all__ = [
    "DEGREES_PER_UNIT",
    "FEATURE_TYPES",
    "LAYOUTS",
    "MM_PER_UNIT",
    "DmisOutput",
    "FeatureActual",
    "MeasuredPoint",
    "ToleranceActual",
    "Vec3",
    "parse_dmis_output",
    "read_dmis_output",
]


# -------------------------------------------------------------------- where a parameter is


def _code_chars(lines: list[str], first: int) -> Iterator[tuple[int, int, str, bool]]:
    """Yield ``(line, column, char, quoted)`` for a statement's text across continuations,
    stopping at a ``$$`` comment or the end of its last line."""
    lineno = first
    while 0 < lineno <= len(lines):
        line, quoted, continues = lines[lineno - 1].rstrip("\r"), False, False
        for column, char in enumerate(line, start=1):
            if char == "'":
                quoted = not quoted
            elif char == "$" and not quoted:
                continues = not line.startswith("$", column)
                break
            yield lineno, column, char, quoted or char == "'"
        if not continues:
            return
        lineno += 1


def _param_position(lines: list[str], first: int, index: int) -> tuple[int, int]:
    """Return the physical ``(line, column)`` where parameter ``index`` of the statement
    starting on line ``first`` begins: -1 means the statement's first character, an
    index past the last parameter the end of the statement."""
    depth, slash, commas, ready = 0, False, 0, False
    where = (first, 1)
    for lineno, column, char, quoted in _code_chars(lines, first):
        if char in " \t\f":
            continue
        if ready or index < 0:
            return lineno, column
        where = (lineno, column + 1)
        if quoted:
            continue
        if char in "([":
            depth += 1
        elif char in ")]":
            depth -= 1
        elif char == "/" and not slash:
            slash, ready = True, index == 0
        elif char == "," and slash and depth == 0:
            commas += 1
            ready = commas == index
    return where


# ------------------------------------------------------------------------------ reading


class _Reader:
    """Walk the statements in order, keeping the units and the current MEAS block."""

    def __init__(self, source: str, lines: list[str]) -> None:
        self.source, self.lines = source, lines
        self.units = _Units()
        self.block: str | None = None
        self.features: list[FeatureActual] = []
        self.tolerances: list[ToleranceActual] = []
        self.points: list[MeasuredPoint] = []
        self.diagnostics: list[Diagnostic] = []

    def read(self, stmt: Statement) -> None:
        """Read one statement; a parameter that does not fit becomes a diagnostic."""
        try:
            self._dispatch(stmt)
        except _DecodeError as exc:
            line, column = _param_position(self.lines, stmt.line, exc.index)
            text = self.lines[line - 1].rstrip("\r") if line <= len(self.lines) else ""
            head = f"{stmt.label}={stmt.major}" if stmt.label else stmt.major
            message = f"{head}: {exc.message}"
            self.diagnostics.append(Diagnostic(self.source, line, column, message, text))

    def _dispatch(self, stmt: Statement) -> None:
        kind = stmt.label.kind if stmt.label else ""
        name = stmt.label.name if stmt.label else ""
        if stmt.major == "UNITS":
            _update_units(self.units, stmt.params)
        elif stmt.major in ("MEAS", "RMEAS"):
            self.block = _block_name(stmt.params)
        elif stmt.major == "ENDMES":
            self.block = None
        elif stmt.major == "PTMEAS":
            xyz, normal = _decode_point(self.units, stmt.params)
            self.points.append(MeasuredPoint(self.block, xyz, normal, stmt.line))
        elif kind == "FA" and stmt.major == "FEAT":
            self._feature(name, stmt)
        elif kind == "TA" and stmt.major == "TOL":
            fields = _decode_tolerance(self.units, stmt.params)
            self.tolerances.append(ToleranceActual(name, *fields, line=stmt.line))

    def _feature(self, name: str, stmt: Statement) -> None:
        fields = _decode_feature(self.units, stmt.params)
        feature = FeatureActual(name, line=stmt.line, **fields)
        self.features.append(feature)
        if feature.type == "POINT":
            xyz, normal = feature.position, feature.direction
            self.points.append(MeasuredPoint(name, xyz, normal, stmt.line, "FEAT/POINT"))

    def result(self, parse_errors: tuple[Diagnostic, ...]) -> DmisOutput:
        """Return the finished output, all diagnostics in line order."""
        diagnostics = sorted((*parse_errors, *self.diagnostics), key=lambda d: (d.line, d.column))
        return DmisOutput(
            self.source,
            tuple(self.features),
            tuple(self.tolerances),
            tuple(self.points),
            tuple(diagnostics),
        )


def _block_name(params: tuple[Param, ...]) -> str | None:
    """Return the feature name of ``MEAS/<type>,F(name),n``, or None."""
    label = params[1] if len(params) > 1 else None
    return label.name if isinstance(label, Label) else None


def parse_dmis_output(text: str, *, source: str = "<string>", strict: bool = False) -> DmisOutput:
    """Parse the text of a DMIS output file.

    Args:
        text: the whole file; CRLF, LF or CR line ends; ``$`` continuations.
        source: the file name used in diagnostics.
        strict: raise instead of returning an output that has diagnostics.

    Returns:
        The feature actuals, tolerance actuals and measured points of every statement
        that could be read, and one diagnostic per statement that could not.

    Raises:
        ResultsParseError: ``strict`` is set and there is at least one diagnostic; it
            carries all of them.
    """
    dmis, parse_errors = parse_dmis_recovering(text, source=source)
    lines = text.removeprefix("\ufeff").replace("\r\n", "\n").replace("\r", "\n").split("\n")
    reader = _Reader(source, lines)
    for stmt in dmis.statements:
        reader.read(stmt)
    output = reader.result(parse_errors)
    if strict and output.diagnostics:
        raise strict_error(output.source, "DMIS output", output.diagnostics)
    return output


def read_dmis_output(path: str | os.PathLike[str], *, strict: bool = False) -> DmisOutput:
    """Read and parse a DMIS output file (UTF-8, or Latin-1 when not valid UTF-8).

    Args:
        path: the file.
        strict: raise instead of returning an output that has diagnostics.

    Raises:
        ProbegenError: the file cannot be read.
        ResultsParseError: ``strict`` is set and the file has diagnostics.
    """
    try:
        with open(path, "rb") as handle:
            data = handle.read()
    except OSError as exc:
        name = os.fspath(path)
        raise ProbegenError(f"cannot read DMIS output '{name}': {exc.strerror}") from exc
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        text = data.decode("latin-1")
    return parse_dmis_output(text, source=os.fspath(path), strict=strict)
