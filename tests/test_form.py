"""Planted form errors on the virtual machine (``sim.form``): the contact model and the
form file.

The local-radius model puts the ball centre exactly ``r`` off the face of radius
``radius + δ`` with ``δ`` taken at the contact's own foot point; these tests check that
to 1e-9 mm on a cylinder (bore_block's bore), a cone and a sphere (revolved_block), and
that the form file reader ends every input in a result or a ``SpecError``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate

from probegen import cad
from probegen.errors import ProbegenError, SpecError
from probegen.sim.contact import PlacedPart
from probegen.sim.form import FormError, Lobe, load_forms

R = 3.0
EXACT = 1e-9


@pytest.fixture(scope="module")
def bore_block() -> cad.Model:
    return cad.load_step(REPO / "samples/bore_block/bore_block.step")


@pytest.fixture(scope="module")
def revolved_block() -> cad.Model:
    return cad.load_step(REPO / "samples/revolved_block/revolved_block.step")


def test_bore_contact_follows_the_planted_radius(bore_block: cad.Model) -> None:
    form = FormError(8, offset=0.003, taper=2e-4, lobes=(Lobe(3, 0.004, 0.5), Lobe(5, 0.001)),
                     custom=lambda theta, h: 0.0005 * math.sin(theta) * h / 50.0)
    part = PlacedPart.from_model(bore_block, translation=(0.3, -0.2, 0.0), forms=(form,))
    for theta in np.linspace(0.0, 2 * math.pi, 11)[:-1]:
        for z in (5.0, 25.0, 45.0):
            e = np.array([math.cos(theta), math.sin(theta), 0.0])
            start = np.array([50.3, 49.8, z]) + 15.0 * e
            hit = part.first_contact(start, start + 10.0 * e, R)
            assert hit is not None and hit.face_id == 8
            rel = hit.centre - np.array([50.3, 49.8, 0.0])
            foot = math.atan2(rel[1], rel[0])
            want = 25.0 + form.delta(foot, z) - R
            assert math.hypot(rel[0], rel[1]) == pytest.approx(want, abs=EXACT)
            assert abs(part.clearance(hit.centre, R)) < EXACT
            assert part.clearance(hit.centre - 1e-4 * e, R) > 0.0  # clear, back off
            assert part.clearance(hit.centre + 1e-4 * e, R) < 0.0  # in the material


def test_cone_and_sphere_contacts(revolved_block: cad.Model) -> None:
    cone = FormError(7, offset=-0.002, lobes=(Lobe(2, 0.003, 1.0),))
    dome = FormError(8, offset=0.005, lobes=(Lobe(4, 0.002),))
    part = PlacedPart.from_model(revolved_block, forms=(cone, dome))
    alpha = math.atan(0.2)
    for theta in np.linspace(0.0, 2 * math.pi, 7)[:-1]:
        e = np.array([math.cos(theta), math.sin(theta), 0.0])
        n = math.cos(alpha) * e + np.array([0.0, 0.0, math.sin(alpha)])
        foot = np.array([25.0, 75.0, 40.0]) + 10.0 * e  # the cone at z = 40: radius 10
        hit = part.first_contact(foot + 6.0 * n, foot, R)
        assert hit is not None and hit.face_id == 7
        # the section radius at the foot's height grows by δ; the ball is r off the cone
        rel = hit.point - np.array([25.0, 75.0, 0.0])
        radius = 12.0 - 0.2 * (rel[2] - 30.0) + cone.delta(math.atan2(rel[1], rel[0]), 0.0)
        assert math.hypot(rel[0], rel[1]) == pytest.approx(radius, abs=EXACT)
        u = np.array([math.cos(theta) * 0.8, math.sin(theta) * 0.8, 0.6])
        centre = np.array([75.0, 75.0, 30.0])
        hit = part.first_contact(centre + 25.0 * u, centre + 10.0 * u, R)
        assert hit is not None and hit.face_id == 8
        rel = hit.point - centre
        h = float(rel[2])  # the sphere's h runs from its centre
        want = 15.0 + dome.delta(math.atan2(rel[1], rel[0]), h)
        assert float(np.linalg.norm(hit.centre - centre)) == pytest.approx(want + R, abs=EXACT)


def test_uniform_offset_is_a_larger_bore(bore_block: cad.Model) -> None:
    part = PlacedPart.from_model(bore_block, forms=(FormError(8, offset=0.01),))
    hit = part.first_contact((50.0, 50.0, 20.0), (80.0, 50.0, 20.0), R)
    assert hit is not None and hit.centre[0] == pytest.approx(50.0 + 25.01 - R, abs=1e-12)


def test_bad_forms(bore_block: cad.Model) -> None:
    with pytest.raises(ProbegenError, match="type cylinder, cone, sphere, torus, found plane"):
        PlacedPart.from_model(bore_block, forms=(FormError(3, offset=0.01),))
    with pytest.raises(ProbegenError, match="limit in"):
        PlacedPart.from_model(bore_block, forms=(FormError(8, limit=1.0),))
    part = PlacedPart.from_model(bore_block, forms=(FormError(8, taper=0.01, limit=0.2),))
    with pytest.raises(ProbegenError, match=r"\|δ\| <= 0.2 mm"):
        part.first_contact((50.0, 50.0, 40.0), (80.0, 50.0, 40.0), R)  # δ = 0.4 there


GOOD = """\
[[form]]
face = 8
offset = 0.003
taper = 0.0002
lobes = [[3, 0.004, 30.0], [5, 0.001, 0]]
limit = 0.05

[[form]]
face = 7
offset = -0.002
"""


def test_load_forms(tmp_path: Path) -> None:
    path = tmp_path / "forms.toml"
    path.write_text(GOOD)
    bore, boss = load_forms(path)
    assert bore == FormError(8, 0.003, 0.0002, (Lobe(3, 0.004, math.radians(30.0)),
                                                 Lobe(5, 0.001, 0.0)), None, 0.05)
    assert boss.face == 7 and boss.offset == -0.002 and boss.limit == 0.1


@pytest.mark.parametrize("text, message", [
    ("", "at least one \\[\\[form\\]\\]"),
    ("[[form]]\noffset = 1e-3\n", "form\\[0\\].face: required key"),
    ("[[form]]\nface = 8\nlobes = [[0, 0.1, 0]]\n", "form\\[0\\].lobes: expected"),
    ("[[form]]\nface = 8\nlimit = 0.5\n", "form\\[0\\].limit: expected a number <= 0.4"),
    ("[[form]]\nface = 8\ntaper = 'x'\n", "form\\[0\\].taper: expected a number"),
    ("[[form]]\nface = 8\n[[form]]\nface = 8\n", "each face once"),
    ("[[form]]\nface = 8\nofset = 1\n", "form\\[0\\].ofset: unknown key"),
])
def test_bad_form_files(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "forms.toml"
    path.write_text(text)
    with pytest.raises(SpecError, match=message):
        load_forms(path)


@settings(max_examples=examples(150),
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.data())
def test_mutated_form_files(tmp_path: Path, data: st.DataObject) -> None:
    text = data.draw(st.composite(lambda draw: mutate(draw, GOOD, '[]=,."-0123456789 \nfe'))())
    path = tmp_path / "forms.toml"
    path.write_text(text, encoding="utf-8")
    try:
        forms = load_forms(path)
    except ProbegenError:
        return
    assert all(f.face >= 1 and 0.0 < f.limit <= 0.4 for f in forms)


def test_cli_sim_with_forms(in_repo: Path, tmp_path: Path) -> None:
    from probegen.cli.app import main

    forms = tmp_path / "forms.toml"
    forms.write_text("[[form]]\nface = 8\noffset = 0.01\n")
    assert main(["compile", "samples/bore_block/bore_block.toml", "-o", str(tmp_path)]) == 0
    program = next(tmp_path.glob("*.nc"))
    out = tmp_path / "run.log"
    assert main(["sim", str(program), "--spec", "samples/bore_block/bore_block.toml",
                 "--form", str(forms), "-o", str(out)]) == 0
    from probegen.evaluate.ingest import ingest
    from probegen.spec.model import load_spec

    bore = ingest(out, load_spec("samples/bore_block/bore_block.toml")).revolved[0]
    assert bore.diameter == pytest.approx(50.02, abs=1e-4)


def test_cli_form_needs_a_model(in_repo: Path, tmp_path: Path,
                                capsys: pytest.CaptureFixture[str]) -> None:
    from probegen.cli.app import main

    forms = tmp_path / "forms.toml"
    forms.write_text("[[form]]\nface = 1\noffset = 0.01\n")
    program = tmp_path / "p.nc"
    program.write_text("%\nO1\nM30\n%\n")
    spec = tmp_path / "spheres.toml"  # analytic spheres, no model
    spec.write_text(f'[machine]\nprofile = "{in_repo / "samples/machines/vmc-fanuc.toml"}"\n'
                    '[[feature]]\nid = "S"\nkind = "sphere_test"\ncentre = [0, 0, 0]\n'
                    'diameter = 25.0\n')
    code = main(["sim", str(program), "--spec", str(spec), "--form", str(forms),
                 "-o", str(tmp_path / "out.log")])
    assert code != 0
    assert "expected a part model" in capsys.readouterr().err


@settings(max_examples=examples(25),
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(offset=st.floats(-0.02, 0.02), taper=st.floats(-5e-4, 5e-4),
       k=st.integers(1, 12), amplitude=st.floats(0.0, 0.01), phase=st.floats(0.0, 6.3),
       theta=st.floats(0.0, 6.28), z=st.floats(5.0, 45.0), tilt=st.floats(-0.5, 0.5))
def test_any_small_form_touches_consistently(bore_block: cad.Model, offset: float,
                                             taper: float, k: int, amplitude: float,
                                             phase: float, theta: float, z: float,
                                             tilt: float) -> None:
    """Random forms and approach directions (up to 0.5 rad off square): the ball stops
    touching (clearance 0) at ``R + δ(foot) − r`` from the axis."""
    form = FormError(8, offset, taper, (Lobe(k, amplitude, phase),))
    part = PlacedPart.from_model(bore_block, forms=(form,))
    e = np.array([math.cos(theta + tilt), math.sin(theta + tilt), 0.0])
    start = np.array([50.0, 50.0, z]) + 10.0 * np.array([math.cos(theta), math.sin(theta), 0])
    hit = part.first_contact(start, start + 20.0 * e, R)
    assert hit is not None and hit.face_id == 8
    rel = hit.point - np.array([50.0, 50.0, 0.0])
    want = 25.0 + form.delta(math.atan2(rel[1], rel[0]), float(rel[2]))
    assert math.hypot(rel[0], rel[1]) == pytest.approx(want, abs=EXACT)
    assert abs(part.clearance(hit.centre, R)) < EXACT
