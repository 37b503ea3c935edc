"""Free-form faces (method M3): guide points, the face as a ParamSurface, spec, plan, IR."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, sample_script

from probegen import cad, ir
from probegen.cad.freeform import FaceMesh, FaceSurface, boundary_samples, guide_points, is_freeform
from probegen.cli.app import main
from probegen.dialects import get_dialect
from probegen.planning import make_setup, part_of, plan_program
from probegen.planning.freeform_spec import FreeformPlan, plan_freeform
from probegen.spec.model import FreeformSpec, Spec, load_spec

STEP = REPO / "samples/freeform/freeform.step"
SPEC = Path("samples/freeform/freeform.toml")
TOP = 6  # the B-spline top face
BORE = np.array([44.0, 20.0])
R = 3.0


@pytest.fixture(scope="module")
def model() -> cad.Model:
    return cad.load_step(STEP)


def _spec(**changes: object) -> Spec:
    spec = load_spec(REPO / SPEC)
    f = dataclasses.replace(spec.features[0], **changes)  # type: ignore[arg-type]
    return dataclasses.replace(spec, features=(f,))


# ---------------------------------------------------------------------------- cad


def test_faces_are_classified(model: cad.Model) -> None:
    assert [f.id for f in model.faces if is_freeform(f)] == [TOP]


@pytest.mark.parametrize("grid", ["uv", "xy"])
def test_guide_points_keep_the_margin_from_every_edge_and_the_hole(model: cad.Model,
                                                                   grid: str) -> None:
    margin = 3.0
    g = guide_points(model, TOP, grid=grid, spacing=4.0, margin=margin)
    assert len(g.points) > 40
    fine = boundary_samples(model, TOP, step=0.002)
    pts = np.array([p.point for p in g.points])
    gaps = np.linalg.norm(pts[:, None, :] - fine[None, :, :], axis=2).min(axis=1)
    assert gaps.min() >= margin - 1e-6
    assert np.linalg.norm(pts[:, :2] - BORE, axis=1).min() > 4.0 + margin * 0.9
    surface = FaceSurface(model, TOP)
    assert surface.inside(np.array([p.uv for p in g.points])).all()
    assert g.skipped and all("margin" in s.reason or "outside" in s.reason
                             or "misses" in s.reason for s in g.skipped)
    assert [p.index for p in g.points] == list(range(1, len(g.points) + 1))


def test_xy_grid_points_lie_on_their_grid_lines(model: cad.Model) -> None:
    g = guide_points(model, TOP, grid="xy", counts=(5, 4), margin=2.0)
    pts = np.array([p.point for p in g.points])
    xs, ys = np.unique(pts[:, 0].round(9)), np.unique(pts[:, 1].round(9))
    assert len(xs) == 5 and len(ys) == 4
    surface = FaceSurface(model, TOP)
    assert np.abs(surface.point(np.array([p.uv for p in g.points])) - pts).max() < 1e-9


def test_face_surface_numpy_spline_matches_occt(model: cad.Model) -> None:
    surface = FaceSurface(model, TOP)
    assert surface.spline is not None and surface.normal_sign == -1.0
    (u0, u1), (v0, v1) = surface.domain
    u, v = np.linspace(u0, u1, 9), np.linspace(v1, v0, 9)
    fast = surface.derivatives(u, v)
    surface.spline = None
    slow = surface.derivatives(u, v)
    for name in ("point", "su", "sv", "suu", "suv", "svv"):
        assert np.abs(getattr(fast, name) - getattr(slow, name)).max() < 1e-9
    normals = surface.normal(np.column_stack([u, v]))
    assert (normals[:, 2] > 0.8).all()  # outward = up for the top face


def test_plane_face_is_a_param_surface_too(model: cad.Model) -> None:
    bottom = FaceSurface(model, 2)
    assert bottom.spline is None
    (u0, u1), (v0, v1) = bottom.domain
    n = bottom.normal(np.array([[(u0 + u1) / 2, (v0 + v1) / 2]]))
    assert np.allclose(n, [[0.0, 0.0, -1.0]])


def test_mesh_seeds_are_close_to_the_exact_parameters(model: cad.Model) -> None:
    mesh = FaceMesh(model, TOP)
    surface = FaceSurface(model, TOP)
    g = guide_points(model, TOP, counts=(4, 4), margin=3.0)
    uv = np.array([p.uv for p in g.points])
    assert np.abs(mesh.nearest_uv(surface.point(uv)) - uv).max() < 1e-3
    hit, seeds = mesh.cast(surface.point(uv) + [0.0, 0.0, 5.0], np.array([0.0, 0.0, -1.0]))
    assert hit.all() and np.abs(seeds - uv).max() < 1e-3


# --------------------------------------------------------------------------- spec


def test_sample_spec_loads() -> None:
    f = load_spec(REPO / SPEC).features[0]
    assert isinstance(f, FreeformSpec)
    assert (f.face, f.grid, f.counts, f.method, f.margin) == (TOP, "uv", (4, 3), "vector", 4.0)
    assert f.direction == (0.0, 0.0, 1.0) and f.extra_spacing == 0.5
    assert f.deviation == (-0.05, 0.05)


def test_inch_spec_is_scaled(tmp_path: Path) -> None:
    text = (REPO / SPEC).read_text().replace('units = "mm"', 'units = "inch"').replace(
        'model = "freeform.step"', f'model = "{STEP}"').replace(
        '"../machines/vmc-fanuc.toml"', f'"{REPO / "samples/machines/vmc-fanuc.toml"}"')
    text = text.replace("margin = 4.0 ", "margin = 0.1 ").replace(
        'method = "vector"', 'method = "microplane"\nextra_spacing = 0.01')
    path = tmp_path / "inch.toml"
    path.write_text(text)
    f = load_spec(path).features[0]
    assert isinstance(f, FreeformSpec)
    assert f.margin == pytest.approx(2.54) and f.extra_spacing == pytest.approx(0.254)


# --------------------------------------------------------------------------- plan


def _plan(**changes: object) -> FreeformPlan:
    spec = _spec(**changes)
    f = spec.features[0]
    assert isinstance(f, FreeformSpec)
    return plan_freeform(f, part_of(spec), spec.machine, make_setup(spec))


def test_vector_touches_run_along_the_nominal_normal(in_repo: Path) -> None:
    p = _plan()
    guides = {g[0]: np.array(g[1]) for g in p.guides}
    for t in p.touches:
        o, c, n = np.array(t.centre), np.array(t.contact), np.array(t.normal)
        assert np.allclose(o[:2], guides[t.guide][:2], atol=1e-9)  # on the vertical line
        assert np.allclose(o - c, R * n, atol=1e-9)                 # r off along n
        assert t.direction == t.normal and t.index == 10 * t.guide
        node = t.node("SURF", R, 2.0, 2.0)
        assert node.contact == t.contact and node.surface is None


def test_vertical2d_touches_and_extra_lines(in_repo: Path) -> None:
    p = _plan(method="vertical2d")
    by_guide: dict[int, list] = {}
    for t in p.touches:
        by_guide.setdefault(t.guide, []).append(t)
    for g, (main_touch, a, b) in by_guide.items():
        assert [t.index for t in (main_touch, a, b)] == [10 * g, 10 * g + 1, 10 * g + 2]
        centre = np.array(main_touch.centre)[:2]
        for extra in (a, b):
            assert np.linalg.norm(np.array(extra.centre)[:2] - centre) == pytest.approx(0.5)
        node = main_touch.node("SURF", R, 2.0, 2.0)
        assert node.normal == (0.0, 0.0, 1.0) and node.surface == main_touch.normal
        assert np.allclose(np.add(node.contact, (0.0, 0.0, R)), main_touch.centre)


def test_microplane_has_three_extra_touches_on_a_circle(in_repo: Path) -> None:
    p = _plan(method="microplane", extra_spacing=0.2)
    roles = [t.role for t in p.touches]
    assert roles == [0, 1, 2, 3] * (len(roles) // 4)
    mains = {t.guide: np.array(t.centre) for t in p.touches if t.role == 0}
    for t in p.touches:
        if t.role:
            assert np.linalg.norm(np.array(t.centre)[:2] - mains[t.guide][:2]) == \
                pytest.approx(0.2)


def test_program_is_checked_and_emitted_in_every_dialect(in_repo: Path) -> None:
    spec = _spec(method="vertical2d")
    planned = plan_program(spec, runtime_variables=False)
    assert planned.clearance.minimum >= 0.0
    block = next(n for n in planned.program.body if isinstance(n, ir.FeatureBlock))
    assert isinstance(block.feature, ir.FreeformDef) and block.feature.method == "vertical2d"
    touches = len(planned.freeform[0].touches)
    dmis = get_dialect("dmis").generate(planned.program)
    assert dmis.count("=FEAT/POINT,CART,") == dmis.count("PTMEAS/CART,") == touches
    assert "MEAS/POINT,F(SURF_10),1" in dmis and "OUTPUT/FA(SURF_12)" in dmis
    for name in ("fanuc", "linuxcnc", "haas"):
        text = get_dialect(name).generate(plan_program(spec, runtime_variables=True).program)
        assert "FEATURE SURF FREEFORM FACE 6 VERTICAL2D" in text


def _roofed_model(tmp_path: Path) -> Path:
    """The sample part with a slab hanging 4 mm above the surface's low end (x < 12)."""
    from build123d import Align, Box, Compound, Pos, export_step

    module = sample_script("freeform")
    roof = Pos(-5.0, -5.0, 26.0) * Box(17.0, 50.0, 3.0, align=(Align.MIN,) * 3)
    target = tmp_path / "roofed.step"
    export_step(Compound([module.make_part(), roof]), target)
    return target


def test_unreachable_points_are_reported_with_the_obstacle(tmp_path: Path) -> None:
    step = _roofed_model(tmp_path)
    spec = _spec(counts=(6, 3), margin=3.0)
    spec = dataclasses.replace(spec, model=step)
    f = spec.features[0]
    assert isinstance(f, FreeformSpec)
    p = plan_freeform(f, part_of(spec), spec.machine, make_setup(spec))
    under = [x for x in p.left_out if x.guide and x.point[0] < 12.0]
    assert under and all("unreachable from above" in x.reason and "face" in x.reason
                         for x in under)
    assert all(g[1][0] > 12.0 for g in p.guides)
    planned = plan_program(spec, runtime_variables=True)
    assert planned.clearance.minimum >= 0.0


def test_cli_plan_and_compile(in_repo: Path, tmp_path: Path,
                              capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", "samples/freeform/freeform_2d.toml"]) == 0
    out = capsys.readouterr().out
    assert "SURF: free-form face 6, method vertical2d" in out
    assert "left out: grid point" in out and "the grid line misses the face" in out
    assert main(["compile", str(SPEC), "-o", str(tmp_path)]) == 0
    text = (tmp_path / "freeform.nc").read_text()  # compact: one library call per touch
    assert "DPRNT[FEAT*SURF*1]" in text and "G31" not in text
    assert text.count("G65P8001") + text.count("G65P8002") == 8
