"""The DMIS post-processor: NIST DMIS programs → Fanuc → virtual machine → evaluation.

Truth: the nominal features of the DMIS program (the STEP models are the nominal parts,
placed as the programs' comments ask) and the same DMIS program run on the virtual CMM
(the same virtual machine and model through the DMIS interpreter).  The posted program
touches the same points as the CMM run, and the control reports the commanded
position of each trigger; with the part where the nominals put it every ball centre is
a round number, so the DPRNT log's 4 decimals lose nothing and the two evaluations
agree to 1e-6 mm.  A displaced part costs the DPRNT rounding (half a unit of the 4th
decimal per coordinate): 2e-4 mm there.
"""

from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, SHARED, assert_golden
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate
from test_linuxcnc import Standalone, assert_close, motions, rs274, run_rs274  # noqa: F401

from probegen import cad, ir
from probegen.cli.app import ExitCode, main
from probegen.dialects import get_dialect
from probegen.dmis.reader import parse_dmis
from probegen.errors import CollisionError, ProbegenError, ResultsParseError, UnsupportedError
from probegen.ir.identity import map_identity
from probegen.machine.kinematics import Machine, load_machine
from probegen.machine.probe_model import Lobing, ProbeModel
from probegen.machine.profile import load_profile
from probegen.planning.collision import SphereObstacle
from probegen.post.evaluate import evaluate_log, ingest_file
from probegen.post.featuremap import dumps, feature_map, parse_feature_map, read_feature_map
from probegen.post.files import PostOutput, post_file
from probegen.post.frontend import post_dmis
from probegen.results import parse_dprnt
from probegen.sim.cmm.interpreter import DmisRunResult, run_dmis
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import CmmAdapter, VirtualMachine, run_text

NIST = SHARED / "ref" / "nist-ippdme"
MACHINE = REPO / "samples" / "post" / "vmc-fanuc-d4.toml"
GOLDEN = REPO / "tests" / "golden" / "post"


@dataclass(frozen=True)
class Case:
    """A NIST DMIS program, its model and where the program wants the model."""

    name: str
    program: Path
    model: Path
    offset: tuple[float, float, float]
    home: tuple[float, float, float]
    reroute: bool


SIMPLE = Case("simple_in", NIST / "IPlusSimplePart/DMIS/simple_in.dms",
              NIST / "IPlusSimplePart/STEP_Part21_AP203/ipp_simple.stp",
              (0.0, 0.0, 0.0), (50.0, 50.0, 200.0), False)
DCX = Case("IMTS_M_clean", NIST / "DCXpart/DMIS/IMTS_M_clean.dmi",
           NIST / "DCXpart/STEP_AP214/DaimlerChryslerTestPartAP214.stp",
           (355.0, 91.0, -80.0), (355.0, 91.0, 150.0), True)
CASES = [SIMPLE, DCX]


@pytest.fixture(scope="module")
def machine():  # type: ignore[no-untyped-def]
    return load_profile(MACHINE)


@pytest.fixture(scope="module")
def posted(machine) -> dict[str, PostOutput]:  # type: ignore[no-untyped-def]
    return {c.name: post_file(c.program, machine, cad.load_part(c.model), dialect="fanuc",
                              offset=c.offset, reroute=c.reroute) for c in CASES}


def run_both(case: Case, out: PostOutput, shift: tuple[float, float, float] = (0, 0, 0),
             kinematics: Machine | None = None, lobing: Lobing | None = None
             ) -> tuple[DmisRunResult, DmisRunResult]:
    """The posted program on the virtual machine, evaluated; and the DMIS program on the
    virtual CMM; the part at the program's place plus ``shift``, both machines with the
    given errors and probe pre-travel."""
    model = cad.load_step(case.model)
    where = tuple(np.add(case.offset, shift))

    def machine() -> VirtualMachine:
        return VirtualMachine(PlacedPart.from_model(model, translation=where),
                              ProbeModel(2.0, lobing or Lobing(0.0, 0.0, 0.0)), kinematics)

    vm = machine()
    res = run_text(out.text, vm, kind="macrob", source=case.name)
    assert res.alarm is None, res.alarm
    assert res.touches == len(out.fmap.touches)
    posted = evaluate_log(parse_dprnt(res.output, strict=True), out.fmap)
    direct = run_dmis(case.program.read_text(), CmmAdapter(machine()), home=case.home)
    assert direct.alarm is None
    return posted, direct


def assert_same(a: DmisRunResult, b: DmisRunResult, tolerance: float) -> None:
    """Every feature of ``a`` equals ``b``'s (location, vector, size, form), mm."""
    assert a.features.keys() == b.features.keys()
    for name, fa in a.features.items():
        fb = b.features[name]
        assert fa.kind == fb.kind
        np.testing.assert_allclose(fa.location, fb.location, atol=tolerance, err_msg=name)
        if fb.vector is not None:
            np.testing.assert_allclose(fa.vector, fb.vector, atol=tolerance, err_msg=name)
        if fb.size is not None:
            assert fa.size == pytest.approx(fb.size, abs=tolerance), name


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_golden_fanuc_programs(case: Case, posted: dict[str, PostOutput]) -> None:
    out = posted[case.name]
    assert_golden(GOLDEN / f"{case.name}.nc", out.text)
    assert out.fmap.text == case.program.read_text()  # nothing dropped
    # the DMIS text itself stays in ../shared/ref (references are read in place)
    summary = replace(out.fmap, text=f"(the DMIS program, {len(out.fmap.text)} characters)")
    assert_golden(GOLDEN / f"{case.name}.features.json", dumps(summary))


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_nist_program_on_the_virtual_machine(case: Case, posted: dict[str, PostOutput]) -> None:
    result, cmm = run_both(case, posted[case.name])
    expected = {"simple_in": {"A_CIRCLE"},
                "IMTS_M_clean": {"PLN1", "PLN2", "PLN3", "CLIN1", "CPNT1", "CYL1", "CYL2"}}
    assert set(result.features) == expected[case.name]
    nominal = {name: result.nominals[name] for name in result.features}
    assert_same(DmisRunResult("", nominal, {}, {}, None, ()), result, 1e-4)
    assert_same(result, cmm, 1e-6)
    assert result.output == cmm.output  # the same DMIS output file, tolerances included
    assert all(t.in_tolerance for t in result.tolerances.values())


def test_displaced_part_still_measures(posted: dict[str, PostOutput]) -> None:
    """The DCX 0.3 mm off in X and Y, 0.1 mm in Z: frames on the measured datums put the
    CMM's later touches elsewhere than the posted program's nominal ones; on this exact
    model the features agree to the log's rounding."""
    result, cmm = run_both(DCX, posted[DCX.name], shift=(0.3, -0.3, 0.1))
    assert_same(result, cmm, 2e-4)
    assert result.features["CYL1"].location[0] == pytest.approx(355.3, abs=2e-4)


def test_machine_errors_and_lobing_agree_with_the_cmm(posted: dict[str, PostOutput]) -> None:
    """With the sample's 21 geometric errors and a lobing probe both machines measure the
    DCX some micrometres off nominal, and the same: to the log's rounding."""
    kinematics = load_machine(REPO / "samples/machines/errors-example.toml")
    result, cmm = run_both(DCX, posted[DCX.name], kinematics=kinematics,
                           lobing=Lobing(0.0012, 0.0008, 0.0005))
    assert_same(result, cmm, 2e-4)
    off = result.features["CYL2"].location[0] - result.nominals["CYL2"].location[0]
    assert abs(off) > 1e-3  # the errors are seen


def test_colliding_goto_names_its_line(machine) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(CollisionError, match=r"IMTS_M_clean.dmi:50: PTMEAS/CART,-50.000,"
                       r".*--reroute lifts"):
        post_file(DCX.program, machine, cad.load_part(DCX.model), dialect="fanuc",
                  offset=DCX.offset)


def test_rerouted_move_is_lifted(posted: dict[str, PostOutput]) -> None:
    out = posted[DCX.name]
    assert out.posted.rerouted == (50,)
    lines = out.text.splitlines()
    at = lines.index("(L50 REROUTED OVER THE CLEARANCE PLANE)")
    up, across, down = lines[at + 1 : at + 4], lines[at + 10], lines[at + 11 : at + 14]
    assert up == ["#190=398.0000", "#191=56.0000", "#192=100.0000"]  # straight up
    assert across == "G0 X305.0000 Y66.0000 Z100.0000"  # over the clearance plane
    assert down == ["#190=305.0000", "#191=66.0000", "#192=-44.0000"]  # down to PTMEAS 50


PROGRAM = """DMISMN/'T'
UNITS/MM,ANGDEC
S(P)=SNSDEF/PROBE,FIXED,CART,0,0,30,0,0,-1,{ball}
SNSLCT/S(P)
SNSET/APPRCH,10.0
SNSET/SEARCH,10.0
GOTO/50.0,50.0,75.0
F(C)=FEAT/CIRCLE,INNER,CART,50.0,50.0,40.0,0.0,0.0,1.0,50.0
{extra}
MEAS/CIRCLE,F(C),4
GOTO/50.0,50.0,40.0
PTMEAS/CART,75.0,50.0,40.0,-1.0,0.0,0.0
PTMEAS/CART,25.0,50.0,40.0,1.0,0.0,0.0
PTMEAS/CART,50.0,75.0,40.0,0.0,-1.0,0.0
PTMEAS/CART,50.0,25.0,40.0,0.0,1.0,0.0
GOTO/50.0,50.0,40.0
ENDMES
GOTO/50.0,50.0,100.0
OUTPUT/FA(C)
ENDFIL
"""


ELLIPSE = "F(T1)=FEAT/ELLIPS,INNER,CART,0,0,0,0,0,1,20,10,1,0,0"


def test_unsupported_statement_names_its_line(machine) -> None:  # type: ignore[no-untyped-def]
    text = PROGRAM.format(ball=4.0, extra=ELLIPSE)
    with pytest.raises(UnsupportedError, match=r"<t>:9: cannot post-process FEAT"):
        post_dmis(parse_dmis(text, source="<t>"), machine)
    out = post_dmis(parse_dmis(text, source="<t>"), machine, skip_unsupported=True)
    assert [s.line for s in out.skipped] == [9]
    assert len(out.touches) == 4


def test_sensor_must_be_the_machines(machine) -> None:  # type: ignore[no-untyped-def]
    """A D6 sensor on a D4 machine: refused; skipped, the program probes and the
    evaluation compensates with the machine's stylus, so the circle is still right."""
    text = PROGRAM.format(ball=6.0, extra="")
    with pytest.raises(UnsupportedError, match=r"<t>:4: .*D6 mm, the machine's stylus D4"):
        post_dmis(parse_dmis(text, source="<t>"), machine)
    posted = post_dmis(parse_dmis(text, source="<t>"), machine, skip_unsupported=True)
    assert posted.dropped_lines == (4,)
    nc = get_dialect("fanuc").generate(posted.program)
    assert "(L4 SKIPPED SNSLCT/S P : THE SENSOR" in nc
    fmap = feature_map(posted, text, "t.dmi", "fanuc")
    assert "$$ (left out by probegen post) SNSLCT/S(P)" in fmap.text
    model = cad.load_step(SIMPLE.model)
    vm = VirtualMachine(PlacedPart.from_model(model), ProbeModel(2.0))
    res = run_text(nc, vm, kind="macrob")
    assert res.alarm is None
    result = evaluate_log(parse_dprnt(res.output), fmap)
    assert result.features["C"].size == pytest.approx(50.0, abs=1e-9)


def test_log_that_does_not_belong_is_refused(posted: dict[str, PostOutput]) -> None:
    fmap = posted[SIMPLE.name].fmap
    good = ("PGSTART O1001 V1\nPT ACIRCLE 1 X73.0000 Y50.0000 Z40.0000\n"
            "PT ACIRCLE 2 X27.0000 Y50.0000 Z40.0000\nPT ACIRCLE 3 X50.0000 Y73.0000 Z40.0000\n")
    with pytest.raises(ResultsParseError, match=r"no PT ACIRCLE 4 in the log \(feature "
                       r"A_CIRCLE, DMIS line 28\)"):
        evaluate_log(parse_dprnt(good + "PGEND O1001\n"), fmap)
    off = good + "PT ACIRCLE 4 X50.5000 Y27.0000 Z40.0000\nPGEND O1001\n"
    with pytest.raises(ResultsParseError, match=r"PT ACIRCLE 4 \(DMIS line 28\) .* 0.5000 mm "
                       r"off its probing line"):
        evaluate_log(parse_dprnt(off), fmap)
    result = evaluate_log(parse_dprnt(off.replace("X50.5000", "X50.0000")), fmap)
    assert result.features["A_CIRCLE"].size == pytest.approx(50.0, abs=1e-9)


def test_feature_map_errors_name_the_key(tmp_path: Path,
                                         posted: dict[str, PostOutput]) -> None:
    path = tmp_path / "m.features.json"
    text = dumps(posted[SIMPLE.name].fmap)
    path.write_text(text.replace('"reach": 20.0', '"reach": "far"', 1))
    with pytest.raises(ResultsParseError, match=r"key 'touches\[0\].reach': expected a "
                       r"finite number|key 'touches\[0\].reach': expected"):
        read_feature_map(path)
    path.write_text(text[:-20])
    with pytest.raises(ResultsParseError, match=r"m.features.json:\d+:\d+: expected the JSON "
                       "feature map that probegen post wrote, found invalid JSON"):
        read_feature_map(path)
    path.write_text(text)
    assert read_feature_map(path) == posted[SIMPLE.name].fmap


def test_cli_post_sim_post_ingest(tmp_path: Path) -> None:
    nc, log, dmo = tmp_path / "simple.nc", tmp_path / "run.log", tmp_path / "simple.dmo"
    assert main(["post", str(SIMPLE.program), "--machine", str(MACHINE), "--model",
                 str(SIMPLE.model), "-o", str(nc)]) == ExitCode.OK
    assert (tmp_path / "simple.features.json").exists()
    assert main(["sim", str(nc), "--part", str(SIMPLE.model), "--machine", str(MACHINE),
                 "-o", str(log)]) == ExitCode.OK
    assert main(["post-ingest", str(log), "--features",
                 str(tmp_path / "simple.features.json"), "-o", str(dmo)]) == ExitCode.OK
    assert dmo.read_text() == (NIST / "IPlusSimplePart/DMIS/output.dms").read_text()
    assert main(["post", str(DCX.program), "--machine", str(MACHINE), "--model",
                 str(DCX.model), "--model-offset", "355", "91", "-80", "-o",
                 str(tmp_path / "dcx.nc")]) == ExitCode.PLANNING


def test_a_move_under_the_part_meets_the_table_unless_it_is_raised(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A GOTO down beside the simple part (100 x 100 x 50, its bottom at z = 0) to
    z = -5: clear of the part, into the table it stands on (refused, naming the table and
    the line); with ``--raised 10`` (parallels) the table is 10 mm below: posted."""
    down = ("GOTO/-20.0,50.0,75.0\nGOTO/-20.0,50.0,-5.0\nGOTO/-20.0,50.0,75.0\n"
            "GOTO/50.0,50.0,75.0")
    program = tmp_path / "under.dmi"
    program.write_text(PROGRAM.format(ball=4.0, extra=down))
    args = ["post", str(program), "--machine", str(MACHINE), "--model", str(SIMPLE.model),
            "-o", str(tmp_path / "under.nc")]
    assert main(args) == ExitCode.PLANNING
    err = capsys.readouterr().err
    assert "under.dmi:10: GOTO/-20.0,50.0,-5.0: " in err, err
    assert "the stylus ball cuts 7.000 mm into the table; expected a clearance of at least " \
        "0.250 mm (the move ends too near the table or under it, whatever the route: " \
        "--raised says how far the part stands above it)" in err, err
    assert main([*args, "--raised", "10"]) == ExitCode.OK


# ------------------------------------------------------------------ property tests

PROFILE = load_profile(MACHINE)
TEXTS = [SIMPLE.program.read_text(), DCX.program.read_text(), PROGRAM.format(ball=4, extra="")]
ALPHABET = "ACDEFGILMNOPRSTUXYZ0123456789.,-+/=()$' \n"


@settings(max_examples=examples(150), suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_mutated_dmis_posts_or_fails_cleanly(data: st.DataObject) -> None:
    source = data.draw(st.sampled_from(TEXTS))
    text = data.draw(st.composite(lambda draw: mutate(draw, source, ALPHABET))())
    skip = data.draw(st.booleans())
    try:
        out = post_dmis(parse_dmis(text, source="<m>"), PROFILE, skip_unsupported=skip)
    except ProbegenError:
        return
    get_dialect("fanuc").generate(out.program)


@settings(max_examples=examples(60))
@given(st.text(ALPHABET, max_size=200))
def test_random_dmis_posts_or_fails_cleanly(text: str) -> None:
    try:
        post_dmis(parse_dmis(text, source="<r>"), PROFILE)
    except ProbegenError:
        return


SIMPLE_MAP = dumps(feature_map(post_dmis(parse_dmis(TEXTS[0]), PROFILE), TEXTS[0],
                               "simple_in.dms", "fanuc"))
SIMPLE_LOG = ("PGSTART O1001 V1\nPT ACIRCLE 1 X73.0000 Y50.0000 Z40.0000\n"
              "PT ACIRCLE 2 X27.0000 Y50.0000 Z40.0000\nPT ACIRCLE 3 X50.0000 Y73.0000 Z40.0000\n"
              "PT ACIRCLE 4 X50.0000 Y27.0000 Z40.0000\nPGEND O1001\n")


@settings(max_examples=examples(150), suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_mutated_feature_map_and_log_evaluate_or_fail_cleanly(data: st.DataObject) -> None:
    fmap_text = SIMPLE_MAP
    log, which = SIMPLE_LOG, data.draw(st.sampled_from(["map", "log", "both"]))
    if which != "log":
        fmap_text = data.draw(st.composite(lambda d: mutate(d, fmap_text, ALPHABET + '"[]{}:'))())
    if which != "map":
        log = data.draw(st.composite(lambda d: mutate(d, log, ALPHABET))())
    try:
        fmap = parse_feature_map(fmap_text, source="<map>")
        parse_dmis(fmap.text, source=fmap.source)
        evaluate_log(parse_dprnt(log), fmap)
    except ProbegenError:
        return


# ------------------------------------------------------------------------ LinuxCNC


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_linuxcnc_post_runs_in_rs274(case: Case, rs274: str,  # noqa: F811
                                     tmp_path: Path) -> None:
    """The LinuxCNC program of each NIST post: LinuxCNC's own interpreter runs it, along
    the path the IR asks for (see test_linuxcnc: rs274 has no probe)."""
    out = post_file(case.program, PROFILE, cad.load_part(case.model), dialect="linuxcnc",
                    offset=case.offset, reroute=case.reroute)
    run = run_rs274(rs274, out.text, tmp_path)
    assert run.returncode == 0, run.output[-2000:]
    expected = Standalone(out.posted.program.setup).run(out.posted.program).path
    actual = motions(run)
    assert [m[0] for m in actual] == [m[0] for m in expected]
    for number, (got, want) in enumerate(zip(actual, expected, strict=True), start=1):
        assert_close(got[1], want[1], f"motion {number} ({got[0]})")


def test_cli_lists_skipped_statements(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    program = tmp_path / "ellipse.dmi"
    program.write_text(PROGRAM.format(ball=4.0, extra=ELLIPSE))
    args = ["post", str(program), "--machine", str(MACHINE), "--model", str(SIMPLE.model),
            "-o", str(tmp_path / "ellipse.nc")]
    assert main(args) == ExitCode.UNSUPPORTED
    assert f"{program}:9: cannot post-process FEAT" in capsys.readouterr().err
    assert main([*args, "--skip-unsupported"]) == ExitCode.OK
    assert f"probegen: skipped {program}:9: F(T1)=FEAT/ELLIPS" in capsys.readouterr().err
    assert "(L9 SKIPPED F T1 =FEAT/ELLIPS," in (tmp_path / "ellipse.nc").read_text()
    assert main(["post", str(program), "--machine", str(MACHINE), "--model",
                 str(SIMPLE.model), "-d", "dmis", "-o", str(tmp_path)]) == ExitCode.UNSUPPORTED


def test_evaluation_loads_neither_jinja2_nor_ocp_nor_the_simulator() -> None:
    """post-ingest runs the DMIS interpreter (``sim.cmm``) but not the virtual machine."""
    code = ("import sys, probegen.post.evaluate; print(sorted(m for m in ('jinja2', 'OCP', "
            "'probegen.sim.vm', 'probegen.sim.contact', 'probegen.sim.macrob', "
            "'probegen.planning', 'probegen.dialects') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=REPO)
    assert out.stdout.strip() == "[]"


SPHERE_PROGRAM = """DMISMN/'SPHERE ON A STEM'
UNITS/{units},ANGDEC
D(M)=DATSET/MCS
S(P)=SNSDEF/PROBE,FIXED,CART,0,0,30,0,0,-1,{ball}
SNSLCT/S(P)
SNSET/APPRCH,{a}
SNSET/SEARCH,{a}
SNSET/RETRCT,{a}
GOTO/0,0,{high}
F(S1)=FEAT/SPHERE,OUTER,CART,0,0,0,{d}
MEAS/SPHERE,F(S1),5
PTMEAS/CART,0,0,{r},0,0,1
GOTO/{side},0,{high}
PTMEAS/CART,{r},0,0,1,0,0
GOTO/{side},{side},0
PTMEAS/CART,0,{r},0,0,1,0
GOTO/-{side},{side},0
PTMEAS/CART,-{r},0,0,-1,0,0
GOTO/-{side},-{side},0
PTMEAS/CART,0,-{r},0,0,-1,0
GOTO/0,-{side},{high}
ENDMES
OUTPUT/FA(S1)
ENDFIL
"""


@pytest.mark.parametrize("units", ["MM", "INCH"])
def test_sphere_in_mm_and_inch(units: str, tmp_path: Path) -> None:
    """A SPHERE measured on the sample sphere: the inch program (every length / 25.4)
    gives the same touches and the same sphere in mm."""
    k = 25.4 if units == "INCH" else 1.0
    values = {"ball": 4.0, "a": 3.0, "high": 30.0, "side": 20.0, "r": 12.5, "d": 25.0}
    text = SPHERE_PROGRAM.format(units=units, **{key: repr(v / k) for key, v in values.items()})
    program = tmp_path / "sphere.dmi"
    program.write_text(text)
    case = Case("sphere", program, REPO / "samples/sphere25/sphere25.step", (0.0, 0.0, 0.0),
                (0.0, 0.0, 100.0), False)
    out = post_file(program, PROFILE, cad.load_part(case.model), dialect="fanuc")
    assert len(out.fmap.touches) == 5
    result, cmm = run_both(case, out)
    sphere = result.features["S1"]
    np.testing.assert_allclose(sphere.location, (0.0, 0.0, 0.0), atol=1e-4)
    assert sphere.size == pytest.approx(25.0, abs=1e-4)
    assert_same(result, cmm, 1e-6)


BALL_PROGRAM = """DMISMN/'THROUGH'
UNITS/MM,ANGDEC
GOTO/-30,0,0
GOTO/30,0,0
F(T1)=FEAT/ELLIPS,INNER,CART,0,0,0,0,0,1,20,10,1,0,0
MEAS/ELLIPS,F(T1),1
PTMEAS/CART,25,0,0,1,0,0
ENDMES
ENDFIL
"""


def test_reroute_lifts_over_the_clearance_plane() -> None:
    """A GOTO straight through a sphere: an error naming the line; with reroute, up to
    the clearance plane (100), across and down, every segment checked; a FEAT the post
    cannot execute is skipped with --skip-unsupported, but the MEAS of it, a measuring
    move, is refused even then (issue 18: the flag never leaves out a measuring move)."""
    ball = SphereObstacle(np.zeros((1, 3)), np.array([12.5]))
    parsed = parse_dmis(BALL_PROGRAM, source="<b>")
    with pytest.raises(CollisionError, match=r"<b>:4: GOTO/30,0,0: .*cuts .* into sphere 1"):
        post_dmis(parsed, PROFILE, obstacle=ball, skip_unsupported=True)
    with pytest.raises(UnsupportedError, match=r"<b>:6: cannot post-process MEAS .*ELLIPS.*"
                                               r"\(a measuring move is never skipped"):
        post_dmis(parsed, PROFILE, obstacle=ball, skip_unsupported=True, reroute=True)
    without_meas = "\n".join(BALL_PROGRAM.splitlines()[:5] + ["ENDFIL"]) + "\n"
    out = post_dmis(parse_dmis(without_meas, source="<b>"), PROFILE, obstacle=ball,
                    skip_unsupported=True, reroute=True)
    assert out.rerouted == (4,)
    moves = [(n.target, n.mode.value) for n in out.program.body if isinstance(n, ir.Move)]
    assert moves == [((-30.0, 0.0, 100.0), "rapid"), ((-30.0, 0.0, 0.0), "protected"),
                     ((-30.0, 0.0, 100.0), "protected"), ((30.0, 0.0, 100.0), "rapid"),
                     ((30.0, 0.0, 0.0), "protected"), ((30.0, 0.0, 100.0), "protected")]
    assert [s.line for s in out.skipped] == [5]
    assert out.touches == () and out.move_clearance > 0.0


def test_post_ingest_checks_the_identity(tmp_path: Path, posted: dict[str, PostOutput],
                                         capsys: pytest.CaptureFixture[str]) -> None:
    out = posted[SIMPLE.name]
    identity = map_identity(out.fmap.text, out.fmap.touches)
    assert f"DPRNT[PGSTART*O1001*V1*{identity}]" in out.text.splitlines()
    features = tmp_path / "simple.features.json"
    features.write_text(dumps(out.fmap))
    log = tmp_path / "run.log"
    log.write_text(SIMPLE_LOG.replace("V1\n", f"V1 {identity}\n", 1))
    _, result, notes = ingest_file(log, features)
    assert notes == () and result.features["A_CIRCLE"].size == pytest.approx(50.0, abs=1e-9)
    log.write_text(SIMPLE_LOG.replace("V1\n", "V1 H0000BEEF\n", 1))
    with pytest.raises(ProbegenError, match=f"run.log:1: expected the program of the spec, "
                                            f"O1001 {identity}, found O1001 H0000BEEF"):
        ingest_file(log, features)
    assert main(["post-ingest", str(log), "--features", str(features), "-o",
                 str(tmp_path / "r.dmo"), "--ignore-identity"]) == ExitCode.OK
    assert "note: WARNING: identity not checked" in capsys.readouterr().out
    log.write_text(SIMPLE_LOG)  # a log from before identities
    assert ingest_file(log, features)[2][0].startswith("log carries no program identity")
