"""Features between a CMM head's indexes (issue 17): planned at the nearest index when the
stylus there stands at most half a step off the feature's axis, probed square to the
feature's axis, and measured right on the virtual CMM; left out with the reason when the
index is farther off or the tilted stylus collides.

Parts: ``samples/parts/odd_angle.step`` (its 8 mm hole on the 37.3 deg slope: the
nearest index A37.5 B90 is 0.2 deg off; ``samples/parts/README.md``) and a block made
here with build123d (the generator of ``samples/parts/make_parts.py``), 80 x 60 x 60 from
the origin, with four holes drilled along head directions ``(A, B)``
(:func:`probegen.ir.frames.head_approach`):

* R2, D10 x 10 on the top face at (40, 30), axis A2 B30: nearest index A0B0 (the
  vertical probe), 2 deg off;
* R4, D10 x 10 on the +Y face at (60, 30), axis A88 B0: nearest index A90B0, 2 deg off;
* R3, D10 x 10 on the +Y face at (20, 30), axis A86.25 B3.75: 5.3 deg from any index,
  probed with the stylus leaning off its axis (planning/tilted.py);
* R1, D6.5 x 45 on the -Y face at (40, 30), axis A88 B180: nearest index A90B180, 2 deg
  off, where every stylus's shank that fits the hole meets its wall.

The virtual CMM runs each DMIS program with the part placed off by a planted offset
(no pre-travel, no noise): each hole's measured axis passes through the nominal axis
moved by the offset, and its diameter is the nominal one, both to 1 µm.
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from probegen import cad, ir
from probegen.cad.revolved import revolved_features
from probegen.cli.app import main
from probegen.dialects import get_dialect
from probegen.ir import frames
from probegen.machine.profile import load_profile
from probegen.planning import PlannedProgram, plan_program
from probegen.planning.orient import orientation_for
from probegen.planning.oriented import at_index
from probegen.planning.revolved_spec import all_revolved_spec, plan_revolved
from probegen.results import parse_dmis_output
from probegen.spec.model import Spec

CMM = REPO / "samples/machines/cmm.toml"
ODD = REPO / "samples/parts/odd_angle.step"
OFFSET = (0.004, -0.003, 0.002)
"""The planted placement error, mm."""
TOL = 1e-3
"""1 µm."""
HOLES = (((40.0, 30.0, 60.0), (2.0, 30.0), 10.0, 10.0),
         ((60.0, 60.0, 30.0), (88.0, 0.0), 10.0, 10.0),
         ((20.0, 60.0, 30.0), (86.25, 3.75), 10.0, 10.0),
         ((40.0, 0.0, 30.0), (88.0, 180.0), 6.5, 45.0))
"""The made block's holes: face point, head direction (A, B) of the axis, diameter and
depth, mm (see the module docstring)."""


@pytest.fixture(scope="module")
def tilts(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The block with holes at head directions (module docstring), as STEP."""
    from build123d import Align, Box, export_step

    spec = importlib.util.spec_from_file_location("make_parts",
                                                  REPO / "samples/parts/make_parts.py")
    assert spec is not None and spec.loader is not None
    make = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(make)
    block = Box(80.0, 60.0, 60.0, align=(Align.MIN, Align.MIN, Align.MIN))
    for at, (a, b), diameter, depth in HOLES:
        block = block - make.hole(at, frames.head_approach(a, b), diameter, depth)
    path = tmp_path_factory.mktemp("grid") / "tilts.step"
    export_step(block, str(path))
    return path


def _planned(path: Path) -> tuple[cad.Part, Spec, tuple[str, ...], PlannedProgram]:
    part = cad.load_part(path)
    spec, notes = all_revolved_spec(part, load_profile(CMM))
    planned = plan_program(spec, runtime_variables=False, part=part)
    assert planned.clearance.minimum >= 0.0
    return part, spec, notes, planned


def _head_of(planned: PlannedProgram) -> dict[str, tuple[tuple[float, float] | None, float]]:
    """Feature id -> (head angles, tilt deg) of the program's revolved features."""
    return {o.plan.spec.id: (o.orientation.head, o.orientation.tilt) for o in planned.oriented}


def _measured(part: cad.Part, planned: PlannedProgram, path: Path, tmp: Path,
              ids: set[str]) -> None:
    """Run the program on the virtual CMM with :data:`OFFSET` and check features ``ids``:
    the measured axis through the nominal one moved by the offset, the axis parallel to
    it, the diameter the nominal one (1 µm)."""
    program, out = tmp / f"{path.stem}.dmi", tmp / f"{path.stem}.out"
    program.write_text(get_dialect("dmis").generate(planned.program))
    code = main(["sim", str(program), "--part", str(path), "--machine", str(CMM),
                 "--offset", *map(str, OFFSET), "-o", str(out)])
    assert code == 0
    output = parse_dmis_output(out.read_text(), strict=True)
    nominal = {f"R{f.id}": f for f in revolved_features(part)}
    for fid in sorted(ids):
        f, found = nominal[fid], output.feature(fid)
        axis = np.asarray(f.axis)
        d = np.asarray(found.position) - (np.asarray(f.origin) + np.asarray(OFFSET))
        assert np.linalg.norm(d - np.dot(d, axis) * axis) < TOL, fid
        assert abs(abs(float(np.dot(np.asarray(found.direction), axis))) - 1.0) < 1e-6, fid
        assert found.diameter == pytest.approx(2.0 * f.radius, abs=TOL), fid


def _touches(program: ir.Program, fid: str) -> list[ir.Touch]:
    """The touches of feature ``fid``, work coordinates."""
    return [t for node, _ in frames.in_work(program.body) if isinstance(node, ir.FeatureBlock)
            for t in node.body if isinstance(t, ir.Touch) and t.feature == fid]


def test_odd_angle_hole_measured_at_the_nearest_index(tmp_path: Path) -> None:
    """The 37.3 deg hole (R1): at A37.5 B90, 0.2 deg off, touched square to its own
    axis; the 30 deg hole (R3) on the grid as before; measured on the virtual CMM."""
    part, spec, notes, planned = _planned(ODD)
    heads = _head_of(planned)
    assert heads["R1"][0] == (37.5, 90.0) and heads["R1"][1] == pytest.approx(0.2)
    assert heads["R3"] == ((30.0, -90.0), 0.0)
    assert not any("deg grid" in n for n in notes)
    text = get_dialect("dmis").generate(planned.program)
    assert "SNSDEF/PROBE,INDEX,POL,37.5,90," in text
    axis = np.asarray(next(f.axis for f in revolved_features(part) if f.id == 1))
    touches = _touches(planned.program, "R1")
    assert len(touches) == 16
    assert all(abs(float(np.dot(t.normal, axis))) < 1e-9 for t in touches)
    _measured(part, planned, ODD, tmp_path, {"R1", "R3"})


def test_tilted_holes_planned_measured_or_left_out_with_the_reason(tilts: Path,
                                                                  tmp_path: Path) -> None:
    part, spec, notes, planned = _planned(tilts)
    heads = _head_of(planned)
    assert set(heads) == {"R2", "R3", "R4"}
    assert heads["R2"][0] == (0.0, 0.0) and heads["R2"][1] == pytest.approx(2.0)
    assert heads["R4"][0] == (90.0, 0.0) and heads["R4"][1] == pytest.approx(2.0)
    # R3, 5.3 deg from any index: probed with the stylus leaning off its axis
    # (planning/tilted.py), no longer left out for a setup
    assert heads["R3"][0] is not None and heads["R3"][1] > 3.75
    assert sorted(notes) == [
        "R1 bore D6.500 (cylinder, faces 7): at the nearest head index A90B180 the stylus "
        "stands 2.00 deg off the feature's axis: no room: the stylus shank meets face 2 (a "
        "smaller or longer stylus, or another orientation) [segment 18 (touch PT 9) from "
        "(40.177, 28.646, -33.695) to (41.117, 27.707, -33.662): the stylus shank cuts "
        "0.305 mm (0.305 mm in from its side, 32.162 mm up from its lower end) into face 2]"]
    _measured(part, planned, tilts, tmp_path, {"R2", "R3", "R4"})


def test_at_index_keeps_the_plan_in_work_coordinates(tilts: Path) -> None:
    """The plan made in the exact frame and expressed at the index is the same plan in
    work coordinates; its clearance moves lie along the feature's axis, their ends at the
    index frame's clearance level."""
    part = cad.load_part(tilts)
    machine = load_profile(CMM)
    f = next(g for g in revolved_features(part) if g.id == 4)
    o = orientation_for(machine, tuple(float(v) for v in f.axis))  # type: ignore[arg-type]
    assert not isinstance(o, str) and o.exact is not None
    from probegen.spec.model import RevolvedSpec

    feature = RevolvedSpec("R4", "test", "cylinder", f.faces[0], None, None, 8, None)
    exact = plan_revolved(feature, part.turned(o.exact), machine, 120.0)
    moved = at_index(exact, o, 150.0)
    e, i = np.asarray(o.exact), np.asarray(o.rotation)
    for p, q in zip(exact.plan.path, moved.plan.path, strict=True):
        assert p.kind is q.kind
        if q.contact is not None:
            assert np.allclose(e @ p.contact, i @ q.contact, atol=1e-9)
            assert np.allclose(e @ p.normal, i @ q.normal, atol=1e-12)
        if q.kind.value in ("entry", "exit", "clear"):
            assert q.position[2] == 150.0
            step = e @ p.position - i @ q.position  # along the feature's axis
            assert np.linalg.norm(np.cross(step, f.axis)) < 1e-9
        else:
            assert np.allclose(e @ p.position, i @ q.position, atol=1e-9)
    assert moved.plan.clear_z == 150.0
    assert np.allclose(i @ moved.definition.axis, e @ exact.definition.axis, atol=1e-12)
    assert math.isclose(o.tilt, 2.0, abs_tol=1e-9)
