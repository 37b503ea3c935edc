"""A feature the probe along its axis cannot measure, probed by a five-axis machine with
its tilted work plane (G68.2) leaning the probe off the feature's axis (issue 17,
planning/oriented.py ``_plan_tilted`` with ``lean_grid``): the neck under a ball of
tests/test_tilted.py, on the five-axis sample (OMP40 body, 40 mm across).

Along its axis every stylus's shank meets the ball; leaning out from under it (the grid
of a CMM head's indices, every 7.5 deg within the tilt axis's range, each direction
turned into the machine's A and C) the neck is measured in two sections.  The Fanuc
program runs on the virtual machine with the part placed off by a planted offset: the
neck's fitted axis passes through the nominal one moved by the offset, and its diameter
is the nominal one, to 1 µm.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from probegen import cad
from probegen.cad.revolved import revolved_features
from probegen.cli.app import main
from probegen.dialects import get_dialect
from probegen.evaluate.ingest import ingest
from probegen.machine.profile import load_profile
from probegen.planning import plan_program
from probegen.planning.oriented import lean_grid, plan_oriented
from probegen.planning.revolved_spec import all_revolved_spec
from probegen.planning.tilted import head_indices

FIVE_AXIS = REPO / "samples/machines/vmc-5axis-fanuc.toml"
OFFSET = (0.004, -0.003, 0.002)
"""The planted placement error, mm."""
TOL = 1e-3
"""1 µm."""
NECK = (30.0, 30.0, 20.0, 10.0, 12.0)
"""The neck: centre x, y, foot z, radius, height, mm (tests/test_tilted.py's part)."""


@pytest.fixture(scope="module")
def overhang(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A block 60 x 60 x 20 with the neck on its top and a ball D30 on the neck, its
    centre 13 mm above the neck's top (5 mm of overhang all round), as STEP."""
    from build123d import Align, Box, Cylinder, Pos, Sphere, export_step

    x, y, z, r, h = NECK
    block = Box(60.0, 60.0, 20.0, align=(Align.MIN, Align.MIN, Align.MIN))
    neck = Pos(x, y, z) * Cylinder(r, h, align=(Align.CENTER, Align.CENTER, Align.MIN))
    ball = Pos(x, y, z + h + 13.0) * Sphere(15.0)
    path = tmp_path_factory.mktemp("lean") / "overhang.step"
    export_step(block + neck + ball, str(path))
    return path


def test_the_lean_grid_is_the_tilt_axis_reach() -> None:
    """The sample's A -110..110: A 0..105 every 7.5 deg, B a whole turn (A 110 is off
    the grid)."""
    grid = lean_grid(load_profile(FIVE_AXIS))
    assert grid is not None and grid.a == (0.0, 110.0) and grid.step == 7.5
    indices = head_indices(grid)
    assert len(indices) == 1 + 14 * 48
    assert lean_grid(load_profile(REPO / "samples/machines/vmc-fanuc.toml")) is None


def test_neck_under_a_ball_measured_with_the_tilted_plane_leaning(
        overhang: Path, tmp_path: Path) -> None:
    part = cad.load_part(overhang)
    machine = load_profile(FIVE_AXIS)
    x, y, _, r, _ = NECK
    neck = next(f for f in revolved_features(part) if f.type == "cylinder"
                and not f.inner and abs(f.radius - r) < 1e-6
                and np.allclose(f.origin[:2], (x, y)))
    fid = f"R{neck.id}"
    spec, notes = all_revolved_spec(part, machine)
    assert not any(n.startswith(f"{fid} ") for n in notes), notes
    feature = next(f for f in spec.features if f.id == fid)
    alone = plan_oriented(feature, part, machine, spec.clearance_z)
    o = alone.orientation
    assert o.head is None and o.exact is not None and o.tilt > 3.75  # leaning
    tilt = dict(o.rotary)
    assert tilt["A"] == pytest.approx(o.tilt) and 0.0 < tilt["A"] <= 110.0
    touches = [p for p in alone.plan.plan.path if p.normal is not None]
    assert len({p.section for p in touches}) == 2 and len(touches) >= 6

    planned = plan_program(spec, runtime_variables=True, part=part)
    assert planned.clearance.minimum >= 0.0
    text = get_dialect("fanuc").generate(planned.program)
    assert "G68.2" in text and "G53.1" in text
    program, log = tmp_path / "overhang.nc", tmp_path / "overhang.log"
    program.write_text(text)
    code = main(["sim", str(program), "--part", str(overhang), "--machine", str(FIVE_AXIS),
                 "--offset", *map(str, OFFSET), "-o", str(log)])
    assert code == 0
    ing = ingest(log, spec, part=part)
    assert ing.results == ()
    (found,) = [f for f in ing.revolved if f.feature == fid]
    axis = np.asarray(neck.axis)
    d = np.asarray(found.centre) - (np.asarray(neck.origin) + np.asarray(OFFSET))
    assert np.linalg.norm(d - np.dot(d, axis) * axis) < TOL
    assert found.axis is not None
    assert abs(abs(float(np.dot(np.asarray(found.axis), axis))) - 1.0) < 1e-6
    assert found.diameter == pytest.approx(2.0 * r, abs=TOL)
