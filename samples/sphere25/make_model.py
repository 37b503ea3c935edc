"""Make the sphere25 sample: a 25.000 mm reference sphere on a stem and base disc.

Geometry (mm): sphere diameter 25.000 centred at (0, 0, 0); cylindrical stem diameter 8
from inside the sphere down to z = -60; base disc diameter 40 from z = -70 to z = -60.

Run from anywhere::

    .venv/bin/python samples/sphere25/make_model.py

It writes ``sphere25.step`` beside this script.  The export is byte-repeatable: the
FILE_NAME time stamp, which OCCT would fill with the current time, is pinned to
``FIXED_TIMESTAMP`` (build123d's ``export_step(timestamp=...)``), and nothing else in
the file depends on the clock or the host.  The header names the OCCT version
("Open CASCADE STEP processor 8.0"), so another OCCT release may change the bytes;
tests/test_samples.py checks that a fresh export equals the committed file.
"""

from __future__ import annotations

from pathlib import Path

from build123d import Align, Cylinder, Part, Pos, Sphere, export_step

SPHERE_DIAMETER = 25.0
STEM_DIAMETER = 8.0
STEM_BOTTOM_Z = -60.0
BASE_DIAMETER = 40.0
BASE_HEIGHT = 10.0
FIXED_TIMESTAMP = "2000-01-01T00:00:00"
TARGET = Path(__file__).with_name("sphere25.step")

_BOTTOM = (Align.CENTER, Align.CENTER, Align.MIN)


def make_part() -> Part:
    """Return the sphere, stem and base fused into one solid."""
    ball = Sphere(SPHERE_DIAMETER / 2)
    stem = Pos(0, 0, STEM_BOTTOM_Z) * Cylinder(STEM_DIAMETER / 2, -STEM_BOTTOM_Z, align=_BOTTOM)
    base_z = STEM_BOTTOM_Z - BASE_HEIGHT
    base = Pos(0, 0, base_z) * Cylinder(BASE_DIAMETER / 2, BASE_HEIGHT, align=_BOTTOM)
    part = ball + stem + base
    part.label = "sphere25"
    return part


def main(target: Path = TARGET) -> Path:
    """Write the STEP file (by default ``sphere25.step`` beside this script)."""
    export_step(make_part(), target, timestamp=FIXED_TIMESTAMP)
    return target


if __name__ == "__main__":
    main()
