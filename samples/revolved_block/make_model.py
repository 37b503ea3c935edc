"""Make the revolved_block sample: a block with a cone and a dome on top and a rounded bore.

Geometry (mm): block 100 x 100 x 30 from (0, 0, 0) to (100, 100, 30); on its top face

* a conical boss (frustum) at (25, 75): diameter 24 at z = 30, 16 at z = 50 (half angle
  atan(4/20) = 11.3099 degrees);
* a dome at (75, 75): the upper half of a sphere of diameter 30 centred at z = 30;
* a through-bore of diameter 30 at (25, 25) whose top edge is rounded with a 4 mm
  fillet (a torus: major radius 19, tube radius 4, tube centre at z = 26).

Run from anywhere::

    .venv/bin/python samples/revolved_block/make_model.py

It writes ``revolved_block.step`` beside this script, byte-repeatable (the FILE_NAME
time stamp is pinned to ``FIXED_TIMESTAMP``, as in ``samples/bore_block``);
tests/test_samples.py checks that a fresh export equals the committed file.
"""

from __future__ import annotations

from pathlib import Path

from build123d import (
    Align,
    Axis,
    Box,
    Cone,
    Cylinder,
    GeomType,
    Part,
    Pos,
    Sphere,
    export_step,
    fillet,
)

BLOCK = (100.0, 100.0, 30.0)
CONE_CENTRE = (25.0, 75.0)
CONE_RADII = (12.0, 8.0)
CONE_HEIGHT = 20.0
DOME_CENTRE = (75.0, 75.0)
DOME_RADIUS = 15.0
ROUND_CENTRE = (25.0, 25.0)
ROUND_RADIUS = 15.0
FILLET = 4.0
FIXED_TIMESTAMP = "2000-01-01T00:00:00"
TARGET = Path(__file__).with_name("revolved_block.step")

_MIN = (Align.MIN, Align.MIN, Align.MIN)
_BOTTOM = (Align.CENTER, Align.CENTER, Align.MIN)


def make_part() -> Part:
    """Return the block with its cone, dome and rounded bore as one solid."""
    top = BLOCK[2]
    block = Box(*BLOCK, align=_MIN)
    bore = Pos(*ROUND_CENTRE, -1.0) * Cylinder(ROUND_RADIUS, top + 2.0, align=_BOTTOM)
    block = block - bore
    rim = block.edges().filter_by(GeomType.CIRCLE).sort_by(Axis.Z)[-1]
    block = fillet(rim, FILLET)
    cone = Pos(*CONE_CENTRE, top) * Cone(*CONE_RADII, CONE_HEIGHT, align=_BOTTOM)
    dome = Pos(*DOME_CENTRE, top) * Sphere(DOME_RADIUS)
    part = block + cone + dome
    part.label = "revolved_block"
    return part


def main(target: Path = TARGET) -> Path:
    """Write the STEP file (by default ``revolved_block.step`` beside this script)."""
    export_step(make_part(), target, timestamp=FIXED_TIMESTAMP)
    return target


if __name__ == "__main__":
    main()
