"""The kinematic chains, the error model and the probe model against hand-derived truth."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from probegen.errors import ProbegenError, SpecError
from probegen.machine.errors_model import AxisErrors, ErrorModel, RotaryErrors, load_errors
from probegen.machine.kinematics import Machine, Topology, load_machine
from probegen.machine.probe_model import Lobing, ProbeModel

TOOL = np.array([12.0, -7.0, -150.0])
BC = Topology.FIVE_AXIS_BC


def _points(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform([0.0, 0.0, -500.0], [800.0, 500.0, 0.0], size=(n, 3))


def _one_term(axis: str, linear: dict[int, list[float]] | None = None,
              angular: dict[int, list[float]] | None = None) -> ErrorModel:
    """An error model with only the given rows (component -> coefficients) on ``axis``."""
    lin, ang = np.zeros((3, 2)), np.zeros((3, 2))
    for row, c in (linear or {}).items():
        lin[row] = c
    for row, c in (angular or {}).items():
        ang[row] = c
    return ErrorModel(**{axis.lower(): AxisErrors(lin, ang)})  # type: ignore[arg-type]


def _random_model(length: float, angle: float, seed: int = 3) -> ErrorModel:
    rng = np.random.default_rng(seed)

    def axis() -> AxisErrors:
        return AxisErrors(rng.normal(size=(3, 3)) * length, rng.normal(size=(3, 3)) * angle)

    s = rng.normal(size=3) * angle
    return ErrorModel(axis(), axis(), axis(), float(s[0]), float(s[1]), float(s[2]))


def _first_order(e: ErrorModel, q: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The VMC's volumetric error to first order, written out term by term.

    Chain W-X-Y-Z-T: X turns y, z and the tool offset; Y turns z and the offset; Z turns
    the offset; squareness adds S_xy·y + S_xz·z to x and S_yz·z to y.
    """
    x, y, z = q.T
    (dxx, dyx, dzx), (exx, eyx, ezx) = (v.T for v in e.x.evaluate(x, e.scale))
    (dxy, dyy, dzy), (exy, eyy, ezy) = (v.T for v in e.y.evaluate(y, e.scale))
    (dxz, dyz, dzz), (exz, eyz, ezz) = (v.T for v in e.z.evaluate(z, e.scale))
    tx, ty, tz = t
    ex = (dxx + dxy + dxz + eyx * (z + tz) - ezx * (y + ty) + eyy * (z + tz) - ezy * ty
          + eyz * tz - ezz * ty + e.sxy * y + e.sxz * z)
    ey = (dyx + dyy + dyz + ezx * tx - exx * (z + tz) + ezy * tx - exy * (z + tz)
          + ezz * tx - exz * tz + e.syz * z)
    ez = (dzx + dzy + dzz + exx * (y + ty) - eyx * tx + exy * ty - eyy * tx
          + exz * ty - eyz * tx)
    return np.column_stack([ex, ey, ez])


# ------------------------------------------------------------------------ 3-axis


def test_zero_errors_are_the_identity() -> None:
    q = _points(50)
    m = Machine()
    assert np.array_equal(m.actual_tool_point(q, TOOL), m.nominal_tool_point(q, TOOL))
    np.testing.assert_allclose(m.nominal_tool_point(q, TOOL), q + TOOL, rtol=0, atol=1e-12)
    assert np.array_equal(m.tool_transforms(q)[:, :3, :3], np.broadcast_to(np.eye(3),
                                                                          (50, 3, 3)))


def test_pure_positioning_error_is_only_along_its_axis() -> None:
    e = _one_term("Y", linear={1: [0.002, 0.006]})  # δyy = 2 µm + 6 µm per metre
    q = _points(30)
    err = Machine(errors=e).volumetric_error(q, TOOL)
    np.testing.assert_allclose(err[:, 1], 0.002 + 0.006 * q[:, 1] / 1000.0, atol=1e-12)
    assert np.all(err[:, [0, 2]] == 0.0)


def test_squareness_xy_moves_x_by_sxy_times_y() -> None:
    # Sign: positive S_xy means Y runs along (S_xy, 1, 0), an angle below 90° to +X.
    q = _points(30)
    err = Machine(errors=ErrorModel(sxy=25e-6)).volumetric_error(q, TOOL)
    np.testing.assert_allclose(err[:, 0], 25e-6 * q[:, 1], atol=1e-12)
    np.testing.assert_allclose(err[:, 1:], 0.0, atol=1e-12)


def test_roll_at_a_lever_arm_gives_the_abbe_offset() -> None:
    roll = 20e-6  # εxx, rad, constant
    m = Machine(errors=_one_term("X", angular={0: [roll, 0.0]}))
    length = 150.0
    # tool hanging 150 mm below the gauge point: y moves by -εxx·(z + t_z) = +3 µm
    err = m.volumetric_error([300.0, 0.0, 0.0], [0.0, 0.0, -length])
    assert err[1] == pytest.approx(roll * length, rel=1e-6)
    # exactly: the arm turns by εxx, so z rises by L·(1 - cos εxx), second order
    np.testing.assert_allclose(err, [0.0, length * math.sin(roll),
                                     length * (1 - math.cos(roll))], rtol=0, atol=1e-13)
    # 200 mm out along Y, the roll lifts the tool point by εxx·y
    err = m.volumetric_error([300.0, 200.0, 0.0], [0.0, 0.0, 0.0])
    assert err[2] == pytest.approx(roll * 200.0, rel=1e-6)


def test_yaw_of_x_shows_as_minus_yaw_times_y() -> None:
    yaw = 8e-6
    m = Machine(errors=_one_term("X", angular={2: [yaw, 0.0]}))
    near, far = m.volumetric_error([[400.0, 50.0, 0.0], [400.0, 450.0, 0.0]], np.zeros(3))
    assert far[0] - near[0] == pytest.approx(-yaw * 400.0, rel=1e-6)


def test_full_transforms_match_the_first_order_formula() -> None:
    q = _points(25, seed=7)
    e = _random_model(1e-4, 1e-7)  # 0.1 µm and 0.1 µrad per coefficient
    err = Machine(errors=e).volumetric_error(q, TOOL)
    rel = np.linalg.norm(err - _first_order(e, q, TOOL), axis=1) / np.linalg.norm(err, axis=1)
    assert rel.max() < 1e-6
    # the remainder is second order: ten times the errors, a hundred times the remainder
    big = _random_model(1e-3, 1e-6)
    rest = Machine(errors=big).volumetric_error(q, TOOL) - _first_order(big, q, TOOL)
    small = _random_model(1e-4, 1e-7)
    rest_small = Machine(errors=small).volumetric_error(q, TOOL) - _first_order(small, q, TOOL)
    ratio = np.linalg.norm(rest, axis=1) / np.linalg.norm(rest_small, axis=1)
    np.testing.assert_allclose(ratio, 100.0, rtol=0.01)


def test_batch_equals_one_by_one_and_a_mapping() -> None:
    m = load_machine(REPO / "samples/machines/errors-example.toml")
    q = _points(10, seed=2)
    batch = m.actual_tool_point(q, TOOL)
    for row, expected in zip(q, batch, strict=True):
        np.testing.assert_array_equal(m.actual_tool_point(row, TOOL), expected)
    mapped = m.actual_tool_point({"X": q[:, 0], "Y": q[:, 1], "Z": q[:, 2]}, TOOL)
    np.testing.assert_array_equal(mapped, batch)
    assert m.actual_tool_point({"X": 1.0, "Y": 2.0, "Z": -3.0}, TOOL).shape == (3,)


def test_sample_errors_are_micrometre_level() -> None:
    m = load_machine(REPO / "samples/machines/errors-example.toml")
    err = m.volumetric_error(_points(200, seed=5), TOOL)
    size = np.linalg.norm(err, axis=1)
    assert 1e-3 < size.max() < 0.05


# ---------------------------------------------------------------------- 5-axis


def test_five_axis_nominal_chain() -> None:
    m = Machine(BC)
    rng = np.random.default_rng(1)
    q = np.column_stack([_points(20), rng.uniform(-1.5, 1.5, (20, 2))])
    p = m.nominal_tool_point(q, TOOL)
    b, c = q[:, 3], q[:, 4]
    tool = np.column_stack([TOOL[0] * np.cos(b) + TOOL[2] * np.sin(b), np.full(20, TOOL[1]),
                            -TOOL[0] * np.sin(b) + TOOL[2] * np.cos(b)])
    m_pt = q[:, :3] + tool
    expected = np.column_stack([m_pt[:, 0] * np.cos(c) - m_pt[:, 1] * np.sin(c),
                                m_pt[:, 0] * np.sin(c) + m_pt[:, 1] * np.cos(c), m_pt[:, 2]])
    np.testing.assert_allclose(p, expected, atol=1e-10)
    np.testing.assert_allclose(m.nominal_axes(p, TOOL, b=b, c=c), q, atol=1e-10)
    assert np.array_equal(Machine(BC, ErrorModel.zero()).actual_tool_point(q, TOOL), p)


def test_m4_installation_offset_closes_the_loop() -> None:
    # Seed 001: ball radius R1 at l1 from the B axis, workpiece radius r on the C axis.
    delta, l1, big_r, r1, r2 = 0.0123, 150.0, 3.0, 20.0, 20.004
    m = Machine(BC, ErrorModel.zero().with_delta(delta))
    assert m.errors.delta == pytest.approx(delta)
    tool = np.array([0.0, 0.0, -l1])

    def x_at_touch(b: float, radius: float) -> float:
        # X where the ball centre sits radius + R1 from the C axis (work origin)
        centre0 = m.actual_tool_point([0.0, 0.0, 0.0, b, 0.0], tool)[0]
        side = -np.sign(centre0) if centre0 != 0 else 1.0
        return float(side * (radius + big_r) - centre0)

    x1 = x_at_touch(math.pi / 2, r1)          # B +90°: the tool points to -X
    x2 = -x_at_touch(-math.pi / 2, r2)        # B -90°: travel towards -X, as a length
    assert x1 + delta == pytest.approx(l1 + r1 + big_r, abs=1e-12)
    assert x2 - delta == pytest.approx(l1 + r2 + big_r, abs=1e-12)
    assert ((x2 - x1) - (r2 - r1)) / 2.0 == pytest.approx(delta, abs=1e-12)


def test_c_axis_tilt_moves_a_point_at_height_by_twice_the_tilt() -> None:
    tilt, h = 30e-6, 200.0
    c = RotaryErrors(np.zeros(3), np.array([tilt, 0.0, 0.0]))
    m = Machine(BC, ErrorModel(c=c))
    p = m.actual_tool_point([0.0, 0.0, 0.0, 0.0, math.pi], [0.0, 0.0, h])
    np.testing.assert_allclose(p, [0.0, -h * math.sin(2 * tilt), h * math.cos(2 * tilt)],
                               atol=1e-12)
    # at C = 0 a direction error does nothing: the axis is referenced there
    np.testing.assert_allclose(m.volumetric_error([0.0, 0.0, 0.0, 0.0, 0.0], [5.0, 0, h]), 0,
                               atol=1e-15)


def test_b_axis_location_error_turns_the_tool_about_the_actual_pivot() -> None:
    b_err = RotaryErrors(np.array([0.01, 0.0, -0.02]), np.zeros(3))
    m = Machine(BC, ErrorModel(b=b_err))
    err = m.volumetric_error([0.0, 0.0, 0.0, math.pi / 2, 0.0], [0.0, 0.0, -100.0])
    # the pivot offset p turns by 90°: error = p - R·p = (0.01 + 0.02, 0, -0.02 + 0.01)
    np.testing.assert_allclose(err, [0.03, 0.0, -0.01], atol=1e-12)


def test_axis_input_errors() -> None:
    with pytest.raises(ProbegenError, match="missing \\['C'\\]"):
        Machine(BC).actual_tool_point({"X": 0, "Y": 0, "Z": 0, "B": 0}, TOOL)
    with pytest.raises(ProbegenError, match="shape"):
        Machine().actual_tool_point([1.0, 2.0], TOOL)


# ------------------------------------------------------------------------- TOML


def test_samples_load() -> None:
    five = load_machine(REPO / "samples/machines/five-axis-bc.toml")
    assert five.topology is BC and five.errors.delta == pytest.approx(0.012)
    vmc = load_errors(REPO / "samples/machines/errors-example.toml")
    assert vmc.sxy == pytest.approx(15e-6)
    assert vmc.x.linear[0, 1] == pytest.approx(0.008)


def test_bad_error_files(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('[kinematics]\ntopology = "vmc-xyfz"\n[errors.X]\nEXY = [1.0]\n')
    with pytest.raises(SpecError, match=r"errors\.X\.EXY: unknown key"):
        load_machine(bad)
    bad.write_text('[kinematics]\ntopology = "vmc"\n')
    with pytest.raises(SpecError, match="kinematics.topology: expected one of"):
        load_machine(bad)
    bad.write_text('[errors.C]\ndelta = 1.0\nEX0C = 2.0\n')
    with pytest.raises(SpecError, match="delta or EX0C"):
        load_errors(bad)
    bad.write_text('[errors.X]\nEXX = "big"\n')
    with pytest.raises(SpecError, match="errors.X.EXX: expected an array"):
        load_errors(bad)


# ------------------------------------------------------------------------ probe


def test_lobing_pattern() -> None:
    lobing = Lobing(lateral=0.004, axial=0.001, lobe=0.0015, phase=0.2)
    probe = ProbeModel(3.0, lobing)
    phi = 0.2 + np.arange(6) * math.pi / 3  # lobe maxima and minima in turn
    side = np.column_stack([np.cos(phi), np.sin(phi), np.zeros(6)])
    np.testing.assert_allclose(probe.trigger_offset(side), 0.004 + 0.0015 * np.array(
        [1, -1, 1, -1, 1, -1]), atol=1e-15)
    assert probe.trigger_offset([0.0, 0.0, -1.0]) == pytest.approx(0.001)
    turned = side @ np.array([[-0.5, math.sqrt(3) / 2, 0], [-math.sqrt(3) / 2, -0.5, 0],
                              [0, 0, 1]])  # every direction turned by 120°
    np.testing.assert_allclose(probe.trigger_offset(turned), probe.trigger_offset(side),
                               atol=1e-15)
    coefficients = ProbeModel(3.0, (0.004, 0.001, 0.0015, 0.2))
    assert coefficients.trigger_offset([1.0, 2.0, -0.5]) == probe.trigger_offset([2, 4, -1])


def test_probe_noise_is_reproducible() -> None:
    a = ProbeModel(3.0, noise_sigma=0.0005, seed=42)
    b = ProbeModel(3.0, noise_sigma=0.0005, seed=42)
    first = [a.noisy_offset([1.0, 0.0, 0.0]) for _ in range(5)]
    assert first == [b.noisy_offset([1.0, 0.0, 0.0]) for _ in range(5)]
    a.reset()
    assert [a.noisy_offset([1.0, 0.0, 0.0]) for _ in range(5)] == first
    assert ProbeModel(3.0, noise_sigma=0.0005, seed=43).noise() != first[0]
    assert np.std(a.noise(20000)) == pytest.approx(0.0005, rel=0.03)
    assert ProbeModel(3.0, lambda n: 0.002 - 0.001 * n[:, 2]).trigger_offset([0, 0, 1]) \
        == pytest.approx(0.001)


def test_probe_input_errors() -> None:
    with pytest.raises(ProbegenError, match="ball radius"):
        ProbeModel(0.0)
    with pytest.raises(ProbegenError, match="non-zero"):
        ProbeModel(3.0).trigger_offset([0.0, 0.0, 0.0])
