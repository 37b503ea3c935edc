"""Tests of probegen.cad: STEP loading, face records, face picking, tessellation.

Bad inputs have golden messages in ``tests/bad_inputs/step/<name>.err``; run with
``PROBEGEN_REGEN=1`` to rewrite them after a deliberate wording change.
"""

from __future__ import annotations

import difflib
import math
import os
import re
from pathlib import Path

import numpy as np
import pytest
from build123d import Align, Box, Cone, Cylinder, GeomType, Part, Pos, Sphere, export_step, fillet
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from probegen import cad
from probegen.errors import ModelError

ROOT = Path(__file__).resolve().parents[1]
REF = Path(__file__).resolve().parents[2] / "shared" / "ref"
REF_FILES = sorted([*REF.glob("nist-step/*.stp"), *REF.glob("nist-ippdme/*/STEP*/*.stp")])
SAMPLE = "samples/sphere25/sphere25.step"
BAD = "tests/bad_inputs/step"
BAD_NAMES = ["missing", "empty", "notstep", "truncated", "garbage_entities"]
REVOLVED = {"cylinder", "cone", "sphere", "torus"}
REGEN = os.environ.get("PROBEGEN_REGEN") == "1"
C, MIN, MAX = Align.CENTER, Align.MIN, Align.MAX


@pytest.fixture(autouse=True)
def at_repo_root(monkeypatch: pytest.MonkeyPatch) -> None:
    """Run every test from the repository root, so relative paths match the goldens."""
    monkeypatch.chdir(ROOT)


@pytest.fixture(scope="module")
def sphere25() -> cad.Model:
    return cad.load_step(ROOT / SAMPLE)


@pytest.fixture(scope="module")
def block(tmp_path_factory: pytest.TempPathFactory) -> cad.Model:
    """A block with a countersunk bore, a filleted boss and a spherical dimple."""
    path = tmp_path_factory.mktemp("block") / "block.step"
    export_step(_block_part(), path)
    return cad.load_step(path)


def _block_part() -> Part:
    part = Box(60, 60, 20, align=(C, C, MIN))
    part -= Pos(-15, 0, 0) * Cylinder(5, 20, align=(C, C, MIN))  # bore r5, z 0..20
    part -= Pos(-15, 0, 20) * Cone(5, 8, 3, align=(C, C, MAX))  # 45 degree countersink
    part -= Pos(0, 18, 20) * Sphere(4)  # dimple r4 centred on the top face
    part += Pos(15, 0, 20) * Cylinder(6, 10, align=(C, C, MIN))  # boss r6, z 20..30
    for z in (30, 20):  # convex fillet on the boss top, concave one at its foot
        part = fillet(_circles(part, 6.0, z), 1.0)
    return part


def _circles(part: Part, radius: float, z: float) -> list:
    return [
        e
        for e in part.edges()
        if e.geom_type == GeomType.CIRCLE
        and math.isclose(e.radius, radius)
        and math.isclose(e.center().Z, z)
    ]


def _only(model: cad.Model, kind: str, **attrs: object) -> cad.FaceRecord:
    found = [
        f
        for f in model.faces
        if f.type == kind and all(getattr(f, k) == v for k, v in attrs.items())
    ]
    assert len(found) == 1, f"{kind} {attrs}: {found}"
    return found[0]


# ------------------------------------------------------------------ reference models


def test_reference_models_are_present() -> None:
    assert len(REF_FILES) >= 14, f"reference STEP files missing under {REF}"


@pytest.mark.parametrize("path", REF_FILES, ids=lambda p: p.name)
def test_reference_model_faces(path: Path) -> None:
    model = cad.load_step(path)
    faces = model.faces
    assert len(faces) > 0
    assert [f.id for f in faces] == list(range(1, len(faces) + 1))
    kinds = [f.type for f in faces]
    assert set(kinds) <= set(cad.FACE_TYPES)
    assert kinds.count("other") == 0
    assert {"plane", "cylinder"} <= set(kinds)
    for f in faces:
        assert (f.inner is not None) == (f.type in REVOLVED), f
        assert math.isclose(math.hypot(*f.axis), 1.0, abs_tol=1e-12), f
        assert f.area > 0.0
        assert (f.radius is not None) == (f.type in REVOLVED)
        lo, hi = np.array(f.bbox_min) - 1e-6, np.array(f.bbox_max) + 1e-6
        assert np.all(lo <= f.centre) and np.all(f.centre <= hi), f
        assert np.all(np.array(model.bbox_min) <= lo + 2e-6)
        assert np.all(hi - 2e-6 <= np.array(model.bbox_max))
    table = cad.features_table(model)
    rows = table.splitlines()
    assert len(rows) == len(faces) + 1
    assert len({len(r) for r in rows}) == 1
    assert not re.search(r"-0\.0+\b|\de[-+]?\d|nan|inf", table)  # no -0, exponents


def test_inch_file_is_returned_in_millimetres() -> None:
    model = cad.load_step(REF / "nist-step" / "nist_ctc_03_asme1_rc.stp")  # INCH units
    inches = {round(f.radius / 25.4, 9) for f in model.faces if f.type == "cylinder"}
    assert {0.25, 0.3125, 0.375, 0.5, 0.75, 1.0} <= inches
    assert model.bbox_max[2] == pytest.approx(162.68015, abs=1e-5)


def test_ipp_simple_part() -> None:
    model = cad.load_step(REF / "nist-ippdme/IPlusSimplePart/STEP_Part21_AP203/ipp_simple.stp")
    assert [f.type for f in model.faces].count("plane") == 7
    bore = _only(model, "cylinder")
    assert bore.inner is True
    assert bore.radius == pytest.approx(25.0)
    assert abs(bore.axis[2]) == pytest.approx(1.0)
    floor = _only(model, "plane", area=pytest.approx(math.pi * 25.0**2))
    assert floor.axis == pytest.approx((0.0, 0.0, 1.0))  # out of the material, up the bore


def test_load_is_repeatable() -> None:
    path = REF / "nist-step" / "nist_ftc_10_asme1_rb.stp"
    first, second = cad.load_step(path), cad.load_step(path)
    assert first == second
    assert cad.features_table(first) == cad.features_table(second)


# ------------------------------------------------------------------- sample sphere25


def test_sample_sphere(sphere25: cad.Model) -> None:
    ball = _only(sphere25, "sphere")
    assert ball.radius == pytest.approx(12.5, abs=1e-9)
    assert ball.origin == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    assert ball.inner is False
    assert ball.axis == pytest.approx((0.0, 0.0, 1.0), abs=1e-9)  # the pole away from the stem
    stem = _only(sphere25, "cylinder", radius=pytest.approx(4.0))
    assert stem.inner is False
    base_top = _only(sphere25, "plane", origin=pytest.approx((0.0, 0.0, -60.0)))
    assert base_top.axis == pytest.approx((0.0, 0.0, 1.0))
    base_bottom = _only(sphere25, "plane", origin=pytest.approx((0.0, 0.0, -70.0)))
    assert base_bottom.axis == pytest.approx((0.0, 0.0, -1.0))
    assert sphere25.bbox_min == pytest.approx((-20.0, -20.0, -70.0))
    assert sphere25.bbox_max == pytest.approx((20.0, 20.0, 12.5))


def test_features_table_golden_rows(sphere25: cad.Model) -> None:
    rows = cad.features_table(sphere25).splitlines()
    assert rows[0].split() == [
        "id", "type", "side", "radius", "minor", "angle",
        "origin", "x", "y", "z", "axis", "x", "y", "z", "area",
    ]  # fmt: skip
    ball = _only(sphere25, "sphere")
    assert rows[ball.id].split() == [
        str(ball.id), "sphere", "outer", "12.5000", "-", "-",
        "0.0000", "0.0000", "0.0000", "0.000000", "0.000000", "1.000000", "1911.873",
    ]  # fmt: skip


def test_tessellate_sphere25(sphere25: cad.Model) -> None:
    mesh = cad.tessellate(sphere25, tolerance=0.01)
    joint = math.sqrt(12.5**2 - 4.0**2)  # -z where the stem enters the ball
    cap = math.pi * (12.5 - joint) ** 2 * (2 * 12.5 + joint) / 3  # ball cut off by the stem
    exact = 4 / 3 * math.pi * 12.5**3 - cap + math.pi * 16 * (60 - joint) + math.pi * 400 * 10
    assert mesh.is_watertight
    assert mesh.volume == pytest.approx(exact, rel=2e-3)  # positive: normals point out
    assert mesh.bounds[0] == pytest.approx(sphere25.bbox_min, abs=0.02)
    assert mesh.bounds[1] == pytest.approx(sphere25.bbox_max, abs=0.02)


BASE_PLATE = REF / "parts" / "metalboop_p0011_rev_e_base_plate.step"


@pytest.mark.skipif(not BASE_PLATE.exists(), reason="shared/ref/parts not present")
def test_tessellate_faces_occt_cannot_mesh() -> None:
    """OCCT's mesher fails on three countersink cones of the MetalBoop base plate (faces
    8, 147, 333: no triangulation); each is meshed on its parameter bounds, every face of
    the part has triangles, on the face and wound out of the material."""
    model = cad.load_step(BASE_PLATE)
    mesh = cad.tessellate(model, tolerance=0.01)
    ids = np.asarray(mesh.metadata["face_ids"])
    assert set(ids.tolist()) == {f.id for f in model.faces}
    part = cad.Part(model)
    for face in (8, 147, 333):
        record = model.faces[face - 1]
        assert record.type == "cone" and record.inner
        centres = mesh.triangles_center[ids == face]
        normals = mesh.face_normals[ids == face]
        area = float(mesh.area_faces[ids == face].sum())
        assert area == pytest.approx(record.area, rel=2e-3)
        assert max(part.exact.distance(face - 1, c)[0] for c in centres) < 0.01
        axis, origin = np.array(record.axis), np.array(record.origin)
        radial = (centres - origin) - np.outer((centres - origin) @ axis, axis)
        radial /= np.linalg.norm(radial, axis=1)[:, None]
        assert np.all(np.sum(normals * radial, axis=1) < -0.5)  # a bore: towards the axis


# ----------------------------------------------------------------- inner and outer


def test_block_inner_and_outer(block: cad.Model) -> None:
    bore = _only(block, "cylinder", radius=pytest.approx(5.0))
    assert bore.inner is True
    assert bore.origin == pytest.approx((-15.0, 0.0, 8.5))  # the bore ends under the sink
    boss = _only(block, "cylinder", radius=pytest.approx(6.0))
    assert boss.inner is False
    sink = _only(block, "cone")
    assert sink.inner is True
    assert sink.half_angle == pytest.approx(math.pi / 4)
    assert sink.axis == pytest.approx((0.0, 0.0, 1.0))  # the radius grows along the axis
    assert sink.radius == pytest.approx(5.0 + (sink.origin[2] - 17.0))
    dimple = _only(block, "sphere")
    assert (dimple.inner, dimple.radius) == (True, pytest.approx(4.0))
    assert dimple.axis == pytest.approx((0.0, 0.0, -1.0))
    assert _only(block, "torus", origin=pytest.approx((15.0, 0.0, 29.0))).inner is False
    assert _only(block, "torus", origin=pytest.approx((15.0, 0.0, 21.0))).inner is True


def test_block_plane_normals_point_out(block: cad.Model) -> None:
    planes = [f for f in block.faces if f.type == "plane"]
    for f in planes:
        inward = np.array(f.origin) - 1e-3 * np.array(f.axis)
        assert np.all(np.array(block.bbox_min) <= inward), f
        assert np.all(inward <= np.array(block.bbox_max)), f
    top = _only(block, "plane", origin=pytest.approx((15.0, 0.0, 30.0)))
    assert top.axis == pytest.approx((0.0, 0.0, 1.0))


# ------------------------------------------------------------------------ face picking


def test_face_at_picks_the_surface(block: cad.Model) -> None:
    bore = _only(block, "cylinder", radius=pytest.approx(5.0))
    assert cad.face_at(block, (-10.0, 0.0, 8.0)) == bore
    assert cad.face_at(block, (-10.2, 0.0, 8.0)) == bore  # 0.2 mm inside the bore
    top = cad.face_at(block, (-25.0, -25.0, 20.0))
    assert (top.type, top.axis) == ("plane", pytest.approx((0.0, 0.0, 1.0)))
    assert cad.face_at(block, (0.0, 18.0, 16.0)) == _only(block, "sphere")
    side = cad.face_at(block, (30.0, 0.0, 10.0))
    assert side.axis == pytest.approx((1.0, 0.0, 0.0))


def test_face_at_edge_goes_to_lower_id(block: cad.Model) -> None:
    x_side = _only(block, "plane", origin=pytest.approx((30.0, 0.0, 10.0)))
    y_side = _only(block, "plane", origin=pytest.approx((0.0, 30.0, 10.0)))
    corner = cad.face_at(block, (30.0, 30.0, 10.0))  # on the edge the two sides share
    assert corner.id == min(x_side.id, y_side.id)


def test_face_at_too_far(sphere25: cad.Model) -> None:
    with pytest.raises(ModelError) as err:
        cad.face_at(sphere25, (0.0, 0.0, 14.0))
    ball = _only(sphere25, "sphere")
    assert str(err.value) == (
        f"{sphere25.path}: no face within 0.5000 mm of (0.0000, 0.0000, 14.0000): "
        f"the nearest is face {ball.id} at 1.5000 mm"
    )
    assert cad.face_at(sphere25, (0.0, 0.0, 14.0), max_distance=2.0) == ball


def test_face_by_id(sphere25: cad.Model) -> None:
    assert cad.face_by_id(sphere25, 1) == sphere25.faces[0]
    count = len(sphere25.faces)
    for bad in (0, count + 1, -1):
        with pytest.raises(ModelError, match=f"expected a face id from 1 to {count}"):
            cad.face_by_id(sphere25, bad)


# -------------------------------------------------------------------------- bad input


@pytest.mark.parametrize("name", BAD_NAMES)
def test_bad_step_golden(name: str, capfd: pytest.CaptureFixture[str]) -> None:
    path = f"{BAD}/{name}.step"
    assert (name == "missing") != Path(path).exists()
    with pytest.raises(ModelError) as err:
        cad.load_step(path)
    got = str(err.value) + "\n"
    golden = Path(f"{BAD}/{name}.err")
    if REGEN:
        golden.write_text(got, encoding="utf-8")
    want = golden.read_text(encoding="utf-8")
    diff = difflib.unified_diff(want.splitlines(True), got.splitlines(True), "golden", "got")
    assert got == want, "".join(diff)
    assert got.startswith(f"{path}: ")
    assert capfd.readouterr().out == ""  # OCCT's own chatter stays off stdout


def test_directory_is_not_a_step_file() -> None:
    with pytest.raises(ModelError, match=r"^tests: expected a STEP file, found a folder$"):
        cad.load_step("tests")


def test_step_crashing_occt_is_a_model_error(tmp_path: Path) -> None:
    """A 2-D CARTESIAN_POINT used as a 3-D vertex kills OCCT's transfer outright."""
    text = (ROOT / SAMPLE).read_text()
    good = "#57 = CARTESIAN_POINT('',(20.,-4.898587196589E-15,-70.));"
    assert good in text
    path = tmp_path / "crash.step"
    path.write_text(text.replace(good, "#57 = CARTESIAN_POINT('',(20.,-4.89858719650.));"))
    with pytest.raises(ModelError, match="crashed|OCCT raised|corrupt"):
        cad.load_step(path)


# ------------------------------------------------------------------------- robustness

_FUZZ = settings(max_examples=examples(30), suppress_health_check=[HealthCheck.too_slow])


def _load_or_model_error(tmp_path: Path, data: bytes) -> None:
    path = tmp_path / "fuzz.step"
    path.write_bytes(data)
    try:
        model = cad.load_step(path)
    except ModelError as exc:
        assert str(exc).startswith(f"{path}: ")
        return
    assert model.faces
    cad.features_table(model)


@_FUZZ
@given(data=st.binary(max_size=4000), wrap=st.booleans())
def test_random_bytes(tmp_path_factory: pytest.TempPathFactory, data: bytes, wrap: bool) -> None:
    if wrap:  # pass the header checks so that OCCT itself sees the bytes
        data = b"ISO-10303-21;\nHEADER;\n" + data + b"\nEND-ISO-10303-21;\n"
    _load_or_model_error(tmp_path_factory.mktemp("fuzz"), data)


@st.composite
def _mutated(draw: st.DrawFn) -> bytes:
    src = (ROOT / SAMPLE).read_bytes()
    start = draw(st.integers(0, len(src) - 1))
    span = draw(st.sampled_from([1, 16, 400, 4000]))
    stop = draw(st.integers(start, min(len(src), start + span)))
    how = draw(st.sampled_from(["slice", "delete", "overwrite", "repeat"]))
    if how == "slice":
        return src[start:stop]
    if how == "delete":
        return src[:start] + src[stop:]
    if how == "overwrite":
        noise = draw(st.binary(min_size=stop - start, max_size=stop - start))
        return src[:start] + noise + src[stop:]
    return src[:start] + src[start:stop] * 2 + src[stop:]


@_FUZZ
@given(data=_mutated())
def test_mutated_step(tmp_path_factory: pytest.TempPathFactory, data: bytes) -> None:
    _load_or_model_error(tmp_path_factory.mktemp("fuzz"), data)
