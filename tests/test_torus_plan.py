"""Torus as a spec kind (method M2): resolution, default sections, the IR's TorusDef,
Fanuc and DMIS emission (goldens) and the virtual machine.

The model is ``samples/revolved_block``: a 30 mm bore whose top edge is rounded with
r = 4 (face 6), a torus of major radius 19 and tube radius 4 whose faces lie on the
inner half of the tube (the side towards the axis), convex: the M2 sense is inner, the
air lies outside the tube (DMIS ``OUTER``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, assert_golden

from probegen import cad, ir
from probegen.dialects import get_dialect
from probegen.machine.probe_model import ProbeModel
from probegen.planning import plan_program
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import VirtualMachine, run_text
from probegen.spec.model import load_spec

MODEL = REPO / "samples/revolved_block/revolved_block.step"
PROFILE = REPO / "samples/machines/vmc-fanuc.toml"
GOLDEN = REPO / "tests/golden/torus"


def _spec(tmp_path: Path, extra: str = "") -> Path:
    if not MODEL.exists():
        pytest.skip(f"{MODEL} is not here")
    path = tmp_path / "rim.toml"
    path.write_text(f'[part]\nmodel = "{MODEL.as_posix()}"\n\n[machine]\nprofile = '
                    f'"{PROFILE.as_posix()}"\nclearance_z = 100.0\n\n[program]\nnumber = 1005\n'
                    f'name = "RIM"\n\n[[feature]]\nid = "RIM"\nkind = "torus"\nface = 6\n'
                    f'points = 6\n{extra}')
    return path


@pytest.fixture(scope="module")
def planned(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    return plan_program(load_spec(_spec(tmp_path_factory.mktemp("rim"))),
                        runtime_variables=True)


def test_torus_definition_and_default_sections(planned) -> None:  # type: ignore[no-untyped-def]
    (rim,) = planned.revolved
    d = rim.definition
    assert isinstance(d, ir.TorusDef)
    assert (d.major_diameter, d.minor_diameter) == pytest.approx((38.0, 8.0))
    assert d.axis == pytest.approx((0.0, 0.0, 1.0))
    assert (d.inner, d.tube_side, d.concave) == (True, -1, False)
    # three sections at 20 / 50 / 80 % of the axial extent: three tube angles
    assert len(rim.plan.sections) == 3
    tilts = sorted(s.section.tilt for s in rim.plan.sections)
    assert len({round(t, 6) for t in tilts}) == 3
    assert len(rim.normals) == 18
    assert planned.clearance.minimum >= 0.0


def test_touches_lie_on_the_torus_along_its_normal(planned) -> None:  # type: ignore[no-untyped-def]
    (rim,) = planned.revolved
    d = rim.definition
    centre = np.asarray(d.centre)
    big, tube = d.major_diameter / 2.0, d.minor_diameter / 2.0
    targets = [p for p in rim.plan.path if p.normal is not None]
    for p in targets:
        c, n = np.asarray(p.contact), np.asarray(p.normal)
        rel = c - centre
        radial = rel - rel[2] * np.array([0.0, 0.0, 1.0])
        ring = centre + big * radial / np.linalg.norm(radial)  # the nearest tube centre
        assert np.linalg.norm(c - ring) == pytest.approx(tube, abs=1e-9)
        outward = (c - ring) / tube  # convex tube: the air is outside it
        assert n == pytest.approx(outward, abs=1e-9)
        assert np.asarray(p.position) == pytest.approx(c + 3.0 * n, abs=1e-9)


@pytest.mark.parametrize("dialect", ["fanuc", "dmis"])
def test_torus_program_matches_golden(planned, dialect: str) -> None:  # type: ignore[no-untyped-def]
    d = get_dialect(dialect)
    text = d.generate(planned.program)
    assert_golden(GOLDEN / f"rim{d.EXTENSION}", text)


def test_dmis_defines_a_torus(planned) -> None:  # type: ignore[no-untyped-def]
    text = get_dialect("dmis").generate(planned.program)
    feat = next(line for line in text.splitlines() if "FEAT/TORUS" in line)
    assert feat.startswith("F(RIM)=FEAT/TORUS,OUTER,CART,")
    assert feat.endswith(",0.000000,0.000000,1.000000,38.0000,8.0000")
    assert "MEAS/TORUS,F(RIM),18" in text


def test_fanuc_torus_program_runs_on_the_virtual_machine(planned) -> None:  # type: ignore[no-untyped-def]
    text = get_dialect("fanuc").generate(planned.program)
    assert "(FEATURE RIM TORUS INNER D38.0000 T8.0000)" in text
    vm = VirtualMachine(PlacedPart.from_model(cad.load_step(MODEL)), ProbeModel(3.0))
    res = run_text(text, vm, kind="macrob")
    assert res.alarm is None
    assert res.touches == 18


def test_all_revolved_plans_the_torus() -> None:
    from probegen.machine.profile import load_profile
    from probegen.planning.revolved_spec import all_revolved_spec

    if not MODEL.exists():
        pytest.skip(f"{MODEL} is not here")
    spec, _ = all_revolved_spec(cad.load_part(MODEL), load_profile(PROFILE))
    kinds = {f.kind for f in spec.features}
    assert "torus" in kinds
    rim = next(f for f in spec.features if f.kind == "torus")
    assert rim.face == 6
