"""Orientations and stylus changes (issue 17) in every dialect, from hand-made IR.

The program: a vertical bore measured with the start stylus (T20, ball 6), a change to
stylus D2 (T21, ball 2), an orientation whose frame +Z is work +X (a bore in the part's
+X face, measured in that frame exactly as a vertical bore), and the orientation back to
the vertical.  Each dialect's text is golden-tested whole; the DMIS points are parsed
back and compared with the frame points mapped by ``ir.frames``; the Fanuc ``G68.2``
angles give the frame's rotation back; refusals name what is missing.
"""

from __future__ import annotations

import math
import re
import subprocess
from dataclasses import replace
from pathlib import Path

import pytest
from conftest import REPO, assert_golden
from test_linuxcnc import rs274  # noqa: F401  (the fixture: skips, or fails in CI, without it)

from probegen import ir
from probegen.dialects import get_dialect
from probegen.dialects.split import fit
from probegen.errors import UnsupportedError
from probegen.ir import frames

GOLDEN = REPO / "tests" / "golden" / "orient"
SETUP = ir.Setup(
    program_number=7, program_name="ORIENT", units="mm", work_offset="G54", clearance_z=50.0,
    ball_diameter=6.0, shank_diameter=4.0, tool_number=20, tool_change=False,
    position_feed=2000.0, probe_feed=300.0, probe_on=("M19",), probe_off=("M20",),
    variable_base=100, reset_codes=("G17", "G40", "G49", "G80", "G94", "G69"),
    probe_length=40.0, options=("G68", "G68.2", "#3004"),
)
SIDE = ir.Orient("TILT1", frames.frame_for((1.0, 0.0, 0.0)), head=(90.0, 90.0),
                 rotary=(("A", -90.0), ("C", 90.0)), clearance_z=80.0)
"""Frame +Z along work +X: frame X = work +Y, frame Y = work +Z."""
VERTICAL = ir.Orient("TILT0", frames.IDENTITY, head=(0.0, 0.0),
                     rotary=(("A", 0.0), ("C", 0.0)), clearance_z=50.0)
D2 = ir.SelectStylus("D2", 21, 2.0, 1.4, 30.0)


def bore(fid: str, centre: tuple[float, float], levels: tuple[float, ...], diameter: float,
         ball: float, top: float) -> tuple[ir.Node, ...]:
    """A bore (axis frame +Z) measured with three touches per level from its axis: the
    move to the level, each touch with its move out and back, the climb to ``top``."""
    cx, cy = centre
    nodes: list[ir.Node] = [ir.Move((cx, cy, top), ir.MoveMode.RAPID)]
    body: list[ir.Node] = []
    k = 0
    for z in levels:
        for angle in (0.0, 120.0, 240.0):
            k += 1
            c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
            centre_pt = (cx, cy, z)
            body += [ir.Move(centre_pt, ir.MoveMode.PROTECTED),
                     ir.Touch(fid, k, ir.TouchRole.MEASURE,
                              (round(cx + diameter / 2 * c, 6), round(cy + diameter / 2 * s, 6),
                               z), (round(-c, 12), round(-s, 12), 0.0),
                              diameter / 2 - ball / 2, 1.0),
                     ir.Move(centre_pt, ir.MoveMode.RETRACT)]
    body.append(ir.Move((cx, cy, top), ir.MoveMode.PROTECTED))
    mid = (levels[0] + levels[-1]) / 2
    definition: ir.FeatureDef = ir.CylinderDef(
        fid, (cx, cy, mid), (0.0, 0.0, 1.0), diameter, abs(levels[0] - levels[-1]),
        inner=True) if len(levels) > 1 else ir.CircleDef(
        fid, (cx, cy, mid), (0.0, 0.0, 1.0), diameter, inner=True)
    return (*nodes, ir.FeatureBlock(definition, tuple(body)))


TOP = bore("TOP", (20.0, 10.0), (40.0,), 20.0, 6.0, 50.0)
SIDE_BORE = bore("SIDE", (0.0, 10.0), (48.0, 42.0), 8.0, 2.0, 80.0)
INDEX_Z = 120.0
"""The index height of the hand-made program (work Z): the changes are routed there."""
UP = ir.Move((20.0, 10.0, INDEX_Z), ir.MoveMode.RAPID)
"""Straight up from the end of TOP (work = the vertical frame)."""
OVER = ir.Move((0.0, INDEX_Z, 80.0), ir.MoveMode.RAPID)
"""Over SIDE's first point (frame (0, 10, 80) = work (80, 0, 10)) at the index height:
work (80, 0, 120), written in SIDE's frame."""
BODY: tuple[ir.Node, ...] = (*TOP, UP, D2, SIDE, OVER, *SIDE_BORE, OVER, VERTICAL)
"""The program as the planner routes it: up to the index height, the changes, level over
the next point; at the end straight up (work (80, 0, 120) again) and back to the
vertical."""


def program(*nodes: ir.Node, setup: ir.Setup = SETUP) -> ir.Program:
    return ir.Program(setup, nodes or BODY)


def text(dialect: str, prog: ir.Program, compact: bool = False) -> str:
    d = get_dialect(dialect)
    d.compact = compact
    return d.generate(prog)


# -- whole files -------------------------------------------------------------------------
@pytest.mark.parametrize(("name", "dialect", "compact"), [
    ("fanuc.nc", "fanuc", True), ("fanuc_inline.nc", "fanuc", False),
    ("program.dmi", "dmis", False)])
def test_programs_in_a_frame_are_golden(name: str, dialect: str, compact: bool) -> None:
    assert_golden(GOLDEN / name, text(dialect, program(), compact))


SMALL = bore("SMALL", (-20.0, 0.0), (45.0,), 4.0, 2.0, 50.0)
PLAIN = replace(SETUP, probe_on=(), probe_off=())
"""LinuxCNC has no probe on/off M codes of its own (rs274 refuses M19/M20 unconfigured)."""


def test_stylus_change_is_golden_on_haas_and_linuxcnc() -> None:
    assert_golden(GOLDEN / "stylus.haas.nc", text("haas", program(*TOP, D2, *SMALL)))
    assert_golden(GOLDEN / "stylus.ngc",
                  text("linuxcnc", program(*TOP, D2, *SMALL, setup=PLAIN)))


# -- the numbers ---------------------------------------------------------------------------
NUMBER = r"(-?\d+\.\d+)"


def test_fanuc_euler_angles_give_the_frame_back() -> None:
    found = re.findall(rf"G68\.2 X{NUMBER} Y{NUMBER} Z{NUMBER} I{NUMBER} J{NUMBER} "
                       rf"K{NUMBER}", text("fanuc", program()))
    assert found, "no G68.2 block"
    for *origin, i, j, k in found:
        rotation = frames.from_euler_zxz(float(i), float(j), float(k))
        assert all(abs(rotation[r][c] - SIDE.rotation[r][c]) < 1e-6
                   for r in range(3) for c in range(3))
        assert [float(v) for v in origin] == list(SIDE.origin)


@pytest.mark.parametrize("axis", [(1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.3, 0.4, 0.5),
                                  (0.0, 0.0, -1.0), (-0.2, 0.1, -0.9)])
def test_fanuc_euler_angles_hold_for_any_frame(axis: tuple[float, float, float]) -> None:
    turned = replace(SIDE, rotation=frames.frame_for(axis), origin=(5.0, -2.5, 1.25))
    i, j, k = (float(v) for v in re.findall(
        rf"G68\.2 X5\.0000 Y-2\.5000 Z1\.2500 I{NUMBER} J{NUMBER} K{NUMBER}",
        text("fanuc", program(turned, VERTICAL)))[0])
    rotation = frames.from_euler_zxz(i, j, k)
    assert max(abs(rotation[r][c] - turned.rotation[r][c])
               for r in range(3) for c in range(3)) < 2e-6  # 4 decimals of a degree


def test_dmis_points_are_the_frame_points_in_work_coordinates() -> None:
    dmi = text("dmis", program())
    measured = [tuple(float(v) for v in m) for m in re.findall(
        rf"PTMEAS/CART,{NUMBER},{NUMBER},{NUMBER},{NUMBER},{NUMBER},{NUMBER}", dmi)]
    expected = [(*n.contact, *n.normal) for node, _ in frames.in_work(BODY)
                for n in ir.walk((node,)) if isinstance(n, ir.Touch)]
    touches = [n for n in ir.walk(BODY) if isinstance(n, ir.Touch)]
    assert len(measured) == len(expected) == len(touches) == 9
    for got, want in zip(measured, expected, strict=True):
        assert max(abs(a - b) for a, b in zip(got, want, strict=True)) < 1e-4  # type: ignore[arg-type]
    # the side bore's touches lie on the +X face's bore: work X = frame Z, Y = frame X
    side = measured[3:]
    assert {round(p[0], 4) for p in side} == {48.0, 42.0}
    assert all(abs(math.hypot(p[1] - 0.0, p[2] - 10.0) - 4.0) < 1e-4 for p in side)
    assert re.search(r"F\(SIDE\)=FEAT/CYLNDR,INNER,CART,45\.0000,0\.0000,10\.0000,"
                     r"1\.000000,0\.000000,0\.000000,8\.0000,6\.0000", dmi)


def test_dmis_declares_one_sensor_per_stylus_and_head_angle() -> None:
    dmi = text("dmis", program())
    assert re.findall(r"S\((\w+)\)=SNSDEF/PROBE,INDEX,POL,([-\d.]+),([-\d.]+),0,0,-1,"
                      r"([\d.]+),([\d.]+)", dmi) == [
        ("PRB20", "0", "0", "40.0000", "6.0000"), ("D2_A0B0", "0", "0", "30.0000", "2.0000"),
        ("D2_A90B90", "90", "90", "30.0000", "2.0000")]
    assert re.findall(r"SNSLCT/S\((\w+)\)", dmi) == ["PRB20", "D2_A0B0", "D2_A90B90",
                                                     "D2_A0B0"]


def test_fanuc_touches_use_the_ball_of_the_stylus_in_the_spindle() -> None:
    """The first touch of each bore ends ``overtravel`` past its contact: the end point is
    ``contact + (r - overtravel)·normal`` with the ball radius then in the spindle."""
    calls = [dict(re.findall(r"([XYZUVW])(-?[\d.]+)", line[8:]))
             for line in text("fanuc", program(), compact=True).split("\n")
             if line.startswith("G65P8002")]
    assert len(calls) == 9
    # TOP touch 1: contact x = 30, normal -1, r = 3, overtravel 1: end x = 30 - 2 = 28
    assert float(calls[0]["U"]) == 28.0
    # SIDE touch 1 (frame coordinates): contact x = 4, r = 1: end x = 4 - 0 = 4
    assert float(calls[3]["U"]) == 4.0


def test_the_header_resets_g69_when_the_profile_forgets_it() -> None:
    setup = replace(SETUP, reset_codes=("G17",))
    assert "G90 G17 G69\n" in text("fanuc", program(setup=setup))
    assert "G90 G17\n" in text("fanuc", program(*TOP, setup=setup))


# -- refusals -------------------------------------------------------------------------------
def test_fanuc_refuses_a_frame_without_the_option() -> None:
    setup = replace(SETUP, options=("G68", "#3004"), limits_source="vmc.toml")
    with pytest.raises(UnsupportedError, match=r"orientation TILT1 needs the tilted working "
                                               r"plane.*expected \"G68.2\".*vmc.toml"):
        text("fanuc", program(setup=setup))
    assert text("fanuc", program(*TOP, D2, setup=setup))  # a stylus change needs no option


def test_fanuc_refuses_a_return_without_rotary_axes() -> None:
    bare = (replace(SIDE, rotary=()), replace(VERTICAL, rotary=()))
    with pytest.raises(UnsupportedError, match="neither names its rotary axes"):
        text("fanuc", program(*bare))


def test_haas_refuses_a_frame_with_its_reason() -> None:
    with pytest.raises(UnsupportedError, match=r"dialect 'haas' cannot turn the probe to "
                                               r"orientation TILT1: .*G268.*setup"):
        text("haas", program())


def test_linuxcnc_refuses_a_frame_with_the_message() -> None:
    with pytest.raises(UnsupportedError, match=re.escape(
            "LinuxCNC: a tilted frame needs a five-axis kinematics this dialect does not "
            "configure; plan this feature with a setup or on a CMM (orientation TILT1)")):
        text("linuxcnc", program())
    assert "(ORIENT TILT0)" in text("linuxcnc", program(VERTICAL, *TOP))


def test_dmis_refuses_a_turned_frame_without_head_angles() -> None:
    with pytest.raises(UnsupportedError, match="gives no head angles"):
        text("dmis", program(replace(SIDE, head=None), *SIDE_BORE))


# -- split ------------------------------------------------------------------------------------
def test_a_split_part_restates_the_frame_and_the_stylus() -> None:
    setup = replace(SETUP, program_size=900, limits_source="vmc.toml")
    body = (*TOP, D2, SIDE, *SIDE_BORE, *bore("SIDE2", (-5.0, 20.0), (45.0,), 8.0, 2.0, 80.0),
            VERTICAL)
    d = get_dialect("fanuc")
    d.compact = True
    fitted = fit(d, ir.Program(setup, body))
    assert len(fitted.parts) == 3, [p.features for p in fitted.parts]
    last = fitted.parts[-1]
    assert last.features == ("SIDE2",)
    assert_golden(GOLDEN / "split_driver.nc", fitted.main)
    assert_golden(GOLDEN / "split_part3.nc", last.text)
    lines = last.text.split("\n")
    assert "G43 H21" in lines and "T21 M6" not in lines  # the stylus taken in part 2
    restate = lines.index("(IN ORIENT TILT1 A-90.000 C90.000)")
    assert lines[restate + 1].startswith("G68.2 ") and lines[restate + 2] == "G53.1"
    assert "G53 Z0" not in lines[:restate + 4]  # no move before the part's own path


# -- rs274 -------------------------------------------------------------------------------------
def test_rs274_runs_the_stylus_change(tmp_path: Path, rs274: str) -> None:  # noqa: F811
    exe = rs274
    prog = program(*TOP, D2, *SMALL, setup=PLAIN)
    (tmp_path / "program.ngc").write_text(text("linuxcnc", prog), encoding="ascii")
    (tmp_path / "tool.tbl").write_text("T20 P20 Z0 D6 ;probe\nT21 P21 Z0 D2 ;D2\n",
                                       encoding="ascii")
    done = subprocess.run([exe, "-g", "-t", "tool.tbl", "program.ngc"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120, check=False)
    out = done.stdout + done.stderr
    assert done.returncode == 0, out
    assert "SELECT_TOOL(21)" in out and "CHANGE_TOOL" in out
    probes = re.findall(r"STRAIGHT_PROBE\(([-\d.]+), ([-\d.]+), ([-\d.]+)", out)
    # SMALL's first touch ends 1 mm past its contact with the D2 ball: x = -18 - 0
    assert [float(v) for v in probes[6]] == [-18.0, 0.0, 45.0]
    assert 'LOG("PGEND O7")' in out


@pytest.mark.parametrize(("level", "written"), [(70.0, "Z70.0000"), (0.0, "Z50.0000")])
def test_the_vertical_is_taken_at_its_level_never_below_the_clearance_plane(
        level: float, written: str) -> None:
    nc = text("fanuc", program(SIDE, replace(VERTICAL, clearance_z=level)))
    assert nc.split("G53 A0 C0\n")[1].startswith(f"G0 G43 H20 {written}\n")
