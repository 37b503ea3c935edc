"""A feature the probe along its axis cannot measure, probed with the CMM's head leaning
the stylus off the axis (issue 17, planning/tilted.py): as a CMM programmer measures a
neck under a ball from the side, the shank leaning away from the ball.

The part is made here with build123d: a block 60 x 60 x 20 from the origin with a neck
D20 x 12 on its top at (30, 30) and a ball D30 on the neck, its centre 13 mm above the
neck's top (the ball overhangs the neck by 5 mm all round).  Along its axis every
stylus's shank meets the ball (the part's limit for that approach, not for the head);
at an index leaning the stylus out from under the ball the neck is measured on an arc
of each of two sections.  The program runs on the virtual CMM with the part placed off
by a planted offset: the neck's measured axis passes through the nominal one moved by
the offset, and its diameter is the nominal one, to 1 µm; every DMIS point lies on the
model with its vector outward (the benchmark's check).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from probegen import cad
from probegen.cad.revolved import revolved_features
from probegen.cli.app import main
from probegen.dialects import get_dialect
from probegen.machine.profile import load_profile
from probegen.planning import plan_program
from probegen.planning.oriented import plan_oriented
from probegen.planning.revolved_spec import all_revolved_spec
from probegen.planning.tilted import head_indices
from probegen.results import DmisOutput, parse_dmis_output

sys.path.insert(0, str(REPO / "benchmarks"))
from points_on_model import check_points  # noqa: E402  (the benchmark's own check)

CMM = REPO / "samples/machines/cmm.toml"
OFFSET = (0.004, -0.003, 0.002)
"""The planted placement error, mm."""
TOL = 1e-3
"""1 µm."""
NECK = (30.0, 30.0, 20.0, 10.0, 12.0)
"""The neck: centre x, y, foot z, radius, height, mm."""
BALL = 15.0
"""The ball's radius, mm; its centre 13 mm above the neck's top."""


def _run(text: str, part: cad.Part, model: Path, tmp_path: Path) -> DmisOutput:
    """The DMIS program's points checked on the model (on it, vectors outward), then the
    program run on the virtual CMM with the part placed off by OFFSET: its output."""
    check = check_points(text, part)
    assert check.points and not check.off_model and not check.inward, check.text()
    program, out = tmp_path / f"{model.stem}.dmi", tmp_path / f"{model.stem}.out"
    program.write_text(text)
    code = main(["sim", str(program), "--part", str(model), "--machine", str(CMM),
                 "--offset", *map(str, OFFSET), "-o", str(out)])
    assert code == 0
    return parse_dmis_output(out.read_text(), strict=True)


@pytest.fixture(scope="module")
def overhang(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The block with the ball on a neck (module docstring), as STEP."""
    from build123d import Align, Box, Cylinder, Pos, Sphere, export_step

    x, y, z, r, h = NECK
    block = Box(60.0, 60.0, 20.0, align=(Align.MIN, Align.MIN, Align.MIN))
    neck = Pos(x, y, z) * Cylinder(r, h, align=(Align.CENTER, Align.CENTER, Align.MIN))
    ball = Pos(x, y, z + h + 13.0) * Sphere(BALL)
    path = tmp_path_factory.mktemp("tilted") / "overhang.step"
    export_step(block + neck + ball, str(path))
    return path


def _neck(part: cad.Part) -> object:
    x, y, _, r, _ = NECK
    return next(f for f in revolved_features(part) if f.type == "cylinder"
                and not f.inner and abs(f.radius - r) < 1e-6
                and np.allclose(f.origin[:2], (x, y)))


def test_head_indices_cover_the_grid_once() -> None:
    """A PH10-like head (A 0..105, B -180..180, 7.5 deg): A0 once, then 14 tilts times
    48 azimuths (B -180 and 180 are one index)."""
    indices = head_indices(load_profile(CMM).head)  # type: ignore[arg-type]
    assert len(indices) == 1 + 14 * 48
    assert len(set(indices)) == len(indices)
    assert (0.0, 0.0) in indices and (105.0, 180.0) not in indices


def test_neck_under_a_ball_measured_with_the_stylus_leaning_out(overhang: Path,
                                                                tmp_path: Path) -> None:
    part = cad.load_part(overhang)
    machine = load_profile(CMM)
    neck = _neck(part)
    fid = f"R{neck.id}"  # type: ignore[attr-defined]
    spec, notes = all_revolved_spec(part, machine)
    assert not any(n.startswith(f"{fid} ") for n in notes), notes
    feature = next(f for f in spec.features if f.id == fid)
    planned_alone = plan_oriented(feature, part, machine, spec.clearance_z)
    o = planned_alone.orientation
    assert o.head is not None and o.head[0] > 0.0 and o.tilt > 3.75  # leaning, not along
    touches = [p for p in planned_alone.plan.plan.path if p.normal is not None]
    assert len({p.section for p in touches}) == 2 and len(touches) >= 6

    planned = plan_program(spec, runtime_variables=False, part=part)
    assert planned.clearance.minimum >= 0.0
    text = get_dialect("dmis").generate(planned.program)
    assert f"SNSDEF/PROBE,INDEX,POL,{o.head[0]:g}," in text
    found = _run(text, part, overhang, tmp_path).feature(fid)
    axis = np.asarray(neck.axis)  # type: ignore[attr-defined]
    d = np.asarray(found.position) - (np.asarray(neck.origin)  # type: ignore[attr-defined]
                                      + np.asarray(OFFSET))
    assert np.linalg.norm(d - np.dot(d, axis) * axis) < TOL
    assert abs(abs(float(np.dot(np.asarray(found.direction), axis))) - 1.0) < 1e-6
    assert found.diameter == pytest.approx(2.0 * NECK[3], abs=TOL)


@pytest.fixture(scope="module")
def tunnel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A block 60 x 40 x 40 from the origin with a tunnel 20 x 30 x 20 (x 20..40, y 10..40,
    z 10..30) open only at its +Y end, every inner edge blended with R3.5: the back
    wall's corners are sphere octants, the two under the roof opening 35 deg below the
    horizontal (beyond the head's A 105), the vertical blends of the back wall closed
    above by the roof; as STEP."""
    from build123d import Align, Box, Pos, export_step, fillet

    block = Box(60.0, 40.0, 40.0, align=(Align.MIN, Align.MIN, Align.MIN))
    hole = Pos(20.0, 20.0, 10.0) * Box(20.0, 30.0, 20.0,
                                       align=(Align.MIN, Align.MIN, Align.MIN))
    cut = block - hole
    inner = [e for e in cut.edges() if 19.9 < e.center().X < 40.1
             and 9.9 < e.center().Z < 30.1 and e.center().Y < 39.9]
    path = tmp_path_factory.mktemp("tilted") / "tunnel.step"
    export_step(fillet(inner, 3.5), str(path))
    return path


def test_tunnel_corner_blends_measured_with_the_head_leaning(tunnel: Path,
                                                             tmp_path: Path) -> None:
    """The back wall's vertical blends under the roof, leaning out of the tunnel, measured
    on the virtual CMM to 1 µm (axis and diameter).  The roof corners' octants (spheres)
    are reached only at A105, leaning up into the tunnel's mouth from below: that path
    passes under the part's lowest point, into the table the part stands on (the
    collision check's table, planning/table.py), so they are left out for a setup."""
    part = cad.load_part(tunnel)
    machine = load_profile(CMM)
    spec, notes = all_revolved_spec(part, machine)
    features = {f"R{f.id}": f for f in revolved_features(part)}
    roof = sorted(k for k, f in features.items() if f.type == "sphere"
                  and f.extent[1] > 1.0)  # the octants above their centre: under the roof
    blends = sorted(k for k, f in features.items() if f.type == "cylinder"
                    and abs(f.axis[2]) > 0.99)
    assert len(roof) == 2 and len(blends) == 2
    assert sorted(n.split()[0] for n in notes) == roof, notes
    planned = plan_program(spec, runtime_variables=False, part=part)
    assert planned.clearance.minimum >= 0.0
    heads = {o.plan.spec.id: o.orientation for o in planned.oriented}
    assert not set(roof) & set(heads)
    for fid in blends:
        assert heads[fid].head is not None and heads[fid].tilt > 3.75, fid
    output = _run(get_dialect("dmis").generate(planned.program), part, tunnel, tmp_path)
    for fid in blends:
        f, found = features[fid], output.feature(fid)
        d = np.asarray(found.position) - (np.asarray(f.origin) + np.asarray(OFFSET))
        if f.type == "cylinder":
            axis = np.asarray(f.axis)
            d = d - np.dot(d, axis) * axis
            assert abs(abs(float(np.dot(np.asarray(found.direction), axis))) - 1.0) < 1e-6
        assert np.linalg.norm(d) < TOL, fid
        assert found.diameter == pytest.approx(2.0 * f.radius, abs=TOL), fid
