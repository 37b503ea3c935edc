"""Make the bore_block sample: a block with a through-bore and a boss on top.

Geometry (mm): block 100 x 100 x 50 from (0, 0, 0) to (100, 100, 50); a vertical
through-bore of diameter 50 at (50, 50); a boss of diameter 20 and height 20 on the top
face at (20, 20), from z = 50 to z = 70.

Run from anywhere::

    .venv/bin/python samples/bore_block/make_model.py

It writes ``bore_block.step`` beside this script.  The export is byte-repeatable in the
same way as ``samples/sphere25/make_model.py`` (the FILE_NAME time stamp is pinned to
``FIXED_TIMESTAMP``); tests/test_samples.py checks that a fresh export
equals the committed file and builds variants (another bore diameter) with
``make_part``; tests/test_actions_closed_loop.py also plants a boss of another
diameter.
"""

from __future__ import annotations

from pathlib import Path

from build123d import Align, Box, Cylinder, Part, Pos, export_step

BLOCK = (100.0, 100.0, 50.0)
BORE_DIAMETER = 50.0
BORE_CENTRE = (50.0, 50.0)
BOSS_DIAMETER = 20.0
BOSS_HEIGHT = 20.0
BOSS_CENTRE = (20.0, 20.0)
FIXED_TIMESTAMP = "2000-01-01T00:00:00"
TARGET = Path(__file__).with_name("bore_block.step")

_MIN = (Align.MIN, Align.MIN, Align.MIN)
_BOTTOM = (Align.CENTER, Align.CENTER, Align.MIN)


def make_part(bore_diameter: float = BORE_DIAMETER,
              boss_diameter: float = BOSS_DIAMETER) -> Part:
    """Return the block with its bore and boss as one solid."""
    block = Box(*BLOCK, align=_MIN)
    bore = Pos(*BORE_CENTRE, -1.0) * Cylinder(bore_diameter / 2, BLOCK[2] + 2.0, align=_BOTTOM)
    boss = Pos(*BOSS_CENTRE, BLOCK[2]) * Cylinder(boss_diameter / 2, BOSS_HEIGHT, align=_BOTTOM)
    part = block - bore + boss
    part.label = "bore_block"
    return part


def main(target: Path = TARGET, bore_diameter: float = BORE_DIAMETER,
         boss_diameter: float = BOSS_DIAMETER) -> Path:
    """Write the STEP file (by default ``bore_block.step`` beside this script)."""
    export_step(make_part(bore_diameter, boss_diameter), target, timestamp=FIXED_TIMESTAMP)
    return target


if __name__ == "__main__":
    main()
