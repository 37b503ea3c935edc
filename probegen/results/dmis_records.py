"""DMIS output records: feature actuals, tolerance actuals, measured points, the output.

The frozen records :func:`probegen.results.dmis_output.parse_dmis_output` returns;
lengths mm, angles degrees.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from probegen.errors import Diagnostic, ProbegenError, did_you_mean

Vec3 = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class FeatureActual:
    """A measured feature, ``FA(name)=FEAT/<type>,...``; lengths mm, angles degrees.

    Attributes:
        name: the label name, upper case (``A_CIRCLE`` of ``FA(A_CIRCLE)``).
        type: the DMIS feature type: ``POINT``, ``PLANE``, ``LINE``, ``CIRCLE``,
            ``SPHERE``, ``CYLNDR``, ``CONE`` or ``TORUS``.
        material: ``"INNER"`` (a hole; a torus: air inside the tube), ``"OUTER"`` (a
            boss; a torus: material inside the tube) or None (types without).
        position: the feature's point: centre (circle, sphere, torus), a point on the axis
            (cylinder), the apex (cone), the point (point, plane, line start).
        direction: unit normal (point, plane, circle), axis (cylinder, cone, torus),
            direction (line); None for a point written without one (or as 0, 0, 0)
            and a sphere without an axis.
        diameter: circle, sphere and cylinder diameter; a torus's major diameter
            (twice the radius of the tube's centre circle).
        minor_diameter: a torus's tube (minor) diameter.
        length: cylinder length when written; bounded line length.
        angle: cone included (full apex) angle, degrees.
        end: end point of a bounded line (``LINE,BND``).
        normal: unit normal of the plane a line lies in, when written.
        line: 1-based line number of the statement in the file.
    """

    name: str
    type: str
    material: Literal["INNER", "OUTER"] | None
    position: Vec3
    direction: Vec3 | None
    diameter: float | None = None
    minor_diameter: float | None = None
    length: float | None = None
    angle: float | None = None
    end: Vec3 | None = None
    normal: Vec3 | None = None
    line: int = 0

    @property
    def inner(self) -> bool | None:
        """True for an inner (hole) feature, False for outer, None if not stated."""
        return None if self.material is None else self.material == "INNER"

    @property
    def radius(self) -> float | None:
        """Half the diameter, or None."""
        return None if self.diameter is None else self.diameter / 2.0


@dataclass(frozen=True, slots=True)
class ToleranceActual:
    """An evaluated tolerance, ``TA(name)=TOL/<kind>,...,INTOL|OUTOL``.

    Attributes:
        name: the label name, upper case.
        kind: the tolerance kind (``DIAM``, ``POS``, ``FLAT``, ``CORTOL``, ...).
        values: the numbers as written, in order, converted to mm (or degrees for
            ``ANGL``, ``ANGLB`` and ``ANGLWRT``).
        qualifiers: the words other than INTOL/OUTOL (``2D``, ``XAXIS``, ``RFS``...).
        status: ``"INTOL"`` or ``"OUTOL"``.
        line: 1-based line number of the statement.
    """

    name: str
    kind: str
    values: tuple[float, ...]
    qualifiers: tuple[str, ...]
    status: Literal["INTOL", "OUTOL"]
    line: int = 0

    @property
    def value(self) -> float:
        """The actual (the first number written)."""
        return self.values[0]

    @property
    def intol(self) -> bool:
        """True when the machine judged the feature within tolerance."""
        return self.status == "INTOL"


@dataclass(frozen=True, slots=True)
class MeasuredPoint:
    """A measured point, mm.

    Attributes:
        feature: the feature it belongs to (the ``MEAS`` block's label name, or the
            point feature's own name), None outside any block.
        xyz: the point.
        normal: unit approach/surface normal when written, else None.
        line: 1-based line number of the statement.
        via: ``"PTMEAS"`` (an echoed ``PTMEAS`` line) or ``"FEAT/POINT"`` (a point
            feature actual).
    """

    feature: str | None
    xyz: Vec3
    normal: Vec3 | None
    line: int = 0
    via: Literal["PTMEAS", "FEAT/POINT"] = "PTMEAS"


@dataclass(frozen=True, slots=True)
class DmisOutput:
    """Everything read from one DMIS output file, good records and diagnostics side by side.

    Attributes:
        source: file name or ``<string>``.
        features: feature actuals in file order.
        tolerances: tolerance actuals in file order.
        points: measured points in file order.
        diagnostics: one per statement that could not be read, in line order.
    """

    source: str
    features: tuple[FeatureActual, ...]
    tolerances: tuple[ToleranceActual, ...]
    points: tuple[MeasuredPoint, ...]
    diagnostics: tuple[Diagnostic, ...]

    def feature(self, name: str) -> FeatureActual:
        """Return the last actual of feature ``name`` (any case).

        Raises:
            ProbegenError: no such feature; the message suggests the closest name.
        """
        wanted = name.upper()
        found = [f for f in self.features if f.name == wanted]
        if not found:
            names = {f.name for f in self.features}
            hint = did_you_mean(wanted, names)
            raise ProbegenError(f"{self.source}: no feature actual FA({wanted}){hint}")
        return found[-1]
