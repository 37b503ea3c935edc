"""The probe body against parts of our own making (issue 17), with the CMM sample profile
(a TP20-like body 13.2 mm across on every stylus; the rack's longest stylus, D3L, 100 mm).

* ``pocket``: a block 40 x 40 x 120 from the origin with a D12 pocket 110 mm deep from
  its top (z = 120 down to 10) and a D8 bore 6 mm deep at the pocket's bottom.  The body
  does not fit the pocket, and no stylus of the rack is long enough for the bottom bore:
  the body truly meets the pocket's wall, so the bore is left out, the reason naming the
  body, the face and how deep it cuts (measured, checked here against the geometry).  The
  pocket itself is measured near its open end, within the stylus's reach.
* ``counterbore``: a block 40 x 40 x 100 with a D16.5 counterbore 10 mm deep (z 90-100)
  over a D12.7 bore 90 mm deep (through, z 0-90): the body fits the counterbore but not
  the bore; the bore is planned at sections the body leaves clear and both are measured
  on the virtual CMM with the part placed off by a planted offset (1 µm).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from test_head_grid import _measured

from probegen import cad
from probegen.cad.revolved import revolved_features
from probegen.machine.profile import load_profile
from probegen.planning import PlannedProgram, plan_program
from probegen.planning.revolved_spec import all_revolved_spec

CMM = REPO / "samples/machines/cmm.toml"
BODY = 13.2 / 2.0
"""The sample's probe body radius, mm."""
_CUT = re.compile(r"approach from \(([-\d.]+), ([-\d.]+), ([-\d.]+)\) to \(([-\d.]+), "
                  r"([-\d.]+), ([-\d.]+)\): the probe body cuts ([\d.]+) mm \(([\d.]+) mm in "
                  r"from its side, ([\d.]+) mm up from its lower end\) into face (\d+)")


def _block(tmp: Path, name: str, height: float,
           holes: tuple[tuple[float, float, float], ...]) -> Path:
    """A 40 x 40 x ``height`` block from the origin with coaxial holes on (20, 20), each
    ``(diameter, bottom z, top z)``, as STEP."""
    from build123d import Align, Box, Cylinder, Pos, export_step

    part = Box(40.0, 40.0, height, align=(Align.MIN, Align.MIN, Align.MIN))
    for diameter, low, high in holes:
        part -= Pos(20.0, 20.0, low) * Cylinder(diameter / 2.0, high - low,
                                                align=(Align.CENTER, Align.CENTER,
                                                       Align.MIN))
    path = tmp / f"{name}.step"
    export_step(part, str(path))
    return path


@pytest.fixture(scope="module")
def pocket(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _block(tmp_path_factory.mktemp("body"), "pocket", 120.0,
                  ((12.0, 10.0, 120.0), (8.0, 4.0, 10.0)))


@pytest.fixture(scope="module")
def counterbore(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _block(tmp_path_factory.mktemp("body"), "counterbore", 100.0,
                  ((16.5, 90.0, 100.0), (12.7, 0.0, 90.0)))


def _id_of(part: cad.Part, diameter: float) -> str:
    """The recognised bore of ``diameter`` (mm)."""
    found = [f for f in revolved_features(part) if f.type == "cylinder" and f.inner
             and abs(2.0 * f.radius - diameter) < 1e-6]
    assert len(found) == 1
    return f"R{found[0].id}"


def _within_reach(planned: PlannedProgram, fid: str, top: float) -> None:
    """Feature ``fid`` is measured with D6 (the largest ball; 50 mm, shorter than the
    feature is deep) at sections whose ball keeps the body above the part's ``top`` (z,
    mm) by the margin (0.3 mm): near the open end, not at fractions of the whole depth."""
    o = next(o for o in planned.oriented if o.plan.spec.id == fid)
    assert o.stylus.label == "D6"
    assert len(o.plan.resolved.sections) == 2
    lowest = min(s.centre[2] for s in o.plan.resolved.sections)
    assert lowest + o.stylus.length >= top + 0.3 - 1e-6


def test_a_bore_below_a_pocket_too_narrow_for_the_body_is_left_out_by_how_much(
        pocket: Path) -> None:
    part = cad.load_part(pocket)
    spec, notes = all_revolved_spec(part, load_profile(CMM))
    bottom, wall = _id_of(part, 8.0), _id_of(part, 12.0)
    assert wall in {f.id for f in spec.features}  # the pocket, near its open end
    _within_reach(plan_program(spec, runtime_variables=False, part=part), wall, 120.0)
    line = next(n for n in notes if n.startswith(f"{bottom} bore D8.000"))
    head = re.search(r"no room: the probe body meets face (\d+), ([\d.]+) mm deep \(a longer "
                     r"stylus, or another orientation\)", line)
    assert head is not None, line
    cut = _CUT.search(line)
    assert cut is not None, line
    end = np.array([float(cut[k]) for k in (4, 5, 6)])  # the ball's centre, deepest
    depth, side, up = float(cut[7]), float(cut[8]), float(cut[9])
    assert (head[1], float(head[2])) == (cut[10], depth)
    pocket_wall = {f"{cad.face_at(part.model, (20.0 + 6.0, 20.0, z)).id}" for z in (60.0,)}
    assert cut[10] in pocket_wall  # the pocket's wall, not the bore's
    # the smallest stylus's (D1, 20 mm) body: its lower end 20 mm above the ball, the
    # pocket's wall up to z = 120 (the body, 65 mm long, wholly in it: its whole length);
    # its axis off the pocket's by the ball's offset
    offset = float(np.hypot(end[0] - 20.0, end[1] - 20.0))
    assert up == pytest.approx(min(120.0 - (end[2] + 20.0), 65.0), abs=0.02)
    assert side == pytest.approx(BODY - (6.0 - offset), abs=0.02)
    assert depth == pytest.approx(min(side, up), abs=1e-9)
    assert "0.015 mm" not in line


def test_a_deep_bore_under_a_counterbore_is_planned_clear_of_the_body(
        counterbore: Path, tmp_path: Path) -> None:
    part = cad.load_part(counterbore)
    spec, notes = all_revolved_spec(part, load_profile(CMM))
    bore, wide = _id_of(part, 12.7), _id_of(part, 16.5)
    assert {bore, wide} <= {f.id for f in spec.features}, notes
    planned = plan_program(spec, runtime_variables=False, part=part)
    assert planned.clearance.minimum >= 0.0
    _within_reach(planned, bore, 100.0)
    _measured(part, planned, counterbore, tmp_path, {bore, wide})
