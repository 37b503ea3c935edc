"""What limits the five-axis sample profile on real parts (issue 17, lane fiveaxis).

Parts made here reproduce what the MetalBoop plates showed with
``samples/machines/vmc-5axis-fanuc.toml`` (margin 0.5 mm, smallest ball 1 mm):

* a D7 boss sunk into a wall but for a sliver, an arc of 0.6 mm (the base plate's R54 and
  R55, arcs of 0.065 mm): the planner retries a short arc with the margin alone at each
  end, which no ball changes, so an arc no longer than twice the margin is the part's
  limit with this margin, said so, not "a smaller stylus" (the 1 mm ball is the
  smallest).
"""

from __future__ import annotations

import math
from pathlib import Path

from build123d import Align, Box, Cylinder, Pos, export_step
from conftest import REPO

from probegen import cad
from probegen.machine.profile import load_profile
from probegen.planning.revolved_spec import all_revolved_spec

FIVE = REPO / "samples/machines/vmc-5axis-fanuc.toml"
C, MIN = Align.CENTER, Align.MIN


def sliver(path: Path, arc: float) -> Path:
    """A 40 x 40 x 5 plate, a wall 10 mm thick and 5 high along its +Y edge, and a D7
    boss on the plate sunk into the wall but for an arc of ``arc`` mm (its section)."""
    radius = 3.5
    inside = radius * math.cos(arc / radius / 2.0)  # the boss's axis behind the wall face
    part = (Box(40, 40, 5, align=(C, C, MIN)) + Pos(0, 15, 5) * Box(40, 10, 5, align=(C, C, MIN))
            + Pos(0, 10 + inside, 5) * Cylinder(radius, 5, align=(C, C, MIN)))
    export_step(part, path)
    return path


def test_an_arc_under_twice_the_margin_is_the_parts_limit(tmp_path: Path) -> None:
    model = sliver(tmp_path / "sliver.step", 0.6)
    spec, notes = all_revolved_spec(cad.load_part(model), load_profile(FIVE))
    assert spec.features == ()
    assert [n.split("): ", 1)[1] for n in notes] == [
        "arc too short: the longest arc of the section measured is 0.600 mm, no longer "
        "than the margin 0.500 mm that every stylus keeps from each end (1.000 mm): the "
        "part's limit with the profile's margin"]
