"""Make the parts of our own making (issue 17): holes on five faces, small holes,
counterbores and countersinks, a flange with a bolt circle, holes at odd angles.

Every nominal size is a constant below, and ``samples/parts/README.md`` lists them per
part; ``tests/test_made_parts.py`` checks that revolved recognition finds each feature
with its size and axis.  All lengths mm, angles deg; the work frame is the model's.

Run from anywhere::

    .venv/bin/python samples/parts/make_parts.py

It writes the five ``.step`` files beside this script, byte-repeatable (the FILE_NAME
time stamp is pinned to ``FIXED_TIMESTAMP``, as in ``samples/bore_block``);
tests/test_made_parts.py checks that a fresh export equals each committed file.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

from build123d import (
    Align,
    Axis,
    Box,
    Cone,
    Cylinder,
    GeomType,
    Part,
    Plane,
    Pos,
    Vector,
    export_step,
    fillet,
)

FIXED_TIMESTAMP = "2000-01-01T00:00:00"
HERE = Path(__file__).resolve().parent

_MIN = (Align.MIN, Align.MIN, Align.MIN)
_DOWN = (Align.CENTER, Align.CENTER, Align.MAX)
"""A cylinder or cone hanging below its plane's origin (a hole cut from a face)."""
PAST = 1.0
"""Cutting tools stick out of the face by this much, so no sliver is left, mm."""

Vec = tuple[float, float, float]


def hole(at: Vec, direction: Vec, diameter: float, depth: float) -> Part:
    """A flat-bottomed hole cutter: diameter ``diameter``, ``depth`` deep into the part
    from the face point ``at``, ``direction`` the hole's outward axis (out of the
    material, away from the bottom)."""
    plane = Plane(origin=Vector(*at) + PAST * Vector(*direction).normalized(),
                  z_dir=Vector(*direction))
    return plane * Cylinder(diameter / 2.0, depth + PAST, align=_DOWN)


# ------------------------------------------------------------------ five-face block

BLOCK5 = (80.0, 60.0, 40.0)
"""The five-face block, from (0, 0, 0) to (80, 60, 40); its bottom face is left plain."""
BLOCK5_ROUND = 2.0
"""Its four vertical edges are rounded with this radius (fillets: quarter cylinders)."""
FIVE_FACE_HOLES: tuple[tuple[str, Vec, Vec, float, float | None], ...] = (
    ("top through", (25.0, 30.0, 40.0), (0.0, 0.0, 1.0), 20.0, None),
    ("top blind", (60.0, 40.0, 40.0), (0.0, 0.0, 1.0), 8.0, 12.0),
    ("Y through", (60.0, 60.0, 14.0), (0.0, 1.0, 0.0), 12.0, None),
    ("front blind", (25.0, 0.0, 20.0), (0.0, -1.0, 0.0), 6.0, 10.0),
    ("right blind", (80.0, 30.0, 20.0), (1.0, 0.0, 0.0), 16.0, 12.0),
    ("left blind", (0.0, 30.0, 20.0), (-1.0, 0.0, 0.0), 10.0, 10.0),
)
"""(name, centre on the face, outward axis, diameter, depth or None for through)."""


def five_face_block() -> Part:
    """A block with bores on the top and the four side faces, Ø6 to Ø20, through and
    blind (:data:`FIVE_FACE_HOLES`); its vertical edges rounded (:data:`BLOCK5_ROUND`)."""
    box = Box(*BLOCK5, align=_MIN)
    part = fillet(box.edges().filter_by(Axis.Z), BLOCK5_ROUND)
    for _name, at, direction, diameter, depth in FIVE_FACE_HOLES:
        through = max(BLOCK5) + 2.0 * PAST
        part -= hole(at, direction, diameter, through if depth is None else depth)
    return part


# ------------------------------------------------------------------ small holes

PLATE_SMALL = (70.0, 30.0, 10.0)
SMALL_HOLES: tuple[tuple[float, float], ...] = ((10.0, 1.5), (25.0, 2.5), (42.0, 4.0),
                                                (58.0, 5.0))
"""(x, diameter) of the through holes along y = 15 of the 70 x 30 x 10 plate."""


def small_holes() -> Part:
    """A plate with vertical through holes of Ø1.5, 2.5, 4 and 5 (:data:`SMALL_HOLES`)."""
    part = Box(*PLATE_SMALL, align=_MIN)
    top = PLATE_SMALL[2]
    for x, diameter in SMALL_HOLES:
        part -= hole((x, PLATE_SMALL[1] / 2.0, top), (0.0, 0.0, 1.0), diameter, top + PAST)
    return part


# ------------------------------------------------------------------ counterbores

PLATE_CB = (90.0, 40.0, 20.0)
COUNTERBORES: tuple[tuple[str, float, float, float, float], ...] = (
    ("M10 counterbore", 15.0, 11.0, 18.0, 11.0),
    ("M6 counterbore", 40.0, 6.6, 11.0, 6.5),
)
"""(name, x, hole diameter, counterbore diameter, counterbore depth) along y = 20."""
COUNTERSINKS: tuple[tuple[str, float, float, float, float], ...] = (
    ("M6 countersink", 62.0, 6.6, 13.0, 90.0),
    ("M8 countersink", 80.0, 9.0, 17.0, 90.0),
)
"""(name, x, hole diameter, countersink diameter at the top face, included angle deg)
along y = 20."""


def countersink(at: Vec, top_diameter: float, hole_diameter: float, angle: float) -> Part:
    """The cone of a countersink from ``at`` (on the top face) down to the hole, with
    ``angle`` included angle, deg, and a lip of :data:`PAST` above the face."""
    slope = math.tan(math.radians(angle / 2.0))
    height = (top_diameter - hole_diameter) / 2.0 / slope
    lip = top_diameter / 2.0 + PAST * slope
    cone = Cone(hole_diameter / 2.0, lip, height + PAST,
                align=(Align.CENTER, Align.CENTER, Align.MIN))
    return Pos(at[0], at[1], at[2] - height) * cone


def counterbores() -> Part:
    """A plate with two counterbored and two countersunk through holes
    (:data:`COUNTERBORES`, :data:`COUNTERSINKS`): a counterbore is the hole, a larger
    coaxial bore above it and the flat step between them."""
    part = Box(*PLATE_CB, align=_MIN)
    top, y = PLATE_CB[2], PLATE_CB[1] / 2.0
    for _name, x, diameter, cb_diameter, cb_depth in COUNTERBORES:
        part -= hole((x, y, top), (0.0, 0.0, 1.0), diameter, top + PAST)
        part -= hole((x, y, top), (0.0, 0.0, 1.0), cb_diameter, cb_depth)
    for _name, x, diameter, cs_diameter, angle in COUNTERSINKS:
        part -= hole((x, y, top), (0.0, 0.0, 1.0), diameter, top + PAST)
        part -= countersink((x, y, top), cs_diameter, diameter, angle)
    return part


# ------------------------------------------------------------------ flange

FLANGE_DIAMETER = 100.0
FLANGE_THICKNESS = 12.0
SPIGOT_DIAMETER = 50.0
SPIGOT_HEIGHT = 10.0
CENTRAL_BORE = 25.0
BOLT_CIRCLE = 75.0
BOLT_HOLE = 9.0
BOLT_HOLES = 6
SPIGOT_ROUND = 2.0
"""The flange: a disk centred on the Z axis from z = 0 to 12, a spigot (boss) from
z = 12 to 22, a central through bore, and 6 through holes on the bolt circle, the first
at +X, then every 60 deg; the foot of the spigot rounded with a 2 mm fillet (a torus:
major radius 27, tube radius 2, tube centre at z = 14)."""


def flange() -> Part:
    """A flange with a central bore, a spigot (its foot rounded) and a bolt circle of 6
    holes."""
    bottom = (Align.CENTER, Align.CENTER, Align.MIN)
    part = Cylinder(FLANGE_DIAMETER / 2.0, FLANGE_THICKNESS, align=bottom)
    part += Pos(0.0, 0.0, FLANGE_THICKNESS) * Cylinder(SPIGOT_DIAMETER / 2.0, SPIGOT_HEIGHT,
                                                       align=bottom)
    foot = part.edges().filter_by(GeomType.CIRCLE).filter_by(
        lambda e: abs(e.radius - SPIGOT_DIAMETER / 2.0) < 1e-6
        and abs(e.center().Z - FLANGE_THICKNESS) < 1e-6)
    part = fillet(foot, SPIGOT_ROUND)
    top = FLANGE_THICKNESS + SPIGOT_HEIGHT
    part -= hole((0.0, 0.0, top), (0.0, 0.0, 1.0), CENTRAL_BORE, top + PAST)
    for k in range(BOLT_HOLES):
        phi = 2.0 * math.pi * k / BOLT_HOLES
        at = (BOLT_CIRCLE / 2.0 * math.cos(phi), BOLT_CIRCLE / 2.0 * math.sin(phi),
              FLANGE_THICKNESS)
        part -= hole(at, (0.0, 0.0, 1.0), BOLT_HOLE, FLANGE_THICKNESS + PAST)
    return part


# ------------------------------------------------------------------ odd angles

BLOCK_ODD = (100.0, 50.0, 40.0)
"""The block before its two top edges are cut off, from (0, 0, 0) to (100, 50, 40)."""
SLOPE_FOOT = 20.0
"""Both sloping faces start at z = 20 on the end faces (x = 0 and x = 100)."""
ODD_FACES: tuple[tuple[str, float, float, float, float], ...] = (
    ("slope 30", 30.0, 100.0, 10.0, 10.0),
    ("slope 37.3", -37.3, 0.0, 8.0, 8.0),
)
"""(name, tilt deg of the face's normal from +Z towards +X, x of its foot, hole diameter,
hole depth): a blind hole square to each sloping face at the middle of the face."""
FACE_DOWN = (50.0, 25.0, 12.0, 15.0)
"""(x, y, diameter, depth): a blind hole up into the bottom face (z = 0)."""


def slope(tilt: float, foot_x: float) -> tuple[Vec, Vec]:
    """The outward normal of a sloping face and its middle point (on y = 25)."""
    t = math.radians(tilt)
    normal = (math.sin(t), 0.0, math.cos(t))
    rise = BLOCK_ODD[2] - SLOPE_FOOT
    run = rise * math.cos(t) / math.sin(t)  # signed: the top edge is inwards of the foot
    middle = (foot_x - run / 2.0, BLOCK_ODD[1] / 2.0, SLOPE_FOOT + rise / 2.0)
    return normal, middle


def odd_angle() -> Part:
    """A block with faces sloping at 30 and 37.3 deg (not on a 7.5 deg head grid), a
    blind hole square to each, and a blind hole in the bottom face (needs a setup)."""
    part = Box(*BLOCK_ODD, align=_MIN)
    size = 4.0 * max(BLOCK_ODD)
    for _name, tilt, foot_x, _diameter, _depth in ODD_FACES:
        normal, _middle = slope(tilt, foot_x)
        plane = Plane(origin=(foot_x, BLOCK_ODD[1] / 2.0, SLOPE_FOOT), z_dir=normal)
        part -= plane * Box(size, size, size, align=(Align.CENTER, Align.CENTER, Align.MIN))
    for _name, tilt, foot_x, diameter, depth in ODD_FACES:
        normal, middle = slope(tilt, foot_x)
        part -= hole(middle, normal, diameter, depth)
    x, y, diameter, depth = FACE_DOWN
    part -= hole((x, y, 0.0), (0.0, 0.0, -1.0), diameter, depth)
    return part


# ------------------------------------------------------------------ files

PARTS: dict[str, Callable[[], Part]] = {
    "five_face_block": five_face_block,
    "small_holes": small_holes,
    "counterbores": counterbores,
    "flange": flange,
    "odd_angle": odd_angle,
}
"""File stem -> the function that makes the part."""


def write(name: str, folder: Path = HERE) -> Path:
    """Write ``<folder>/<name>.step`` (the FILE_NAME time stamp pinned)."""
    part = PARTS[name]()
    part.label = name
    target = folder / f"{name}.step"
    export_step(part, target, timestamp=FIXED_TIMESTAMP)
    return target


def main(folder: Path = HERE) -> list[Path]:
    """Write every part's STEP file into ``folder`` (by default beside this script)."""
    return [write(name, folder) for name in PARTS]


if __name__ == "__main__":
    for path in main():
        print(f"wrote {path}")
