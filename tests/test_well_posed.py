"""The free-fit rule (geometry/determined.py), the planner's side (planning/well_posed.py)
and a real part's CMM program on the virtual CMM (issue 17: every program runs with no
alarm)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen import cad
from probegen.geometry.determined import levels, undetermined
from probegen.geometry.fits_axial import fit_torus
from probegen.machine.profile import load_profile
from probegen.planning.well_posed import fits_freely

Z = (0.0, 0.0, 1.0)
PARTS = REPO.parent / "shared" / "ref" / "parts"


def ring(radius: float, z: float, n: int = 8, arc: float = 2.0 * math.pi,
         start: float = 0.0) -> np.ndarray:
    """``n`` points on a horizontal circle at height ``z`` over ``arc`` radians."""
    t = start + np.linspace(0.0, arc, n, endpoint=arc < 2.0 * math.pi)
    return np.column_stack([radius * np.cos(t), radius * np.sin(t), np.full(n, z)])


def test_one_section_does_not_determine_a_cone_a_cylinder_or_a_sphere() -> None:
    """The points of one section lie on one circle, on many cones, cylinders and spheres;
    a second section (for a sphere: a pole touch) determines them."""
    one = ring(5.0, 2.0)
    for kind in ("cone", "cylinder", "sphere"):
        assert "in one section: a free " + kind in undetermined(kind, one, Z)
    assert undetermined("cone", np.vstack([one, ring(4.0, 3.0)]), Z) == ""
    assert undetermined("cylinder", np.vstack([one, ring(5.0, 6.0, 3)]), Z) == ""
    pole = np.array([[0.0, 0.0, 7.0]])
    assert undetermined("sphere", np.vstack([ring(5.0, 0.0, 4), pole]), None) == ""


def test_a_torus_needs_three_tube_positions_and_a_circle_three_points() -> None:
    two = np.vstack([ring(10.0, 0.5), ring(9.0, 1.0)])
    assert "a free torus fit needs three sections" in undetermined("torus", two, Z)
    assert undetermined("torus", np.vstack([two, ring(9.2, 1.5)]), Z) == ""
    assert "a free circle fit needs at least 3" in undetermined("circle", ring(5, 0, 2), Z)
    assert undetermined("circle", ring(5.0, 0.0, 3, arc=0.5), Z) == ""
    line = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    assert "on one line" in undetermined("circle", line, Z)


def test_a_tilted_section_stays_one_level() -> None:
    """A ring of a part tilted 0.1 deg, radius 50 mm (0.09 mm of height across it), is
    one level; two sections 0.1 mm apart are two."""
    tilt = math.radians(0.1)
    r = ring(50.0, 0.0, 16)
    r[:, 2] = r[:, 0] * math.tan(tilt)
    assert levels(r, Z) == [16]
    assert levels(np.vstack([ring(5.0, 0.0), ring(5.0, 0.1)]), Z) == [8, 8]


def test_only_dmis_fits_freely() -> None:
    assert fits_freely("dmis")
    assert not any(fits_freely(d) for d in ("fanuc", "haas", "linuxcnc", "nonesuch"))


@settings(max_examples=examples(60))
@given(st.lists(st.tuples(*[st.floats(-100.0, 100.0)] * 3), min_size=0, max_size=12),
       st.sampled_from(["circle", "cylinder", "cone", "sphere", "torus"]))
def test_any_points_give_a_verdict(points: list[tuple[float, float, float]],
                                   kind: str) -> None:
    """Random points end in "" or a sentence, never an exception."""
    assert isinstance(undetermined(kind, np.array(points, dtype=float), Z), str)


def test_a_torus_from_three_partial_sections_fits_from_the_nominal_axis() -> None:
    """Three partial rings of the inner half of a tube (NIST FTC 10's R41: tube r 1 mm
    seen by a 3 mm ball, rings over 90 deg): the start's centre is not pulled off the
    axis by the rings' different radii, the fit finds the torus (it used to end 29 deg
    off)."""
    major, tube = 13.5, 4.0
    pts = []
    for h in (0.8, 0.5, 0.2):
        rho = major - math.sqrt(tube * tube - (h * 4.0) ** 2)
        pts.append(ring(rho, h * 4.0, 8, arc=math.pi / 2, start=1.0))
    fit = fit_torus(np.vstack(pts) + np.array([-41.0, 40.3, 36.5]), Z, nearest=True)
    assert fit.major_radius == pytest.approx(major, abs=1e-6)
    assert fit.minor_radius == pytest.approx(tube, abs=1e-6)
    assert fit.centre == pytest.approx((-41.0, 40.3, 36.5), abs=1e-6)


def test_a_cone_with_one_reachable_section_is_left_out_not_written() -> None:
    """The planner refuses a cone whose touches lie in one section (the spec forces one),
    for DMIS and for Fanuc alike: probegen's evaluation of a Macro B log needs two
    sections of a cone as a CMM's free fit does (it would be NOT EVALUATED)."""
    from dataclasses import replace

    from probegen.errors import PlanningError
    from probegen.planning.revolved_plan import plan_revolved
    from probegen.spec.model import RevolvedSpec

    model = REPO / "samples/parts/counterbores.step"
    part = cad.load_part(model)
    from probegen.cad.revolved import revolved_features

    cone = next(f for f in revolved_features(part) if f.type == "cone" and f.accessible)
    spec = RevolvedSpec("C1", "test", "cone", cone.faces[0], None, (0.5 * cone.length,), 8,
                        None)
    machine = load_profile(REPO / "samples/machines/cmm.toml")
    why = r"cone: too few touches to evaluate it: \d touches in 1 sections \(at least 7 " \
        r"needed, in 2 sections\) \(the rest dropped by the collision check, e\.g\. touch " \
        r"\d+ dropped: its approach from .* of face \d+; expected a clearance of at least " \
        r"0\.150 mm\); give more points or sections"
    with pytest.raises(PlanningError, match=why):
        plan_revolved(spec, part, machine, 100.0)
    fanuc = replace(machine, dialect="fanuc", head=None, rack=())
    with pytest.raises(PlanningError, match=why):
        plan_revolved(spec, part, fanuc, 100.0)


@pytest.mark.skipif(not PARTS.is_dir(), reason="../shared/ref/parts is not there")
def test_a_real_part_cmm_program_runs_on_the_virtual_cmm(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """stretch_dw3_tablet_holder with the CMM sample to DMIS (``--all-revolved``): its cone
    R2 lost 7 of 8 touches to the collision check with the largest stylus and the
    virtual CMM refused the one-point cone; now every feature is well posed and the
    program runs with no alarm, every touch made."""
    from probegen.cli.app import main
    from probegen.dialects import get_dialect
    from probegen.planning import plan_program
    from probegen.planning.revolved_spec import all_revolved_spec

    model = PARTS / "stretch_dw3_tablet_holder.step"
    profile = REPO / "samples/machines/cmm.toml"
    part = cad.load_part(model)
    spec, _ = all_revolved_spec(part, load_profile(profile))
    planned = plan_program(spec, runtime_variables=False, part=part)
    cones = [p for p in planned.revolved if p.spec.kind == "cone"]
    assert cones and all(len({p.section for p in c.plan.path if p.normal is not None}) >= 2
                         for c in cones)
    program = tmp_path / "prog.dmi"
    program.write_text(get_dialect("dmis").generate(planned.program), encoding="ascii")
    assert main(["sim", str(program), "--part", str(model), "--machine", str(profile),
                 "-o", str(tmp_path / "out.log")]) == 0
    touches = sum(len(p.normals) for p in planned.revolved)
    assert f"({touches} touches)" in capsys.readouterr().err


def test_the_virtual_cmm_refuses_a_torus_in_two_tube_positions() -> None:
    """Sixteen points on two tube angles lie on a family of tori: the virtual CMM says
    so, as a CMM that fits freely must, instead of reporting one of them."""
    from test_dmis_torus import placed, torus_program

    from probegen.sim.cmm.interpreter import DmisProgramError, run_dmis

    lines = torus_program("OUTER").replace("MEAS/TORUS,F(RG),24",
                                           "MEAS/TORUS,F(RG),16").splitlines()
    start, end = lines.index("MEAS/TORUS,F(RG),16"), lines.index("ENDMES")
    block = lines[start + 1:end]
    last = [k for k, line in enumerate(block) if line.startswith("PTMEAS")][15]
    cut = lines[:start + 1] + block[:last + 1] + lines[end:]
    with pytest.raises(DmisProgramError, match=r"F\(RG\): 16 points in two sections: a "
                                               r"free torus fit needs three sections"):
        run_dmis("\n".join(cut) + "\n", placed("OUTER"))


def test_two_sections_of_a_degree_of_arc_fit_no_cone() -> None:
    """metalboop front plate R22: a cone in two sections, each six touches on one degree
    of arc, determined in theory; the free fit (condition 8e8) refuses it, so the
    planner does."""
    from probegen.geometry.determined import unfit

    half = math.radians(30.0)
    arcs = [ring(5.0 + h * math.tan(half), h, 6, arc=math.radians(1.0)) for h in (0.0, 1.0)]
    points = np.vstack(arcs)
    assert undetermined("cone", points, Z) == ""
    assert unfit("cone", points, Z) != ""  # ill-conditioned, or off the nominal axis
    wide = np.vstack([ring(5.0 + h * math.tan(half), h, 6, arc=math.pi) for h in (0.0, 1.0)])
    assert unfit("cone", wide, Z) == ""


@pytest.mark.parametrize(("degrees", "refused"), [(30.0, False), (0.3, True)])
def test_a_planned_free_fit_keeps_far_from_the_fits_limit(degrees: float,
                                                           refused: bool) -> None:
    """Exact touches on a 0.3 degree arc fit (condition about 2e6, under the fits' 1e8)
    but are refused for planning: rounded and scattered they would not."""
    from probegen.geometry.determined import PLANNED_CONDITION, unfit

    t = np.radians(np.linspace(0.0, degrees, 8))
    points = np.column_stack([20.0 * np.cos(t), 20.0 * np.sin(t), np.zeros_like(t)])
    why = unfit("circle", points, None)
    assert bool(why) is refused, why
    if refused:
        assert f"keeps below {PLANNED_CONDITION:.0e}" in why
