"""The machine a DMIS run drives (the :class:`Cmm` protocol), the mutable state of one
run and the helpers every statement handler shares.

Handlers read parameters through the helpers here, which raise

* :class:`NotExecutable` for what the virtual CMM does not execute (variables,
  expressions, statement forms it lacks): the run turns it into ``UnsupportedError``
  or, with ``skip_unsupported``, a skipped statement;
* :class:`DmisProgramError` for a program that is wrong (undefined label, a word where
  a number must be, too few points): always raised.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from probegen.constants import MM_PER_INCH
from probegen.dmis.reader import Call, Expr, Label, Param, Statement, format_param
from probegen.dmis.values import DmisProgramError
from probegen.geometry.frames import FloatArray
from probegen.sim.cmm.features import Compensation, DmisFeature, Vec3
from probegen.sim.cmm.frames import Frame
from probegen.sim.cmm.tolerances import Tolerance, ToleranceResult

DEFAULT_APPROACH = 5.0
"""SNSET/APPRCH (mm) until the program sets one."""

DEFAULT_RETRACT = 5.0
"""SNSET/RETRCT (mm) until the program sets one."""

DEFAULT_SEARCH = 5.0
"""SNSET/SEARCH (mm) until the program sets one."""


class Cmm(Protocol):
    """The machine the virtual CMM drives (coordinates: machine, mm, ball centre)."""

    @property
    def ball_radius(self) -> float:
        """Radius of the physical stylus ball (mm)."""
        ...

    def move(self, start: Vec3, end: Vec3) -> None:
        """Move the ball centre straight from ``start`` to ``end``.

        Raises:
            SimAlarm: the ball meets the part on the way.
        """
        ...

    def probe(self, start: Vec3, direction: Vec3, distance: float) -> Vec3 | None:
        """Move from ``start`` along the unit ``direction`` up to ``distance``.

        Returns:
            The ball centre where the ball touched the part, or None.
        """
        ...


class NotExecutable(Exception):
    """A statement (or a part of one) the virtual CMM does not execute."""


class SkipWithNote(NotExecutable):
    """A statement left out by design, always, with its reason and without any flag:
    what the CMM software writes for itself (report format, temperature compensation,
    fly mode, clearance zones, vision settings ...), nothing a touch depends on."""


@dataclass(frozen=True, slots=True)
class ForeignSensor:
    """A sensor that is not a touch probe (``SNSDEF/VIDEO``, ``LASER`` ...).

    Attributes:
        line: the ``SNSDEF`` line.
        text: the ``SNSDEF`` statement as written.
        kind: its kind (``VIDEO``).
    """

    line: int
    text: str
    kind: str


@dataclass(slots=True)
class MeasBlock:
    """An open ``MEAS`` ... ``ENDMES`` block.

    Attributes:
        nominal: the nominal feature measured (None when the MEAS was skipped).
        name: the measured feature's name.
        count: the number of points the MEAS statement announced.
        line: line of the MEAS statement.
        centres: ball centres recorded so far (MCS).
        vectors: their unit PTMEAS vectors (MCS).
        skipped_at: line of the skipped statement (the MEAS or one inside) that keeps
            the block from being fitted, or None.
    """

    nominal: DmisFeature | None
    name: str
    count: int
    line: int
    centres: list[FloatArray] = field(default_factory=list)
    vectors: list[FloatArray] = field(default_factory=list)
    skipped_at: int | None = None


@dataclass(slots=True)
class VmState:
    """Everything a DMIS run changes; lengths in millimetres, positions in MCS."""

    cmm: Cmm
    source: str
    compensation: Compensation
    position: FloatArray | None
    frame: Frame = field(default_factory=Frame.machine)
    scale: float = 1.0
    angle_scale: float = float(np.pi / 180.0)
    frames: dict[str, Frame] = field(default_factory=dict)
    saved: dict[str, Frame] = field(default_factory=dict)
    nominals: dict[str, DmisFeature] = field(default_factory=dict)
    actuals: dict[str, DmisFeature] = field(default_factory=dict)
    datums: dict[str, DmisFeature] = field(default_factory=dict)
    tolerances: dict[str, Tolerance] = field(default_factory=dict)
    results: dict[str, ToleranceResult] = field(default_factory=dict)
    sensors: dict[str, float] = field(default_factory=dict)
    sensor_axes: dict[str, tuple[tuple[float, float, float], tuple[float, float] | None] | None] \
        = field(default_factory=dict)
    """Per sensor: its stylus axis and head angles (``sensors.Axis``), or None."""
    sensor_lengths: dict[str, float | None] = field(default_factory=dict)
    """Per sensor: the length its SNSDEF gives (mm; the second-last number), or None."""
    foreign: dict[str, ForeignSensor] = field(default_factory=dict)
    selected_foreign: ForeignSensor | None = None
    radius: float | None = None
    notes: list[tuple[int, str, str]] = field(default_factory=list)
    approach: float = DEFAULT_APPROACH
    retract: float = DEFAULT_RETRACT
    search: float = DEFAULT_SEARCH
    depth: float = 0.0
    meas: MeasBlock | None = None
    name: str | None = None
    header: str | None = None
    lines: list[str] = field(default_factory=list)
    skipped_labels: dict[str, int] = field(default_factory=dict)
    statement: Statement | None = None

    # ------------------------------------------------------------------ errors

    def error(self, message: str) -> DmisProgramError:
        """Return a DmisProgramError located at the current statement (if any)."""
        if self.statement is None:
            return DmisProgramError(f"{self.source}: {message}")
        st = self.statement
        return DmisProgramError(f"{self.source}:{st.line}: {message} ({st.text})")

    # -------------------------------------------------------------- parameters

    def number(self, param: Param, what: str) -> float:
        """Return a numeric parameter as a float.

        Raises:
            NotExecutable: a variable or expression (the VM does not evaluate them).
            DmisProgramError: anything else that is not a number.
        """
        if isinstance(param, int | float) and not isinstance(param, bool):
            return float(param)
        if isinstance(param, str | Expr | Call):
            raise NotExecutable(f"{what} is {format_param(param)}: not a number, nor a "
                                "declared variable or an expression of them")
        raise self.error(f"{what}: expected a number, found {format_param(param)}")

    def numbers(self, params: tuple[Param, ...] | list[Param], what: str) -> list[float]:
        """Return every parameter of ``params`` as a float (see :meth:`number`)."""
        return [self.number(p, what) for p in params]

    def length(self, param: Param, what: str) -> float:
        """Return a length parameter in millimetres."""
        return self.number(param, what) * self.scale

    def label(self, param: Param, kinds: tuple[str, ...], what: str) -> Label:
        """Return ``param`` as a label of one of ``kinds``.

        Raises:
            DmisProgramError: it is not such a label.
        """
        if isinstance(param, Label) and param.kind in kinds:
            return param
        wanted = " or ".join(f"{k}(name)" for k in kinds)
        raise self.error(f"{what}: expected {wanted}, found {format_param(param)}")

    def set_units(self, words: tuple[Param, ...]) -> None:
        """Apply ``UNITS/MM|INCH[,ANGDEC|ANGRAD][,...]``."""
        lengths = {"MM": 1.0, "INCH": MM_PER_INCH}
        angles = {"ANGDEC": float(np.pi / 180.0), "ANGRAD": 1.0}
        unit = words[0] if words else None
        if not isinstance(unit, str) or unit not in lengths:
            raise NotExecutable(f"UNITS/{format_param(unit) if unit else ''}: "
                                "only MM and INCH are executed")
        angle = words[1] if len(words) > 1 else "ANGDEC"
        if not isinstance(angle, str) or angle not in angles:
            raise NotExecutable(f"angle unit {format_param(angle)}: only ANGDEC and "
                                "ANGRAD are executed")
        self.scale, self.angle_scale = lengths[unit], angles[angle]

    # ----------------------------------------------------------------- lookups

    def nominal(self, name: str) -> DmisFeature:
        """Return nominal F(name) or raise (skipped -> NotExecutable, else program error)."""
        return self._lookup(self.nominals, "F", name)

    def actual(self, name: str) -> DmisFeature:
        """Return actual FA(name) (measured or constructed)."""
        return self._lookup(self.actuals, "FA", name)

    def datum(self, name: str) -> DmisFeature:
        """Return the actual feature DATDEF made datum DAT(name)."""
        return self._lookup(self.datums, "DAT", name)

    def feature_ref(self, param: Param, what: str) -> DmisFeature:
        """Return the actual feature of an ``FA(x)`` or ``DAT(x)`` parameter."""
        ref = self.label(param, ("FA", "DAT"), what)
        return self.actual(ref.name) if ref.kind == "FA" else self.datum(ref.name)

    def _lookup(self, table: dict[str, DmisFeature], kind: str, name: str) -> DmisFeature:
        if name in table:
            return table[name]
        self.check_skipped(kind, name)
        raise self.error(f"{kind}({name}) is not defined (measured/constructed) yet")

    def check_skipped(self, kind: str, name: str) -> None:
        """Raise NotExecutable if label ``kind(name)`` came from a skipped statement."""
        key = f"{'F' if kind == 'FA' else kind}({name})"
        if key in self.skipped_labels:
            line = self.skipped_labels[key]
            raise NotExecutable(f"uses {kind}({name}), left undefined by the skipped "
                                f"statement at line {line}")

    def use_machine_stylus(self, st: Statement, why: str) -> None:
        """Select the machine's calibrated stylus for ``st`` (a sensor that stands for it)
        and note it (line, text, note)."""
        self.radius = float(self.cmm.ball_radius)
        self.notes.append((st.line, st.text, f"{why}: mapped to the machine's calibrated "
                                             f"stylus D{2 * self.radius:g} mm"))

    def emit(self, text: str) -> None:
        """Append text (one or more lines) to the output file."""
        self.lines.append(text)
