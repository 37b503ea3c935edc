"""The 3-D views' data: stylus path, measured points, nominal sphere, error balls.

A scene is plain data the page's viewer (``templates/report/viewer.js.j2``) draws on a
canvas: line segments with a style, points, and shaded balls.  It is embedded in the
page as JSON with fixed decimals (:func:`scene_json`), so the page is repeatable.

Error balls (method M1, "Picture"): a ball at each nominal point ``c + R·n_i`` with
radius ``ρ_i = |ε_i|·R·sin(π/12)/ε_max`` (``ε_i`` the radial residual, ``ε_max`` the
largest ``|ε_i|``), so balls about 30° apart never overlap; light for ``ε_i > 0``, dark
for ``ε_i < 0``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field

from probegen.report import palette
from probegen.report.model import Feature, Results, Vec3
from probegen.report.numbers import compact

DECIMALS = 4
"""Decimals of scene coordinates, mm (0.1 µm: finer than any drawing needs)."""

WIRE_STEPS = 36
"""Straight pieces per circle of the sphere wireframe."""

STYLES: dict[str, dict[str, object]] = {
    "rapid": {"colour": palette.PATH["rapid"], "width": 1.5, "dash": [6, 4]},
    "protected": {"colour": palette.PATH["protected"], "width": 1.5, "dash": []},
    "touch": {"colour": palette.PATH["touch"], "width": 3.0, "dash": []},
    "other": {"colour": palette.PATH["other"], "width": 1.5, "dash": []},
    "reference": {"colour": palette.REFERENCE, "width": 1.0, "dash": []},
}
"""How the viewer strokes each segment style."""


@dataclass(frozen=True, slots=True)
class Ball:
    """One error ball: centre (mm), radius ``rho`` (mm), residual ``eps`` (mm)."""

    centre: Vec3
    rho: float
    eps: float


@dataclass(slots=True)
class Scene:
    """What one 3-D view draws.

    Attributes:
        id: the page element id of the embedded JSON.
        title: caption of the view.
        segments: (start, end, style) with style a key of :data:`STYLES`.
        points: measured points, mm.
        balls: error balls.
    """

    id: str
    title: str
    segments: list[tuple[Vec3, Vec3, str]] = field(default_factory=list)
    points: list[Vec3] = field(default_factory=list)
    balls: list[Ball] = field(default_factory=list)


def error_balls(feature: Feature) -> list[Ball]:
    """The M1 error balls of a sphere test (empty without residuals or a nominal size).

    Args:
        feature: a sphere-test feature with directions, residuals and ``D``.
    """
    radius = feature.nominal_radius
    if radius is None or not feature.residuals or not feature.directions:
        return []
    eps_max = max(abs(e) for e in feature.residuals)
    scale = 0.0 if eps_max == 0.0 else radius * math.sin(math.pi / 12.0) / eps_max
    c = feature.nominal_centre
    return [Ball(_along(c, n, radius), abs(e) * scale, e)
            for n, e in zip(feature.directions, feature.residuals, strict=True)]


def path_scene(results: Results) -> Scene:
    """The stylus path coloured by segment kind, the measured points on top, and each
    sphere test's nominal sphere as a faint wireframe."""
    scene = Scene("scene-path", "Stylus path (ball centre, nominal) and measured points")
    scene.segments += [(s.start, s.end, s.group) for s in results.path]
    for f in results.features:
        scene.points += f.points
        if f.kind == "sphere_test" and f.nominal_radius:
            scene.segments += wireframe(f.nominal_centre, f.nominal_radius)
    return scene


def ball_scene(feature: Feature, index: int) -> Scene:
    """Error balls of one sphere test on its nominal sphere's wireframe."""
    scene = Scene(f"scene-balls-{index}", f"Error balls of {feature.id} (method M1)")
    if feature.nominal_radius:
        scene.segments += wireframe(feature.nominal_centre, feature.nominal_radius)
    scene.balls = error_balls(feature)
    return scene


def wireframe(centre: Vec3, radius: float) -> list[tuple[Vec3, Vec3, str]]:
    """Latitude circles every 30° and meridians every 30° of a sphere, as segments."""
    out: list[tuple[Vec3, Vec3, str]] = []
    for ring in _circles():
        pts = [_along(centre, n, radius) for n in ring]
        out += [(a, b, "reference") for a, b in zip(pts, pts[1:], strict=False)]
    return out


def _circles() -> Iterator[list[Vec3]]:
    """Unit-sphere circles: 5 latitudes and 6 meridian great circles, closed."""
    steps = [2.0 * math.pi * k / WIRE_STEPS for k in range(WIRE_STEPS + 1)]
    for lat in (30, 60, 90, 120, 150):
        t = math.radians(lat)
        yield [(math.sin(t) * math.cos(a), math.sin(t) * math.sin(a), math.cos(t))
               for a in steps]
    for lon in range(0, 180, 30):
        p = math.radians(lon)
        yield [(math.sin(a) * math.cos(p), math.sin(a) * math.sin(p), math.cos(a))
               for a in steps]


def _along(centre: Vec3, direction: Sequence[float], distance: float) -> Vec3:
    return (centre[0] + distance * direction[0], centre[1] + distance * direction[1],
            centre[2] + distance * direction[2])


def scene_json(scene: Scene) -> str:
    """The scene as JSON text with fixed decimals, safe inside a ``<script>`` element."""
    styles = list(STYLES)
    doc = {
        "title": scene.title,
        "styles": [dict(STYLES[s], name=s) for s in styles],
        "segments": [[*a, *b, styles.index(style)] for a, b, style in scene.segments],
        "points": [list(p) for p in scene.points],
        "balls": [[*b.centre, b.rho, 1 if b.eps > 0 else -1] for b in scene.balls],
        "colours": {"point": palette.POINT, "light": palette.LIGHT,
                    "lightEdge": palette.LIGHT_EDGE, "dark": palette.DARK,
                    "darkEdge": palette.DARK_EDGE},
    }
    return _dump(doc)


def _dump(value: object) -> str:
    """JSON with every float rounded to :data:`DECIMALS` decimals, trailing zeros trimmed."""
    if isinstance(value, bool) or value is None:
        return json.dumps(value)
    if isinstance(value, float):
        return compact(value, DECIMALS)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value).replace("<", "\\u003c").replace(">", "\\u003e")
    if isinstance(value, dict):
        return "{" + ",".join(f"{_dump(str(k))}:{_dump(v)}" for k, v in value.items()) + "}"
    if isinstance(value, list | tuple):
        return "[" + ",".join(_dump(v) for v in value) + "]"
    raise TypeError(f"cannot write {type(value).__name__} into a scene")


