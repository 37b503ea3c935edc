"""Named setups (issue 17, item 2): a block built here with build123d, a bore on top and a
face-down bore on the bottom, on the five-axis sample profile plus a ``FLIPPED`` setup
(the part turned over about X).  No tilt of the trunnion reaches the face-down bore (180
deg, beyond +-110): it is measured in the setup.  Compile gives two programs (golden),
both run on the virtual machine with the part placed as each setup says and a planted
offset, the two logs ingested together recover both bores in part coordinates."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, assert_golden
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen.cli.app import main
from probegen.errors import ExitCode, PlanningError, SpecError
from probegen.ir import frames
from probegen.planning import part_of
from probegen.planning.setups import (
    AS_LOADED,
    SetupProgram,
    header_comments,
    plan_setups,
    program_name,
    setup_file,
    setup_hint,
    split_setups,
    transpose,
)
from probegen.spec.model import load_spec

GOLDEN = REPO / "tests" / "golden" / "setups"
FIVE = REPO / "samples" / "machines" / "vmc-5axis-fanuc.toml"
FLIPPED = '''
[[setup]]
name = "FLIPPED"
rotation = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]
note = "part turned over about X, top face on the table"
'''
SPEC = '''[part]
model = "part.step"

[machine]
profile = "{profile}"
clearance_z = 60.0

[program]
number = 1001
name = "TWO BORES"

[[feature]]
id = "TOP"
kind = "cylinder"
at = [24.0, 30.0, 35.0]          # the D12 bore from the top, 15 deep
tolerance = {{ diameter = [-0.01, 0.01], position = 0.02 }}

[[feature]]
id = "BOTTOM"
kind = "cylinder"
at = [65.0, 30.0, 5.0]           # the D10 bore from the bottom, 15 deep: faces down
tolerance = {{ diameter = [-0.01, 0.01], position = 0.02 }}
{extra}'''
OFFSET = np.array([0.004, -0.003, 0.002])


def five_without_setups() -> str:
    """The five-axis sample profile's text without its ``[[setup]]`` block (the sample
    declares ``FLIPPED``, with a note of its own): the tests add their own setups."""
    text = FIVE.read_text(encoding="utf-8")
    start = text.index("# The setups the operator may turn the part into")
    end = text.index("[feeds]", start)
    assert "[[setup]]" in text[start:end] and "[[setup]]" not in text[end:]
    return text[:start] + text[end:]
"""Where the part really lies on the table, off its nominal place (table frame), mm."""


def block(path: Path) -> Path:
    """A 100 x 60 x 40 block (corner at the origin) with a D12 bore 15 deep from the top
    at (30, 30) and a D10 bore 15 deep from the bottom at (70, 30)."""
    from build123d import Align, Box, Cylinder, Pos, export_step

    shape = Box(100, 60, 40, align=(Align.MIN, Align.MIN, Align.MIN))
    shape = shape - Pos(30, 30, 40) * Cylinder(6, 30) - Pos(70, 30, 0) * Cylinder(5, 30)
    export_step(shape, str(path))
    return path


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The part, the five-axis profile with and without the FLIPPED setup, and a spec on
    each (``spec.toml``, ``nosetup.toml``)."""
    tmp = tmp_path_factory.mktemp("setups")
    block(tmp / "part.step")
    base = five_without_setups()
    (tmp / "five.toml").write_text(base + FLIPPED, encoding="utf-8")
    (tmp / "five0.toml").write_text(base, encoding="utf-8")
    (tmp / "spec.toml").write_text(SPEC.format(profile="five.toml", extra=""),
                                   encoding="utf-8")
    (tmp / "nosetup.toml").write_text(SPEC.format(profile="five0.toml", extra=""),
                                      encoding="utf-8")
    return tmp


@pytest.fixture(scope="module")
def compiled(folder: Path) -> Path:
    out = folder / "out"
    assert main(["-q", "compile", str(folder / "spec.toml"), "-o", f"{out}/"]) == ExitCode.OK
    return out


def test_each_feature_goes_to_the_first_setup_that_reaches_it(folder: Path) -> None:
    spec = load_spec(folder / "spec.toml")
    programs = split_setups(spec, part_of(spec))
    assert [(p.name, p.features, p.spec.program_number, p.spec.program_name)
            for p in programs] == [(AS_LOADED, ("TOP",), 1001, "TWO BORES"),
                                   ("FLIPPED", ("BOTTOM",), 1002, "TWO BORES FLIPPED")]
    flipped = programs[1]
    # the point of the spec turned into the table frame: R·at (y and z change sign)
    assert flipped.spec.features[0].at == (65.0, -30.0, -5.0)
    # the turned part lies below the table zero (z from -40 to 0), its clearance plane is
    # as far above it as the spec's is above the part as loaded (60 - 40)
    assert flipped.part is not None
    assert flipped.part.bbox_max[2] == pytest.approx(0.0, abs=1e-6)
    assert flipped.spec.clearance_z == pytest.approx(20.0, abs=1e-6)
    assert flipped.to_part((70.0, -30.0, -7.5)) == pytest.approx((70.0, 30.0, 7.5))


def test_a_spec_forces_a_setup_and_an_unknown_one_is_refused(folder: Path) -> None:
    spec_path = folder / "forced.toml"
    text = SPEC.format(profile="five.toml", extra="").replace(
        'at = [24.0, 30.0, 35.0]          # the D12 bore from the top, 15 deep',
        'at = [24.0, 30.0, 35.0]\nsetup = "FLIPPED"')
    spec_path.write_text(text, encoding="utf-8")
    spec = load_spec(spec_path)
    assert [f.setup for f in spec.features] == ["FLIPPED", None]  # type: ignore[union-attr]
    spec_path.write_text(text.replace('setup = "FLIPPED"', 'setup = "FLIPED"'),
                         encoding="utf-8")
    with pytest.raises(SpecError, match=r"feature\[0\]\.setup: expected a setup of the "
                                        r"machine profile \(FLIPPED; .*five\.toml: "
                                        r"\[\[setup\]\]\), found 'FLIPED' \(did you mean "
                                        r"'FLIPPED'\?\)"):
        load_spec(spec_path)


def test_a_setup_with_an_origin_is_refused(folder: Path) -> None:
    base = five_without_setups()
    (folder / "five_origin.toml").write_text(
        base + FLIPPED + "origin = [0.0, 60.0, 40.0]\n", encoding="utf-8")
    (folder / "origin.toml").write_text(SPEC.format(profile="five_origin.toml", extra=""),
                                        encoding="utf-8")
    spec = load_spec(folder / "origin.toml")
    with pytest.raises(SpecError, match=r"setup\[0\]\.origin: expected \[0, 0, 0\] .*found "
                                        r"\[0, 60, 40\] in setup FLIPPED"):
        split_setups(spec, part_of(spec))


def test_compile_writes_one_program_per_setup(compiled: Path) -> None:
    assert sorted(p.name for p in compiled.glob("spec*.nc")) == ["spec.nc",
                                                                 "spec_FLIPPED.nc"]
    for name in ("spec.nc", "spec_FLIPPED.nc"):
        assert_golden(GOLDEN / name, (compiled / name).read_text(encoding="ascii"))
    text = (compiled / "spec_FLIPPED.nc").read_text(encoding="ascii")
    assert "O1002(TWO BORES FLIPPED)" in text
    assert "(TURN THE PART: PART TURNED OVER ABOUT X, TOP FACE ON THE TABLE)" in text
    assert "(PART TO TABLE: EULER ZXZ I0 J180 K0)" in text


def test_header_comments_fit_a_fanuc_block(folder: Path) -> None:
    spec = load_spec(folder / "spec.toml")
    programs = split_setups(spec, part_of(spec))
    for p in programs:
        for c in header_comments(p, programs):
            assert len(c.text) <= 72 and c.text == c.text.upper()
            assert "(" not in c.text and ")" not in c.text


def test_both_programs_run_and_recover_both_bores_in_part_coordinates(
        folder: Path, compiled: Path) -> None:
    """The part turned as each setup says and off by OFFSET (table frame): each bore's
    centre comes back in part coordinates off by Rᵀ·OFFSET, to 1 um."""
    spec = str(folder / "spec.toml")
    logs = {}
    for name, setup in (("spec.nc", None), ("spec_FLIPPED.nc", "FLIPPED")):
        log = folder / f"{name}.log"
        args = ["-q", "sim", str(compiled / name), "--spec", spec, "-o", str(log),
                "--offset", *(str(v) for v in OFFSET)]
        assert main(args + (["--setup", setup] if setup else [])) == 0
        logs[name] = log
    out = folder / "both"
    assert main(["-q", "ingest", str(logs["spec.nc"]), str(logs["spec_FLIPPED.nc"]),
                 "--spec", spec, "-o", str(out)]) == ExitCode.OK
    results = json.loads((out / "results.json").read_text(encoding="utf-8"))
    got = {f["id"]: {c["name"]: c for c in f["characteristics"]} for f in results["features"]}
    assert list(got) == ["TOP", "BOTTOM"]
    truth = {"TOP": OFFSET, "BOTTOM": np.asarray(frames.apply_t(frames.FLIP_X,
                                                                tuple(OFFSET)))}
    nominal = {"TOP": (30.0, 30.0, 12.0), "BOTTOM": (70.0, 30.0, 10.0)}
    for fid, shift in truth.items():
        c = got[fid]
        for axis, k in (("X", 0), ("Y", 1)):
            assert c[axis]["deviation"] == pytest.approx(shift[k], abs=0.001), (fid, axis)
        assert c["D"]["measured"] == pytest.approx(nominal[fid][2], abs=0.001)
    # the bottom bore's y comes back with the sign of the part, not the table's
    assert got["BOTTOM"]["Y"]["measured"] == pytest.approx(30.0 + 0.003, abs=0.001)


def test_one_log_leaves_the_other_setups_feature_not_measured(
        folder: Path, compiled: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = str(folder / "spec.toml")
    log = folder / "flipped_only.log"
    assert main(["-q", "sim", str(compiled / "spec_FLIPPED.nc"), "--spec", spec, "-o",
                 str(log), "--setup", "FLIPPED"]) == 0
    out = folder / "one"
    code = main(["-q", "ingest", str(log), "--spec", spec, "-o", str(out)])
    assert code == ExitCode.INCOMPLETE
    text = capsys.readouterr().out
    assert ("TOP: NOT EVALUATED: not measured: no log of setup AS LOADED (program O1001) "
            "was given") in text
    results = json.loads((out / "results.json").read_text(encoding="utf-8"))
    status = {f["id"]: f["status"] for f in results["features"]}
    assert status["TOP"] == "NOT EVALUATED" and status["BOTTOM"] == "OK"


def test_a_log_of_another_program_is_refused(folder: Path, compiled: Path) -> None:
    log = folder / "other.log"
    log.write_text("%\nPGSTART O2001 V2 H00000000\nPGEND\n", encoding="ascii")
    assert main(["-q", "ingest", str(log), "--spec", str(folder / "spec.toml"), "-o",
                 str(folder / "x")]) != ExitCode.OK


def test_two_logs_of_one_program_are_refused(folder: Path, compiled: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    spec = str(folder / "spec.toml")
    logs = []
    for k in (1, 2):
        log = folder / f"top_{k}.log"
        assert main(["-q", "sim", str(compiled / "spec.nc"), "--spec", spec, "-o",
                     str(log)]) == 0
        logs.append(str(log))
    code = main(["-q", "ingest", *logs, "--spec", spec, "-o", str(folder / "twice")])
    assert code != ExitCode.OK
    assert (f"{logs[1]}: expected one log per setup program, found a second log of O1001 "
            f"(setup AS LOADED; the first: {logs[0]})") in capsys.readouterr().err


def test_the_setup_of_sim_must_be_known(folder: Path, compiled: Path) -> None:
    assert main(["-q", "sim", str(compiled / "spec_FLIPPED.nc"), "--spec",
                 str(folder / "spec.toml"), "--setup", "SIDE"]) == ExitCode.SPEC


def test_without_a_setup_the_face_down_bore_asks_for_one(folder: Path) -> None:
    spec = load_spec(folder / "nosetup.toml")
    with pytest.raises(PlanningError, match=r"feature\[1\]: tilt 180\.0 deg: beyond the A "
                                            r"axis's range -110\.\.110: needs a setup: add a "
                                            r"\[\[setup\]\] to the machine profile$"):
        plan_setups(spec, runtime_variables=True, part=part_of(spec))


def test_a_profile_without_setups_plans_one_program_as_before(folder: Path) -> None:
    """The same spec without the bottom bore on the profile without setups: one program,
    the spec itself, no setup header."""
    from probegen.planning import plan_program

    spec = load_spec(folder / "nosetup.toml")
    from dataclasses import replace

    spec = replace(spec, features=spec.features[:1])
    part = part_of(spec)
    (only, planned), = plan_setups(spec, runtime_variables=True, part=part)
    assert only.spec is spec and only.setup is None
    assert planned.program == plan_program(spec, runtime_variables=True, part=part).program


def test_plan_all_revolved_writes_one_program_per_setup(
        folder: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = folder / "allrev"
    assert main(["plan", "--all-revolved", str(folder / "part.step"), "--machine",
                 str(folder / "five.toml"), "-d", "fanuc", "-o", str(out)]) == ExitCode.OK
    text = capsys.readouterr().out
    rows = [line.split() for line in text.splitlines() if line.startswith("R")]
    assert [(r[0], r[-1]) for r in rows] == [("R1", "LOADED"), ("R2", "FLIPPED")]
    assert "wrote " + str(out / "part_FLIPPED.nc") + " (setup FLIPPED: R2)" in text
    assert sorted(p.name for p in out.iterdir()) == ["part.nc", "part_FLIPPED.nc",
                                                     "part_all_revolved.toml"]
    assert "wrote " + str(out / "part_all_revolved.toml") + " (the spec of these" in text


def test_small_helpers() -> None:
    r = frames.from_euler_zxz(30.0, 60.0, -45.0)
    assert np.allclose(np.asarray(transpose(r)) @ np.asarray(r), np.eye(3))
    sp = SetupProgram(None, 0, None, None)  # type: ignore[arg-type]
    assert setup_file("a/b.nc", sp, True) == "a/b.nc"
    from probegen.machine.profile import NamedSetup

    flipped = SetupProgram(NamedSetup("FLIPPED", frames.FLIP_X), 1, None, None)  # type: ignore[arg-type]
    assert setup_file("a/b.nc", flipped, False) == str(Path("a/b_FLIPPED.nc"))
    spec = type("S", (), {"program_name": "A VERY LONG PROGRAM NAME"})()
    assert program_name(spec, NamedSetup("UPSIDE_DOWN_SIDE", frames.FLIP_X)) == \
        "A VERY UPSIDE_DOWN_SIDE"  # type: ignore[arg-type]
    assert setup_hint("x: needs a setup [detail]", type("M", (), {"setups": ()})()) == \
        "x: needs a setup: add a [[setup]] to the machine profile [detail]"  # type: ignore[arg-type]
    assert setup_hint("x: a smaller stylus", type("M", (), {"setups": ()})()) == \
        "x: a smaller stylus"  # type: ignore[arg-type]


SIDE = '''
[[setup]]
name = "SIDE"
euler_zxz = [0.0, 90.0, 0.0]
note = "part on its side, bottom face towards +Y"
'''


def test_a_setup_feature_may_need_a_tilt_too(folder: Path) -> None:
    """The part on its side (R = Rx(90 deg)): the face-down bore now faces +Y in the table
    frame, reached by the trunnion tilted 90 deg.  Planned in that frame on the setup's
    part turned further; a log of exact touches (frame coordinates, as the control prints
    them under G68.2) ingests to the bore in part coordinates, the other setup's feature
    not measured."""
    from probegen import ir
    from probegen.evaluate.setups import ingest_setups
    from probegen.planning.identity import planned_touches

    (folder / "five_side.toml").write_text(five_without_setups() + SIDE,
                                           encoding="utf-8")
    (folder / "side.toml").write_text(SPEC.format(profile="five_side.toml", extra=""),
                                      encoding="utf-8")
    spec = load_spec(folder / "side.toml")
    part = part_of(spec)
    (_, _), (side, planned) = plan_setups(spec, runtime_variables=True, part=part)
    assert side.name == "SIDE" and side.features == ("BOTTOM",)
    (o,) = planned.oriented
    assert not o.orientation.identity and o.orientation.rotary[0] == ("A", 90.0)
    block_ = next(n for n, _ in frames.in_work(planned.program.body)
                  if isinstance(n, ir.FeatureBlock))
    assert side.to_part(block_.feature.centre) == pytest.approx((70.0, 30.0, 7.5))
    assert frames.apply_t(side.rotation, block_.feature.axis) == pytest.approx((0, 0, -1))
    # exact touches of the nominal bore, in the frame: 2 mm (bore radius 5 - ball 3) from
    # its axis along each search line
    frame_def = next(n for n in planned.program.body if isinstance(n, ir.FeatureBlock)).feature
    centre = np.asarray(frame_def.centre)
    lines = [f"PGSTART O{side.spec.program_number} V2 {planned.program.setup.identity}",
             "FEAT BOTTOM 1"]
    for t in planned_touches(planned.program, ()):
        start, end = np.asarray(t.start), np.asarray(t.end)
        u = (end - start) / np.linalg.norm(end - start)
        ball = np.array([centre[0], centre[1], start[2]]) + 2.0 * u
        lines.append(f"PT 1 {t.index} X{ball[0]:.4f} Y{ball[1]:.4f} Z{ball[2]:.4f}")
    log = folder / "side.log"
    log.write_text("%\n" + "\n".join([*lines, "PGEND"]) + "\n", encoding="ascii")
    ing = ingest_setups([log], spec, part=part)
    (bottom,) = ing.revolved
    assert bottom.feature == "BOTTOM"
    assert bottom.centre[:2] == pytest.approx((70.0, 30.0), abs=1e-4)
    assert bottom.diameter == pytest.approx(10.0, abs=1e-4)
    assert [n.feature for n in ing.not_evaluated] == ["TOP"]


def test_the_dmis_program_of_a_setup_runs_on_the_virtual_cmm(folder: Path) -> None:
    """The same spec to DMIS: two programs; the FLIPPED one on the virtual CMM with the
    part turned and off by OFFSET reports the bottom bore in the setup's (table) frame:
    R·(70, 30) + OFFSET."""
    from probegen.results import read_dmis_output

    out = folder / "dmis"
    spec = str(folder / "spec.toml")
    assert main(["-q", "compile", spec, "-d", "dmis", "-o", f"{out}/"]) == ExitCode.OK
    assert sorted(p.name for p in out.glob("*.dmi")) == ["spec.dmi", "spec_FLIPPED.dmi"]
    assert "$$ TURN THE PART: PART TURNED OVER ABOUT X" in (out / "spec_FLIPPED.dmi").read_text(
        encoding="ascii")
    output = out / "flipped.dms"
    assert main(["-q", "sim", str(out / "spec_FLIPPED.dmi"), "--spec", spec, "--setup",
                 "FLIPPED", "--offset", *(str(v) for v in OFFSET), "-o", str(output)]) == 0
    (fa,) = read_dmis_output(output).features
    assert fa.name == "BOTTOM"
    assert fa.position[:2] == pytest.approx((70.0 + OFFSET[0], -30.0 + OFFSET[1]), abs=1e-3)


@settings(max_examples=examples(60))
@given(lines=st.lists(st.one_of(
    st.sampled_from(["PGSTART O1001 V2 H00000000", "PGSTART O1002 V2 H00000000",
                     "PGSTART O1003", "PGEND", "PT 1 1 X1. Y2. Z3.", "%", ""]),
    st.text("PGSTARTO0123456789 VH\n*", max_size=30)), max_size=6),
    count=st.integers(1, 3))
def test_random_logs_pair_with_a_program_or_are_refused(lines: list[str], count: int) -> None:
    """Logs of random lines: each paired with the program whose number its PGSTART prints,
    or a ProbegenError naming the log."""
    import tempfile
    from types import SimpleNamespace

    from probegen.errors import ProbegenError
    from probegen.evaluate.setups import log_program, pair_logs

    programs = [SimpleNamespace(spec=SimpleNamespace(program_number=1001 + k),
                                name=f"S{k}") for k in range(2)]
    with tempfile.TemporaryDirectory() as tmp:
        logs = []
        for k in range(count):
            path = Path(tmp) / f"{k}.log"
            path.write_text("\n".join(lines[k:]) + "\n", encoding="ascii")
            logs.append(path)
        try:
            paired = pair_logs(logs, programs)  # type: ignore[arg-type]
        except ProbegenError as exc:
            assert any(str(log) in str(exc) for log in logs)
            return
        for k, log in paired.items():
            assert log_program(log) == 1001 + k
        assert len(set(paired.values())) == len(paired) == len(logs)


def test_a_spec_all_in_one_setup_ingests_in_part_coordinates(folder: Path,
                                                             compiled: Path) -> None:
    """Only the bottom bore, so the only program is the FLIPPED one (number 1002): its log
    alone is the whole result, in part coordinates."""
    from probegen.evaluate.setups import ingest_setups

    text = SPEC.format(profile="five.toml", extra="")
    (folder / "bottom.toml").write_text(text[:text.index('[[feature]]\nid = "TOP"')] +
                                        text[text.index('[[feature]]\nid = "BOTTOM"'):],
                                        encoding="utf-8")
    spec = load_spec(folder / "bottom.toml")
    (only,) = split_setups(spec, part_of(spec))
    assert only.name == "FLIPPED" and only.spec.program_number == 1002
    log = folder / "bottom_only.log"
    assert main(["-q", "sim", str(compiled / "spec_FLIPPED.nc"), "--spec",
                 str(folder / "bottom.toml"), "--setup", "FLIPPED", "-o", str(log)]) == 0
    (bottom,) = ingest_setups([log], spec).revolved
    assert bottom.centre[:2] == pytest.approx((70.0, 30.0), abs=1e-3)


ODD = REPO / "samples" / "parts" / "odd_angle.step"
SAMPLES = {"fanuc": FIVE, "dmis": REPO / "samples" / "machines" / "cmm.toml"}


@pytest.mark.parametrize("dialect", ["fanuc", "dmis"])
def test_the_sample_profiles_measure_a_face_down_hole_in_their_flipped_setup(
        tmp_path: Path, dialect: str) -> None:
    """``plan --all-revolved`` on odd_angle.step with each sample profile as is (its
    ``[[setup]]`` FLIPPED): the D12 hole that opens downwards at (50, 25) goes to the
    FLIPPED program (no head index nor tilt reaches it as loaded); both programs run on
    the virtual machine / CMM with the part turned as the setup says and off by OFFSET
    (table frame).  Five-axis: the logs ingested together give the hole in part
    coordinates, off by Rᵀ·OFFSET, to 1 µm; CMM: the CMM reports it in the setup's
    frame, at R·(50, 25) + OFFSET."""
    from probegen import cad
    from probegen.cli.plan import program_text
    from probegen.evaluate.setups import ingest_setups
    from probegen.machine.profile import load_profile
    from probegen.planning.setups import all_revolved_setups
    from probegen.results import read_dmis_output

    part = cad.load_part(ODD)
    spec, notes = all_revolved_setups(part, load_profile(SAMPLES[dialect]))
    setups = plan_setups(spec, runtime_variables=dialect == "fanuc", part=part)
    assert [(sp.name, sp.features) for sp, _ in setups][1] == ("FLIPPED", ("R2",))
    assert not any(n.startswith("R2 ") for n in notes)
    outputs = []
    for sp, planned in setups:
        program = tmp_path / f"{sp.name.replace(' ', '_')}.{'nc' if dialect == 'fanuc' else 'dmi'}"
        program.write_text(program_text(dialect, planned, notes), encoding="ascii")
        log = program.with_suffix(".log")
        args = ["-q", "sim", str(program), "--part", str(ODD), "--machine",
                str(SAMPLES[dialect]), "--offset", *(str(v) for v in OFFSET), "-o", str(log)]
        assert main(args + (["--setup", sp.name] if sp.setup else [])) == 0, sp.name
        outputs.append(log)
    if dialect == "dmis":
        (fa,) = read_dmis_output(outputs[1]).features
        assert fa.name == "R2"
        assert fa.position[:2] == pytest.approx((50.0 + OFFSET[0], -25.0 + OFFSET[1]),
                                                abs=1e-3)
        return
    got = {r.feature: r for r in ingest_setups(outputs, spec, part=part).revolved}
    shift = frames.apply_t(frames.FLIP_X, tuple(OFFSET))
    assert got["R2"].centre[:2] == pytest.approx((50.0 + shift[0], 25.0 + shift[1]),
                                                 abs=1e-3)
    assert got["R2"].diameter == pytest.approx(12.0, abs=1e-3)
