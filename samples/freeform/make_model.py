"""Make the freeform sample: a block whose top is a B-spline bump, with a bore through it.

Geometry (mm): a block 60 x 40 from (0, 0, 0) to (60, 40, ...) whose top face is the
B-spline surface interpolating ``z = 20 + 6·cos(π(x − 30)/50)·cos(π(y − 20)/50)`` on a
grid over x -5..65, y -5..45 (slopes up to about 25°); a vertical through-bore of
diameter 8 at (44, 20) cuts a hole (an inner loop) into that face.

Run from anywhere::

    .venv/bin/python samples/freeform/make_model.py

It writes ``freeform.step`` beside this script, byte-repeatable (the FILE_NAME time
stamp is pinned to ``FIXED_TIMESTAMP``); tests/test_samples.py checks that
a fresh export equals the committed file.
"""

from __future__ import annotations

import math
from pathlib import Path

from build123d import Align, Box, Cylinder, Face, Keep, Part, Pos, Vector, export_step

BLOCK = (60.0, 40.0, 40.0)
BASE_Z = 20.0
AMPLITUDE = 6.0
WAVE = 50.0
BORE_DIAMETER = 8.0
BORE_CENTRE = (44.0, 20.0)
FIXED_TIMESTAMP = "2000-01-01T00:00:00"
TARGET = Path(__file__).with_name("freeform.step")

_MIN = (Align.MIN, Align.MIN, Align.MIN)
_BOTTOM = (Align.CENTER, Align.CENTER, Align.MIN)


def height(x: float, y: float) -> float:
    """The design height of the top surface at ``(x, y)``, mm."""
    return BASE_Z + AMPLITUDE * math.cos(math.pi * (x - 30.0) / WAVE) * math.cos(
        math.pi * (y - 20.0) / WAVE)


def top_surface() -> Face:
    """The B-spline face through the design heights on a 15 x 11 grid (5 mm pitch)."""
    rows = [[Vector(x, y, height(x, y)) for x in range(-5, 70, 5)] for y in range(-5, 50, 5)]
    return Face.make_surface_from_array_of_points(rows)


def make_part() -> Part:
    """Return the block cut by the B-spline surface, with the bore."""
    block = Box(*BLOCK, align=_MIN)
    cut = block.split(top_surface(), keep=Keep.TOP)
    bore = Pos(*BORE_CENTRE, -1.0) * Cylinder(BORE_DIAMETER / 2, BLOCK[2] + 2.0,
                                              align=_BOTTOM)
    part = Part(cut.wrapped) - bore
    part.label = "freeform"
    return part


def main(target: Path = TARGET) -> Path:
    """Write the STEP file (by default ``freeform.step`` beside this script)."""
    export_step(make_part(), target, timestamp=FIXED_TIMESTAMP)
    return target


if __name__ == "__main__":
    main()
