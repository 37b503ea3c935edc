"""The virtual CMM (DMIS interpreter) against analytic parts.

The fake CMM below holds a part as a signed distance function (negative inside the
material) under a rigid placement; it sphere-traces the stylus ball along every move
(an alarm on contact) and every probing move (the first touch).  The parts: the NIST
simple part (a blind bore), a 25 mm sphere on a stem, and the NIST DCX part as far as
IMTS_M_clean.dmi measures it.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pytest

from probegen.dmis.reader import parse_dmis, read_dmis
from probegen.errors import UnsupportedError
from probegen.sim.alarms import SimAlarm
from probegen.sim.cmm.frames import Frame, alignment_angle
from probegen.sim.cmm.interpreter import ALARM_NO_CONTACT, DmisProgramError, DmisRunResult, run_dmis
from tests.conftest import REPO, SHARED, assert_golden

NIST = SHARED / "ref" / "nist-ippdme"
SIMPLE = NIST / "IPlusSimplePart" / "DMIS"
IMTS = NIST / "DCXpart" / "DMIS" / "IMTS_M_clean.dmi"
SPHERE_PROGRAM = REPO / "tests" / "golden" / "sphere25" / "sphere_test.dmi"
DATA = REPO / "tests" / "data" / "dmisvm"

FAKE_COLLISION = 9901
"""Alarm number of the fake CMM for an unexpected contact."""

Sdf = Callable[[np.ndarray], float]

# ------------------------------------------------------------------ analytic parts


def box(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> Sdf:
    """Exact signed distance of an axis-aligned box."""
    centre = (np.array(lo) + np.array(hi)) / 2.0
    half = (np.array(hi) - np.array(lo)) / 2.0

    def sdf(p: np.ndarray) -> float:
        q = np.abs(p - centre) - half
        return float(np.linalg.norm(np.maximum(q, 0.0)) + min(q.max(), 0.0))
    return sdf


def rod(x: float, y: float, radius: float, z0: float, z1: float) -> Sdf:
    """Exact signed distance of a solid cylinder along Z."""
    def sdf(p: np.ndarray) -> float:
        d = np.array([math.hypot(p[0] - x, p[1] - y) - radius,
                      abs(p[2] - (z0 + z1) / 2.0) - (z1 - z0) / 2.0])
        return float(min(d.max(), 0.0) + np.linalg.norm(np.maximum(d, 0.0)))
    return sdf


def ball(centre: tuple[float, float, float], radius: float) -> Sdf:
    """Exact signed distance of a solid sphere."""
    c = np.array(centre)
    return lambda p: float(np.linalg.norm(p - c) - radius)


def minus(solid: Sdf, *holes: Sdf) -> Sdf:
    """The solid with the holes removed (a lower bound of the distance, exact on faces)."""
    return lambda p: max(solid(p), *(-hole(p) for hole in holes))


def union(*solids: Sdf) -> Sdf:
    """The union of solids."""
    return lambda p: min(solid(p) for solid in solids)


SIMPLE_PART = minus(box((0, 0, -25), (100, 100, 50)), rod(50, 50, 25, 0, 60))
"""NIST simple part: 100 x 100 block, top at z 50, blind bore d50 at (50, 50), bottom z 0."""

SPHERE_CENTRE = (1.0, -0.5, 0.3)
SPHERE_PART = union(ball(SPHERE_CENTRE, 12.5), rod(1.0, -0.5, 5.0, -150.0, 0.3))
"""The 25 mm test sphere on a d10 stem, centre off the program's nominal (0, 0, 0)."""

DCX_PART = minus(box((-86, -52, 0), (86, 52, 30)), rod(0, 0, 15.5, 14, 40),
                 rod(0, 0, 6.25, -10, 40))
"""DCX part as IMTS measures it (part frame): block to z 30, bore d31 above z 14, d12.5 below."""


def rotation(z_deg: float, x_deg: float = 0.0) -> np.ndarray:
    """Rotation about Z after a rotation about X (degrees)."""
    cz, sz = math.cos(math.radians(z_deg)), math.sin(math.radians(z_deg))
    cx, sx = math.cos(math.radians(x_deg)), math.sin(math.radians(x_deg))
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    return rz @ rx


@dataclass
class FakeCmm:
    """A CMM with an analytic part placed at ``rotation @ p + translation`` (MCS)."""

    part: Sdf
    ball_radius: float
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    moves: int = 0
    probes: int = 0

    def clearance(self, centre: np.ndarray) -> float:
        local = self.rotation.T @ (centre - np.array(self.translation))
        return self.part(local) - self.ball_radius

    def move(self, start: tuple[float, ...], end: tuple[float, ...]) -> None:
        self.moves += 1
        a, b = np.array(start), np.array(end)
        length = float(np.linalg.norm(b - a))
        t = 0.0
        while True:
            c = a + (b - a) * (t / length if length else 0.0)
            gap = self.clearance(c)
            if gap < -1e-7:
                where = ", ".join(f"{v:.3f}" for v in c)
                raise SimAlarm(FAKE_COLLISION, f"unexpected contact at {where}")
            if t >= length:
                return
            t = min(t + max(gap, 1e-4), length)

    def probe(self, start: tuple[float, ...], direction: tuple[float, ...],
              distance: float) -> tuple[float, float, float] | None:
        self.probes += 1
        a, u = np.array(start), np.array(direction)
        t = 0.0
        for _ in range(10_000):
            c = a + t * u
            gap = self.clearance(c)
            if gap <= 1e-12:
                return (float(c[0]), float(c[1]), float(c[2]))
            t += gap
            if t > distance:
                return None
        return None


def dcx_cmm(rot: np.ndarray | None = None,
            shift: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> FakeCmm:
    """The DCX part placed as IMTS's comments ask (origin at machine 355, 91, -80)."""
    origin = (355.0 + shift[0], 91.0 + shift[1], -80.0 + shift[2])
    return FakeCmm(DCX_PART, 2.0, np.eye(3) if rot is None else rot, origin)


# ------------------------------------------------------------------------ helpers


def feature_values(result: DmisRunResult, label: str) -> list[float]:
    """The numbers of the last ``label = FEAT/...`` (or ``TOL/``) in the output file."""
    found = [st for st in parse_dmis(result.output).statements
             if st.label is not None and str(st.label) == label]
    assert found, f"{label} not in the output:\n{result.output}"
    return [float(p) for p in found[-1].params if isinstance(p, int | float)]


def assert_matches_nominal(result: DmisRunResult, name: str, tolerance: float) -> None:
    """The actual feature equals its nominal (machine coordinates)."""
    actual, nominal = result.features[name], result.nominals[name]
    np.testing.assert_allclose(actual.location, nominal.location, atol=tolerance)
    if nominal.vector is not None:
        np.testing.assert_allclose(actual.vector, nominal.vector, atol=tolerance)
    if nominal.size is not None:
        assert actual.size == pytest.approx(nominal.size, abs=tolerance)


# ------------------------------------------------------------------- (a) simple part


def test_simple_part_writes_the_nist_output() -> None:
    result = run_dmis(read_dmis(SIMPLE / "simple_in.dms"), FakeCmm(SIMPLE_PART, 2.0))
    assert result.alarm is None and result.skipped == ()
    assert result.output == (SIMPLE / "output.dms").read_text()


def test_vector_compensation_agrees_on_a_perfect_bore() -> None:
    result = run_dmis(read_dmis(SIMPLE / "simple_in.dms"), FakeCmm(SIMPLE_PART, 2.0),
                      compensation="vector")
    assert result.output == (SIMPLE / "output.dms").read_text()


def test_inch_program_reports_in_inches() -> None:
    text = (SIMPLE / "simple_in.dms").read_text()
    inch = re.sub(r"-?\d+\.\d+", lambda m: repr(float(m.group()) / 25.4), text)
    inch = inch.replace("UNITS/ MM", "UNITS/ INCH")
    result = run_dmis(inch, FakeCmm(SIMPLE_PART, 2.0))
    values = feature_values(result, "FA(A_CIRCLE)")
    np.testing.assert_allclose(values, [50 / 25.4, 50 / 25.4, 40 / 25.4, 0, 0, 1, 50 / 25.4],
                               atol=6e-6)
    assert result.features["A_CIRCLE"].size == pytest.approx(50.0, abs=1e-9)


# ------------------------------------------------------------------ (b) sphere test


def test_sphere_test_locates_then_measures_in_the_sphere_frame() -> None:
    result = run_dmis(read_dmis(SPHERE_PROGRAM), FakeCmm(SPHERE_PART, 3.0))
    assert result.alarm is None
    located, measured = result.features["SPH1L"], result.features["SPH1"]
    np.testing.assert_allclose(located.location, SPHERE_CENTRE, atol=1e-9)
    np.testing.assert_allclose(measured.location, SPHERE_CENTRE, atol=1e-9)
    assert measured.size == pytest.approx(25.0, abs=1e-9)
    assert measured.form == pytest.approx(0.0, abs=1e-9)
    assert feature_values(result, "FA(SPH1)") == [0.0, 0.0, 0.0, 25.0]
    assert feature_values(result, "FA(SPH1L)") == [1.0, -0.5, 0.3, 25.0]
    assert result.output.splitlines()[0] == "FILNAM/'SPHERE TEST'"
    assert result.output.endswith("RECALL/D(PCS)\nENDFIL\n")


# ---------------------------------------------------------------------- (c) DCX part


def test_dcx_part_reports_every_feature_at_its_nominal() -> None:
    result = run_dmis(read_dmis(IMTS), dcx_cmm())
    assert result.alarm is None  # MODE/PROG,MAN: skipped with its reason, no flag needed
    assert [(s.line, s.text) for s in result.skipped] == [(36, "MODE/PROG,MAN")]
    for name in ("PLN1", "PLN2", "PLN3", "CLIN1", "CPNT1", "CYL1", "CYL2"):
        assert_matches_nominal(result, name, 1e-6)
    assert {name: r.in_tolerance for name, r in result.tolerances.items()} == {
        f"TOL{i}": True for i in range(1, 8) if i != 1} | {"TOL1": True}
    assert all(abs(r.deviation) < 1e-6 for r in result.tolerances.values())
    assert feature_values(result, "FA(CYL1)") == [0, 0, 26, 0, 0, -1, 31, 12]
    assert feature_values(result, "FA(CLIN1)") == [0, -52, 30, 1, 0, 0, 0, 0, 1]
    assert_golden(DATA / "imts_output.dmo", result.output)


@pytest.mark.parametrize(("z_deg", "x_deg", "shift"), [
    (0.2, 0.0, (0.3, 0.0, 0.0)),
    (-0.2, 0.05, (0.3, -0.2, 0.1)),
])
def test_dcx_datum_alignment_absorbs_the_placement(
        z_deg: float, x_deg: float, shift: tuple[float, float, float]) -> None:
    result = run_dmis(read_dmis(IMTS), dcx_cmm(rotation(z_deg, x_deg), shift))
    assert result.alarm is None
    assert_matches_nominal(result, "CYL1", 1e-6)
    assert_matches_nominal(result, "CYL2", 1e-6)
    assert feature_values(result, "FA(CYL2)") == [0, 0, 0, 0, 0, 1, 12.5, 14]
    assert all(r.in_tolerance for r in result.tolerances.values())
    for name in ("TOL2", "TOL3", "TOL4", "TOL6", "TOL7"):
        assert abs(result.tolerances[name].deviation) < 1e-6
    # before the alignment the part is where the rough frame does not expect it
    assert abs(result.features["PLN3"].location[0] - result.nominals["PLN3"].location[0]) > 0.1


def test_output_statements_follow_the_program() -> None:
    result = run_dmis(read_dmis(IMTS), dcx_cmm())
    lines = result.output.splitlines()
    assert lines[:3] == ["FILNAM/'IMTS DMIS output', 4.0", "UNITS/MM, ANGDEC",
                         "D(MCS1) = DATSET/MCS"]
    assert "TA(TOL3) = TOL/POS, 2D, 0.00000, INTOL" in lines
    assert "TEXT/OUTFIL, 'CYL1 - CYLINDER - '" in lines
    assert lines[-1] == "ENDFIL"
    assert all(len(line) <= 80 for line in lines)


THREE_DATUMS = """DATDEF/FA(PLN1),DAT(A)
DATDEF/FA(PLN2),DAT(B)
DATDEF/FA(PLN3),DAT(C)
D(ABC)=DATSET/DAT(A),ZDIR,ZORIG,DAT(B),-YDIR,YORIG,DAT(C),XORIG
OUTPUT/FA(CPNT1),F(CPNT1)
EVAL/FA(PLN1),T(TOL1)
OUTPUT/TA(TOL1)
SAVE/DA(ABC)
D(BACK)=DATSET/MCS
RECALL/DA(ABC)
OUTPUT/FA(PLN3)
ENDFIL
"""


def test_datset_with_three_datums_puts_the_origin_on_the_corner() -> None:
    head = IMTS.read_text().splitlines()[:93]
    program = "\n".join(head) + "\n" + THREE_DATUMS
    result = run_dmis(program, dcx_cmm(rotation(0.3, -0.1), (-0.4, 0.2, 0.05)))
    assert result.alarm is None
    assert feature_values(result, "FA(CPNT1)")[:3] == [0, 0, 0]
    assert feature_values(result, "F(CPNT1)")[:3] != [0, 0, 0]  # nominal: rough frame
    assert feature_values(result, "TA(TOL1)") == [0.0]
    assert feature_values(result, "FA(PLN3)")[0] == 0.0
    assert result.output.count("FA(PLN3) = FEAT/PLANE") == 2


# -------------------------------------------------------------------- frames alone


def test_trans_and_rotate_move_the_part_frame() -> None:
    frame = Frame.machine().translated(0, 355.0).rotated(2, math.radians(90.0))
    np.testing.assert_allclose(frame.to_pcs(np.array([356.0, 0.0, 0.0])), [0, -1, 0],
                               atol=1e-12)
    np.testing.assert_allclose(frame.matrix @ [356.0, 0, 0, 1], [0, -1, 0, 1], atol=1e-12)
    np.testing.assert_allclose(frame.to_mcs(frame.to_pcs(np.array([1.0, 2, 3]))), [1, 2, 3])


def test_rotate_to_a_feature_aligns_the_named_axis() -> None:
    diagonal = np.array([1.0, 1.0, 0.0]) / math.sqrt(2.0)
    machine = Frame.machine()
    turned = machine.rotated(2, alignment_angle(machine, 2, 1, 1.0, diagonal))
    np.testing.assert_allclose(turned.rotation[1], diagonal, atol=1e-12)
    flipped = machine.rotated(2, alignment_angle(machine, 2, 0, -1.0, diagonal))
    np.testing.assert_allclose(flipped.rotation[0], -diagonal, atol=1e-12)


# ------------------------------------------------------------------------- cone

CONE_APEX, CONE_HALF = (0.5, -0.3, 40.0), math.radians(30.0)


def cone_part(p: np.ndarray) -> float:
    """A solid cone, apex up at CONE_APEX, opening downwards (distance exact on the nappe)."""
    h = CONE_APEX[2] - p[2]
    rho = math.hypot(p[0] - CONE_APEX[0], p[1] - CONE_APEX[1])
    if h * math.cos(CONE_HALF) + rho * math.sin(CONE_HALF) < 0.0:
        return math.hypot(rho, h)
    return rho * math.cos(CONE_HALF) - h * math.sin(CONE_HALF)


def cone_program() -> str:
    """Twelve points on three rings, each approached from straight above."""
    lines = [PROLOGUE, "F(CN)=FEAT/CONE,OUTER,CART,0,0,40,0,0,-1,60",
             "MEAS/CONE,F(CN),12"]
    c, s = math.cos(CONE_HALF), math.sin(CONE_HALF)
    for ring, (h, turn) in enumerate([(10.0, 0.0), (15.0, 45.0), (20.0, 20.0)]):
        for k in range(4):
            a = math.radians(turn + 90.0 * k + 7.0 * ring)
            ux, uy = math.cos(a), math.sin(a)
            x, y, z = h * math.tan(CONE_HALF) * ux, h * math.tan(CONE_HALF) * uy, 40.0 - h
            i, j, kz = c * ux, c * uy, s
            lines.append(f"GOTO/{x + 14 * i:.6f},{y + 14 * j:.6f},70")
            lines.append(f"PTMEAS/CART,{x:.9f},{y:.9f},{z:.9f},{i:.9f},{j:.9f},{kz:.9f}")
            lines.append(f"GOTO/{x + 14 * i:.6f},{y + 14 * j:.6f},70")
    lines += ["ENDMES", "OUTPUT/FA(CN)", "ENDFIL"]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("compensation", ["feature", "vector"])
def test_cone_apex_axis_and_angle(compensation: str) -> None:
    result = run_dmis(cone_program(), FakeCmm(cone_part, 2.0), compensation=compensation)
    assert result.alarm is None
    cone = result.features["CN"]
    exact = compensation == "feature"  # the apex is off nominal: vector compensation errs
    np.testing.assert_allclose(cone.location, CONE_APEX, atol=1e-9 if exact else 0.05)
    np.testing.assert_allclose(cone.vector, (0, 0, -1), atol=1e-9 if exact else 0.05)
    assert cone.size == pytest.approx(60.0, abs=1e-7 if exact else 0.5)


# ------------------------------------------------------------------------- alarms

PROLOGUE = """DMISMN/'ALARMS',5.0
UNITS/MM,ANGDEC
S(P)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,-1,50,4.0
SNSLCT/S(P)
SNSET/APPRCH,10
SNSET/SEARCH,10
"""


def test_goto_through_the_part_raises_the_cmm_alarm() -> None:
    program = PROLOGUE + "GOTO/-20,50,25\nGOTO/120,50,25\nENDFIL\n"
    result = run_dmis(program, FakeCmm(SIMPLE_PART, 2.0))
    assert result.alarm is not None
    assert (result.alarm.number, result.alarm.line) == (FAKE_COLLISION, 8)
    assert not result.output.endswith("ENDFIL\n")


def test_ptmeas_without_a_surface_raises_no_contact() -> None:
    program = PROLOGUE + ("F(P1)=FEAT/PLANE,CART,20,20,80,0,0,1\nMEAS/PLANE,F(P1),3\n"
                          "PTMEAS/CART,20,20,80,0,0,1\nENDMES\nENDFIL\n")
    result = run_dmis(program, FakeCmm(SIMPLE_PART, 2.0))
    assert result.alarm is not None
    assert (result.alarm.number, result.alarm.line) == (ALARM_NO_CONTACT, 9)
    assert "APPRCH + SEARCH = 20" in result.alarm.message


# ---------------------------------------------------------------- unsupported input

EXTRA = """T(PAR)=TOL/PARLEL,0.01,DAT(A)
OUTPUT/FA(A_CIRCLE),TA(PAR)
F(C2)=FEAT/CIRCLE,INNER,CART,50,50,30,0,0,1,50
MEAS/CIRCLE,F(C2),2
PTMEAS/POL,25,0,30,-1,0,0
PTMEAS/CART,25,50,30,1,0,0
ENDMES
OUTPUT/FA(C2)
ENDFIL
"""


def _simple_with_extras() -> str:
    return (SIMPLE / "simple_in.dms").read_text().replace("ENDFIL\n", EXTRA)


def test_unsupported_statement_names_its_line() -> None:
    with pytest.raises(UnsupportedError, match=r"<string>:33: .*TOL/PARLEL"):
        run_dmis(_simple_with_extras(), FakeCmm(SIMPLE_PART, 2.0))


def test_skip_unsupported_lists_what_was_not_executed() -> None:
    result = run_dmis(_simple_with_extras(), FakeCmm(SIMPLE_PART, 2.0),
                      skip_unsupported=True)
    assert [s.line for s in result.skipped] == [33, 34, 37, 40]
    assert "FA(C2)" in result.skipped[-1].reason and "line 37" in result.skipped[-1].reason
    assert result.output == (SIMPLE / "output.dms").read_text()


def test_wrong_program_raises_a_program_error() -> None:
    with pytest.raises(DmisProgramError, match=r"<string>:3: FA\(NOPE\) is not defined"):
        run_dmis("DMISMN/'X',5.0\nUNITS/MM,ANGDEC\nOUTPUT/FA(NOPE)\nENDFIL\n",
                 FakeCmm(SIMPLE_PART, 2.0))
    with pytest.raises(DmisProgramError, match=r"^<string>: the program ends without ENDFIL"):
        run_dmis("DMISMN/'X',5.0\nUNITS/MM,ANGDEC\n", FakeCmm(SIMPLE_PART, 2.0))
