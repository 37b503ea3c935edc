"""IR nodes of the in-process decisions (``docs/actions.md``): fit and check a measured
feature at run time, then set a work offset, correct a tool or rotate the frame.

A ``Check`` computes named run-time results from the ball centres its touches stored
(``result(feature, key)`` names them); the action nodes read those results.  Keys:

| key | meaning |
|---|---|
| ``X`` ``Y`` | circle: fitted centre (work coordinates, mm) |
| ``D`` | circle: fitted diameter (ball-compensated), mm |
| ``F`` | circle: roundness (range of radial distances of the ball centres), mm |
| ``P`` | line/plane: face position along its normal axis (ball-compensated), mm |
| ``A`` | line: angle from its nominal direction, degrees (counter-clockwise +) |
| ``E`` | excess material along the outward normal (circle: +-half the size error), mm |
| ``NG`` | 1 when a limit is exceeded, else 0 |

All lengths are mm in work coordinates; a dialect converts units.
"""

from __future__ import annotations

from dataclasses import dataclass

Vec3 = tuple[float, float, float]


def result(feature: str, key: str) -> str:
    """The run-time value name of result ``key`` of ``feature`` (see the table above)."""
    return f"{feature}.{key}"


def point_names(feature: str, index: int, axes: str = "XYZ"
                ) -> tuple[str | None, str | None, str | None]:
    """The run-time value names of touch ``index``'s ball centre X, Y, Z (None for an
    axis not in ``axes``)."""
    x, y, z = (f"{feature}.{a}{index}" if a in axes else None for a in "XYZ")
    return (x, y, z)


def point_index(name: str) -> int:
    """The touch index in a name made by :func:`point_names` (``BORE.X3`` -> 3)."""
    return int(name.rsplit(".", 1)[1][1:])


@dataclass(frozen=True, slots=True)
class Limit:
    """One tolerance: ``key`` (``diameter``, ``position``, ``form``, ``angle``) and the
    lowest and highest allowed value of its deviation (mm or degrees).

    ``diameter``: D minus nominal; ``position``: circle: twice the centre's distance
    from nominal (a zone diameter), line/plane: the deviation along the outward
    normal; ``form``: the circle's roundness; ``angle``: ``|A|``.
    """

    key: str
    lower: float
    upper: float


@dataclass(frozen=True, slots=True)
class Check:
    """Fit a measured feature at run time, print the results and apply its limits.

    Attributes:
        feature: feature id.
        fit: ``circle`` (algebraic Kasa fit in XY), ``line`` (principal direction in XY
            and position) or ``plane`` (position along the normal axis).
        points: run-time names of each touch's ball centre (X, Y, Z; None = not stored).
        nominal: circle: nominal centre; line/plane: nominal position of the face (a
            point on it), mm.
        normal: line/plane: outward unit normal (axis-aligned); circle: the axis.
        diameter: circle: nominal diameter, mm (0 otherwise).
        inner: circle: a bore (True) or a boss.
        ball_radius: stylus ball radius used to compensate, mm.
        direction: line: nominal direction angle in XY (start to end), degrees in
            (-180, 180]; the fitted angle is compared modulo 180.
        limits: the tolerances to check.
        on_fail: ``alarm``, ``stop``, ``continue`` or ``flag``.
        flag: the variable set to NG with ``flag``.
        corrections: per point, the vector added to its stored ball centre before the
            fit (a probe calibration's ``r(n) − ball_radius`` along the touch's
            nominal normal, ``compensate.calibrated_centres``), mm; empty: none.
    """

    feature: str
    fit: str
    points: tuple[tuple[str | None, str | None, str | None], ...]
    nominal: Vec3
    normal: Vec3
    diameter: float
    inner: bool
    ball_radius: float
    direction: float
    limits: tuple[Limit, ...]
    on_fail: str
    flag: int | None = None
    corrections: tuple[Vec3, ...] = ()


@dataclass(frozen=True, slots=True)
class SetWorkOffset:
    """Shift work offset ``offset`` so measured features lie at their nominal places.

    ``target = running + (result - nominal)`` per axis, where ``running`` is the work
    offset the program measured in (``Setup.work_offset``).

    Attributes:
        feature: the feature it comes from.
        offset: ``G54``-``G59`` or ``G54.1 Pn``.
        running: the program's work offset.
        shifts: (axis 0-2, result name, nominal value mm) per axis set.
    """

    feature: str
    offset: str
    running: str
    shifts: tuple[tuple[int, str, float], ...]


@dataclass(frozen=True, slots=True)
class UpdateTool:
    """Correct a tool's wear: ``c = -feedback * excess``; no change within the dead
    band; an alarm beyond ``max_correction`` (lengths mm).

    Attributes:
        feature: the feature it comes from.
        tool: offset number.
        offset: ``radius`` (D wear) or ``length`` (H wear).
        excess: the result name of the excess material along the outward normal.
        dead_band: smallest correction made, mm.
        max_correction: largest correction allowed, mm.
        feedback: fraction applied.
    """

    feature: str
    tool: int
    offset: str
    excess: str
    dead_band: float
    max_correction: float
    feedback: float


@dataclass(frozen=True, slots=True)
class Align:
    """Rotate the frame by a measured angle (degrees, result name ``angle``) about
    ``centre`` (XY, work coordinates of the new offset, mm): ``mode`` ``g68`` issues
    G68 (a DMIS ``ROTATE``); ``variable`` also or only stores the angle."""

    feature: str
    angle: str
    centre: tuple[float, float]
    mode: str
    variable: int | None


ActionNode = Check | SetWorkOffset | UpdateTool | Align
"""The nodes of this module."""

SPEC_KEY = {Check: "on_out_of_tolerance", SetWorkOffset: "set_work_offset",
            UpdateTool: "update_tool", Align: "align"}
"""The spec key behind each node (for messages)."""


def describe(node: ActionNode) -> str:
    """``update_tool of feature BORE``: the node as the user wrote it."""
    return f"{SPEC_KEY[type(node)]} of feature {node.feature}"
