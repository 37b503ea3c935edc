"""``FEAT/TORUS`` and ``MEAS/TORUS`` on the virtual CMM, and the torus actual in its output.

Parts are analytic (the fake CMM of ``tests/test_dmis_vm.py``): a solid ring (OUTER:
the material inside the tube) and a toroidal groove in a solid (INNER: the air inside
the tube), placed off the program's nominal by a shift and a small tilt.  The CMM fits
the exact ball centres, so centre, axis and both diameters come back to the fit's
precision (1e-7 mm here); the output file's five decimals to 1e-5.
"""

from __future__ import annotations

import contextlib
import math

import numpy as np
import pytest
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen.dmis.reader import parse_dmis
from probegen.errors import ProbegenError
from probegen.results import parse_dmis_output
from probegen.sim.cmm.interpreter import DmisProgramError, run_dmis
from tests.test_dmis_vm import FakeCmm, feature_values, rotation

MAJOR, MINOR = 20.0, 8.0
"""Radius of the tube's centre circle and of the tube (mm) of both parts."""

BALL = 2.0
TILT = rotation(30.0, 2.0)
SHIFT = (0.2, -0.15, 0.1)


def ring(p: np.ndarray) -> float:
    """Solid torus about Z through the origin (exact signed distance)."""
    return math.hypot(math.hypot(p[0], p[1]) - MAJOR, p[2]) - MINOR


def groove(p: np.ndarray) -> float:
    """Material everywhere but inside the same torus: a toroidal cavity."""
    return -ring(p)


def torus_program(side: str, units: str = "MM", tolerances: str = "") -> str:
    """Twenty-four points on three tube angles; the probe comes from outside the ring
    (OUTER) or from the tube's centre circle (INNER)."""
    k = 25.4 if units == "INCH" else 1.0
    inner = side == "INNER"
    approach = 2.0 if inner else 6.0
    lines = ["DMISMN/'TORUS',5.0", f"UNITS/{units},ANGDEC",
             f"S(P)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,-1,50,{2 * BALL / k!r}", "SNSLCT/S(P)",
             f"SNSET/APPRCH,{approach / k!r}", f"SNSET/SEARCH,{6.0 / k!r}",
             f"F(RG)=FEAT/TORUS,{side},CART,0,0,0,0,0,1,{2 * MAJOR / k!r},{2 * MINOR / k!r}",
             tolerances, "MEAS/TORUS,F(RG),24"]
    for ring_no, phi in enumerate((-50.0, 10.0, 70.0) if inner else (0.0, 40.0, 80.0)):
        c, s = math.cos(math.radians(phi)), math.sin(math.radians(phi))
        for n in range(8):
            a = math.radians(45.0 * n + 15.0 * ring_no)
            ux, uy = math.cos(a), math.sin(a)
            normal = np.array([c * ux, c * uy, s])  # out of the tube
            point = np.array([MAJOR * ux, MAJOR * uy, 0.0]) + MINOR * normal
            vector = -normal if inner else normal  # out of the material
            start = point + (BALL + approach) * vector
            safe = [MAJOR * ux, MAJOR * uy, 0.0] if inner else [start[0], start[1], 40.0]
            lines.append("GOTO/" + ",".join(f"{v / k:.9f}" for v in safe))
            lines.append("PTMEAS/CART," + ",".join(f"{v / k:.9f}" for v in point) + ","
                         + ",".join(f"{v:.12f}" for v in vector))
            lines.append("GOTO/" + ",".join(f"{v / k:.9f}" for v in safe))
    lines += ["ENDMES", "OUTPUT/FA(RG)" + (",TA(POS3),TA(POS2)" if tolerances else ""),
              "ENDFIL"]
    return "\n".join(line for line in lines if line) + "\n"


def placed(side: str) -> FakeCmm:
    return FakeCmm(groove if side == "INNER" else ring, BALL, TILT, SHIFT)


TRUE_CENTRE = np.array(SHIFT)
TRUE_AXIS = TILT @ np.array([0.0, 0.0, 1.0])


@pytest.mark.parametrize("side", ["OUTER", "INNER"])
def test_torus_centre_axis_and_diameters(side: str) -> None:
    result = run_dmis(torus_program(side), placed(side))
    assert result.alarm is None
    torus = result.features["RG"]
    assert (torus.kind, torus.qualifier) == ("TORUS", side)
    np.testing.assert_allclose(torus.location, TRUE_CENTRE, atol=1e-7)
    np.testing.assert_allclose(torus.vector, TRUE_AXIS, atol=1e-9)
    assert torus.size == pytest.approx(2 * MAJOR, abs=1e-7)
    assert torus.minor == pytest.approx(2 * MINOR, abs=1e-7)
    assert torus.form == pytest.approx(0.0, abs=1e-7)
    # the output file: FEAT/TORUS,side,CART,x,y,z,i,j,k,major,minor with 5 decimals
    values = feature_values(result, "FA(RG)")
    np.testing.assert_allclose(values, [*TRUE_CENTRE, *TRUE_AXIS, 2 * MAJOR, 2 * MINOR],
                               atol=6e-6)
    read = parse_dmis_output(result.output, strict=True).feature("RG")
    assert (read.type, read.material) == ("TORUS", side)
    assert read.diameter == pytest.approx(2 * MAJOR, abs=1e-5)
    assert read.minor_diameter == pytest.approx(2 * MINOR, abs=1e-5)


def test_vector_compensation_is_exact_on_a_part_at_its_nominal() -> None:
    cmm = FakeCmm(ring, BALL)
    result = run_dmis(torus_program("OUTER"), cmm, compensation="vector")
    torus = result.features["RG"]
    np.testing.assert_allclose(torus.location, (0.0, 0.0, 0.0), atol=1e-7)
    assert torus.size == pytest.approx(2 * MAJOR, abs=1e-7)
    assert torus.minor == pytest.approx(2 * MINOR, abs=1e-7)


def test_inch_program_reports_in_inches() -> None:
    result = run_dmis(torus_program("OUTER", units="INCH"), placed("OUTER"))
    values = feature_values(result, "FA(RG)")
    want = [*(TRUE_CENTRE / 25.4), *TRUE_AXIS, 2 * MAJOR / 25.4, 2 * MINOR / 25.4]
    np.testing.assert_allclose(values, want, atol=6e-6)
    read = parse_dmis_output(result.output, strict=True).feature("RG")
    assert read.minor_diameter == pytest.approx(2 * MINOR, abs=25.4 * 1e-5)


def test_position_tolerance_of_the_centre() -> None:
    tols = "T(POS3)=TOL/POS,3D,0.52\nT(POS2)=TOL/POS,2D,0.52"
    result = run_dmis(torus_program("OUTER", tolerances=tols), placed("OUTER"))
    pos3, pos2 = result.tolerances["POS3"], result.tolerances["POS2"]
    assert pos3.deviation == pytest.approx(2 * float(np.linalg.norm(SHIFT)), abs=1e-7)
    assert pos2.deviation == pytest.approx(2 * math.hypot(SHIFT[0], SHIFT[1]), abs=1e-7)
    assert (pos3.in_tolerance, pos2.in_tolerance) == (False, True)
    assert "TA(POS3) = TOL/POS, 3D, 0.53852, OUTOL" in result.output


def test_diameter_tolerance_is_refused_on_a_torus() -> None:
    program = torus_program("OUTER").replace(
        "OUTPUT/FA(RG)", "T(D)=TOL/DIAM,-0.01,0.01\nOUTPUT/FA(RG),TA(D)")
    with pytest.raises(DmisProgramError, match=r"TOL/DIAM does not apply to the TORUS RG"):
        run_dmis(program, placed("OUTER"))


@pytest.mark.parametrize(("old", "new", "message"), [
    ("F(RG)=FEAT/TORUS,OUTER,CART,0,0,0,0,0,1,40.0,16.0",
     "F(RG)=FEAT/TORUS,OUTER,CART,0,0,0,0,0,1,40.0", r":7: FEAT/TORUS takes 8 numbers"),
    ("F(RG)=FEAT/TORUS,OUTER,", "F(RG)=FEAT/TORUS,",
     r":7: FEAT/TORUS: expected INNER or OUTER, found CART"),
    ("0,0,0,0,0,1,40.0", "0,0,0,0,0,0,40.0", r":7: .*vector"),
    ("MEAS/TORUS,F(RG),24", "MEAS/SPHERE,F(RG),24", r"MEAS/SPHERE: F\(RG\) is a TORUS"),
])
def test_wrong_torus_statements_name_their_line(old: str, new: str, message: str) -> None:
    program = torus_program("OUTER")
    assert old in program
    with pytest.raises(DmisProgramError, match=message):
        run_dmis(program.replace(old, new), placed("OUTER"))


def test_too_few_points_for_a_torus() -> None:
    program = torus_program("OUTER").replace("MEAS/TORUS,F(RG),24", "MEAS/TORUS,F(RG),6")
    lines = program.splitlines()
    start = lines.index("MEAS/TORUS,F(RG),6")
    cut = lines[:start + 1 + 18] + lines[lines.index("ENDMES"):]
    with pytest.raises(DmisProgramError, match="MEAS/TORUS needs at least 7 points, found 6"):
        run_dmis("\n".join(cut) + "\n", placed("OUTER"))


def test_grammar_reads_the_torus_statement() -> None:
    (st_,) = parse_dmis("F(RIM)=FEAT/TORUS,OUTER,CART,25,25,26,0,0,1,38,8\n").statements
    assert (str(st_.label), st_.major) == ("F(RIM)", "FEAT")
    assert st_.params == ("TORUS", "OUTER", "CART", 25, 25, 26, 0, 0, 1, 38, 8)


@settings(max_examples=examples(60))
@given(st.lists(st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                          st.integers(-10, 10), st.sampled_from(["INNER", "OUTER", "CART"])),
                max_size=12))
def test_random_torus_definitions_end_in_a_result_or_a_probegen_error(
        params: list[object]) -> None:
    text = ",".join(repr(p) if isinstance(p, float) else str(p) for p in params)
    program = f"DMISMN/'T',5.0\nUNITS/MM,ANGDEC\nF(T)=FEAT/TORUS,{text}\nENDFIL\n"
    with contextlib.suppress(ProbegenError):  # anything else fails the test
        run_dmis(program, FakeCmm(ring, BALL))
