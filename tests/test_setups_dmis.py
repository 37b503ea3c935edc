"""DMIS outputs of setup programs in the part's frame (issue 17, item 2): each setup's
DMIS program run on the virtual CMM with the part turned as the setup says and off its
place, the outputs ingested together, every feature reported in part coordinates; a
mismatched output refused.  Also the cones of a setup program: every PTMEAS on the
model (benchmarks/points_on_model.py's check) and recovered on the virtual CMM and the
five-axis virtual machine."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen.cli.app import main
from probegen.errors import ExitCode, ProbegenError
from probegen.ir import frames

sys.path.insert(0, str(REPO / "benchmarks"))
from points_on_model import check_points  # noqa: E402  (the benchmark's own check)

CMM = REPO / "samples" / "machines" / "cmm.toml"
FIVE = REPO / "samples" / "machines" / "vmc-5axis-fanuc.toml"
ODD = REPO / "samples" / "parts" / "odd_angle.step"
OFFSET = np.array([0.004, -0.003, 0.002])
"""Where the part really lies on the table, off its nominal place (table frame), mm."""


def _run_all(tmp: Path, model: Path, profile: Path, dialect: str
             ) -> tuple[Any, Any, list[tuple[Any, Path, Path]]]:
    """``plan --all-revolved`` of ``model`` as the API gives it, each setup's program
    written and run on the virtual CMM / machine off by OFFSET: (part, spec, [(setup
    program, program file, output)])."""
    from probegen import cad
    from probegen.cli.plan import program_text
    from probegen.machine.profile import load_profile
    from probegen.planning.setups import all_revolved_setups, plan_setups

    part = cad.load_part(model)
    spec, notes = all_revolved_setups(part, load_profile(profile))
    setups = plan_setups(spec, runtime_variables=dialect == "fanuc", part=part)
    ext = {"fanuc": ".nc", "dmis": ".dmi"}[dialect]
    out = []
    for sp, planned in setups:
        program = tmp / f"{model.stem}_{sp.name.replace(' ', '_')}{ext}"
        program.write_text(program_text(dialect, planned, notes), encoding="ascii")
        output = program.with_suffix(".dms" if dialect == "dmis" else ".log")
        args = ["-q", "sim", str(program), "--part", str(model), "--machine", str(profile),
                "--offset", *(str(v) for v in OFFSET), "-o", str(output)]
        assert main(args + (["--setup", sp.name] if sp.setup else [])) == 0, sp.name
        out.append((sp, program, output))
    return part, spec, out


def _shift(sp: Any) -> np.ndarray:
    """OFFSET (table frame) in part coordinates for setup program ``sp``: Rᵀ·OFFSET."""
    return np.asarray(frames.apply_t(sp.rotation, tuple(OFFSET)))


def _across(v: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """``v`` square to ``axis``."""
    return v - (v @ axis) * axis


def _check_recovered(results: Any, runs: list[tuple[Any, Path, Path]], spec: Any) -> None:
    """Every feature of every setup: its centre off by Rᵀ·OFFSET square to its axis (in
    part coordinates), its size nominal, to 1 µm."""
    got = {r.feature: r for r in results.revolved}
    assert not results.not_evaluated
    assert sorted(got) == sorted(f.id for f in spec.features)
    for sp, _, _ in runs:
        for fid in sp.features:
            r = got[fid]
            dev = np.array([c.deviation for c in r.characteristics if c.name in "XYZ"])
            axis, shift = np.asarray(r.axis), _shift(sp)
            assert _across(dev, axis) == pytest.approx(_across(shift, axis), abs=1e-3), \
                (sp.name, fid)
            size = {c.name: c for c in r.characteristics}
            if "D" in size:
                assert size["D"].deviation == pytest.approx(0.0, abs=1e-3), (sp.name, fid)
            if "ANGLE" in size:
                assert size["ANGLE"].deviation == pytest.approx(0.0, abs=1e-3), fid


def test_odd_angle_dmis_outputs_ingest_in_part_coordinates(tmp_path: Path) -> None:
    """odd_angle.step on the CMM sample: R1, R3 as loaded (head indexed), R2 FLIPPED; the
    two outputs, given in either order, give every feature in part coordinates."""
    from probegen.evaluate.setups_dmis import ingest_dmis_setups

    part, spec, runs = _run_all(tmp_path, ODD, CMM, "dmis")
    assert [sp.name for sp, _, _ in runs] == ["AS LOADED", "FLIPPED"]
    outputs = [o for _, _, o in runs]
    for order in (outputs, outputs[::-1]):
        got = ingest_dmis_setups(order, spec, part=part)
        _check_recovered(got, runs, spec)
    flipped = {r.feature: r for r in got.revolved}["R2"]
    # the CMM reported (50, -25) + OFFSET in the table frame; in the part: (50, 25) + Rᵀ·O
    assert flipped.centre[:2] == pytest.approx((50.004, 25.003), abs=1e-3)


def test_a_mismatched_dmis_output_is_refused(tmp_path: Path) -> None:
    from probegen.evaluate.setups_dmis import ingest_dmis_setups

    part, spec, runs = _run_all(tmp_path, ODD, CMM, "dmis")
    flipped = runs[1][2]
    with pytest.raises(ProbegenError, match="a second DMIS output of 'ALL REVOLVED FLIPPED'"):
        ingest_dmis_setups([flipped, flipped], spec, part=part)
    other = tmp_path / "other.dms"
    other.write_text("FILNAM/'SOMETHING ELSE'\nUNITS/MM, ANGDEC\nOUTPUT/FA(Q1)\n"
                     "FA(Q1) = FEAT/CIRCLE, INNER, CART, 1, 2, 3, 0, 0, 1, 5\nENDFIL\n",
                     encoding="ascii")
    with pytest.raises(ProbegenError, match="expected the DMIS output of one of the spec's"):
        ingest_dmis_setups([other], spec, part=part)
    named = tmp_path / "named.dms"
    named.write_text(other.read_text(encoding="ascii").replace("SOMETHING ELSE",
                                                               "ALL REVOLVED FLIPPED"),
                     encoding="ascii")
    with pytest.raises(ProbegenError, match="found Q1: the output of another spec"):
        ingest_dmis_setups([named], spec, part=part)
    # without its FILNAM line, an output is paired by its features (R2: FLIPPED only)
    bare = tmp_path / "bare.dms"
    bare.write_text("\n".join(line for line in flipped.read_text(encoding="ascii")
                              .splitlines() if not line.startswith("FILNAM")) + "\n",
                    encoding="ascii")
    got = ingest_dmis_setups([bare], spec, part=part)
    assert [r.feature for r in got.revolved] == ["R2"]
    assert {n.feature for n in got.not_evaluated} == {"R1", "R3"}
    assert all("no DMIS output of setup AS LOADED" in n.reason for n in got.not_evaluated)
    # paired by its FILNAM, an output without the feature's actual leaves it NOT EVALUATED
    empty = tmp_path / "empty.dms"
    empty.write_text("FILNAM/'ALL REVOLVED FLIPPED'\nUNITS/MM, ANGDEC\nENDFIL\n",
                     encoding="ascii")
    got = ingest_dmis_setups([empty], spec, part=part)
    assert not got.revolved
    (r2,) = [n for n in got.not_evaluated if n.feature == "R2"]
    assert r2.reason == f"no feature actual FA(R2) in {empty}"


def countersunk_block(path: Path) -> Path:
    """A 60 x 40 x 20 block (corner at the origin) with a D8 hole through at (20, 20),
    countersunk 90 deg to D14 from the bottom face, and a D10 bore 8 deep from the top
    at (45, 20) chamfered 1 mm (a cone facing up): the countersink faces down, only the
    part turned over reaches it."""
    from build123d import Align, Box, Cone, Cylinder, Pos, export_step

    box = Box(60, 40, 20, align=(Align.MIN, Align.MIN, Align.MIN))
    sink = Pos(20, 20, 0) * Cone(7, 0.0, 7, align=(Align.CENTER, Align.CENTER, Align.MIN))
    shape = box - Pos(20, 20, 10) * Cylinder(4, 20) - sink
    chamfer = Pos(45, 20, 20) * Cone(0.0, 6, 6, align=(Align.CENTER, Align.CENTER, Align.MAX))
    shape = shape - Pos(45, 20, 16) * Cylinder(5, 8) - chamfer
    export_step(shape, str(path))
    return path


@pytest.mark.parametrize("dialect", ["dmis", "fanuc"])
def test_the_cones_of_a_flipped_setup_are_on_the_model_and_recovered(
        tmp_path: Path, dialect: str) -> None:
    """The countersink that faces down goes to the FLIPPED program; every PTMEAS of the
    DMIS programs lies on the model as each setup turns it (the points check of
    benchmarks/points_on_model.py), and on the virtual CMM (DMIS) or the virtual
    five-axis machine (Fanuc Macro B) off by OFFSET every feature comes back in part
    coordinates to 1 µm."""
    from probegen.evaluate.setups import ingest_setups
    from probegen.evaluate.setups_dmis import ingest_dmis_setups

    model = countersunk_block(tmp_path / "countersunk.step")
    part, spec, runs = _run_all(tmp_path, model, CMM if dialect == "dmis" else FIVE,
                                dialect)
    kinds = {f.id: f.kind for f in spec.features}
    flipped = [sp for sp, _, _ in runs if sp.name == "FLIPPED"]
    assert flipped and any(kinds[f] == "cone" for f in flipped[0].features), \
        [(sp.name, sp.features) for sp, _, _ in runs]
    outputs = [o for _, _, o in runs]
    if dialect == "dmis":
        for sp, program, _ in runs:
            check = check_points(program.read_text(encoding="ascii"), sp.part)  # as it lies
            assert check.points and not check.off_model and not check.inward, \
                (sp.name, check.text())
        got = ingest_dmis_setups(outputs, spec, part=part)
    else:
        got = ingest_setups(outputs, spec, part=part)
    _check_recovered(got, runs, spec)


def test_ingest_of_both_dmis_outputs_on_the_command_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """test_setups.py's block (a bore on top, one facing down) compiled to DMIS, both
    programs run on the virtual CMM off by OFFSET, ``probegen ingest`` of both outputs:
    results.json in part coordinates, both bores OK; the FLIPPED output given twice is
    refused, naming it."""
    from test_setups import FLIPPED, SPEC, block, five_without_setups

    block(tmp_path / "part.step")
    (tmp_path / "five.toml").write_text(five_without_setups() + FLIPPED, encoding="utf-8")
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC.format(profile="five.toml", extra=""), encoding="utf-8")
    out = tmp_path / "dmis"
    assert main(["-q", "compile", str(spec), "-d", "dmis", "-o", f"{out}/"]) == ExitCode.OK
    outputs = []
    for name, setup in (("spec_FLIPPED.dmi", "FLIPPED"), ("spec.dmi", None)):
        output = tmp_path / f"{name}.dms"
        args = ["-q", "sim", str(out / name), "--spec", str(spec), "-o", str(output),
                "--offset", *(str(v) for v in OFFSET)]
        assert main(args + (["--setup", setup] if setup else [])) == 0
        outputs.append(str(output))
    res = tmp_path / "res"
    assert main(["-q", "ingest", *outputs, "--spec", str(spec), "-o", str(res)]) == ExitCode.OK
    results = json.loads((res / "results.json").read_text(encoding="utf-8"))
    got = {f["id"]: {c["name"]: c for c in f["characteristics"]} for f in results["features"]}
    assert list(got) == ["TOP", "BOTTOM"]
    assert [f["status"] for f in results["features"]] == ["OK", "OK"]
    shift = {"TOP": OFFSET, "BOTTOM": np.asarray(frames.apply_t(frames.FLIP_X, tuple(OFFSET)))}
    for fid, s in shift.items():
        for axis, k in (("X", 0), ("Y", 1)):
            assert got[fid][axis]["deviation"] == pytest.approx(s[k], abs=1e-3), (fid, axis)
        assert got[fid]["D"]["deviation"] == pytest.approx(0.0, abs=1e-3)
    assert got["BOTTOM"]["Y"]["measured"] == pytest.approx(30.0 + 0.003, abs=1e-3)
    capsys.readouterr()
    code = main(["-q", "ingest", outputs[0], outputs[0], "--spec", str(spec), "-o", str(res)])
    assert code != ExitCode.OK
    assert "a second DMIS output of 'TWO BORES FLIPPED'" in capsys.readouterr().err
    log = tmp_path / "run.log"
    log.write_text("%\nPGSTART O1001 V2 H00000000\nPGEND\n", encoding="ascii")
    code = main(["-q", "ingest", outputs[0], str(log), "--spec", str(spec), "-o", str(res)])
    assert code != ExitCode.OK
    assert "expected DMIS output files only" in capsys.readouterr().err


@pytest.mark.parametrize("dialect", ["dmis", "fanuc"])
def test_plan_all_revolved_then_ingest_every_setup_on_the_command_line(
        tmp_path: Path, dialect: str) -> None:
    """``plan --all-revolved odd_angle.step -d D -o DIR`` writes one program per setup and
    the spec they were planned from; each program runs on the virtual CMM / five-axis
    machine off by OFFSET; ``ingest`` of all the outputs with that spec reports every
    feature in part coordinates: its centre off by Rᵀ·OFFSET square to its axis (POS
    and, for the vertical R2 turned over, X and Y), its diameter nominal, to 1 µm."""
    from probegen import cad
    from probegen.cad.revolved import revolved_features

    profile = CMM if dialect == "dmis" else FIVE
    ext = {"dmis": ".dmi", "fanuc": ".nc"}[dialect]
    out = tmp_path / "out"
    assert main(["-q", "plan", "--all-revolved", str(ODD), "--machine", str(profile), "-d",
                 dialect, "-o", str(out)]) == ExitCode.OK
    spec = out / "odd_angle_all_revolved.toml"
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [f"odd_angle{ext}", f"odd_angle_FLIPPED{ext}", spec.name])
    outputs = []
    for stem, setup in (("odd_angle_FLIPPED", "FLIPPED"), ("odd_angle", None)):
        output = out / f"{stem}{'.dms' if dialect == 'dmis' else '.log'}"
        args = ["-q", "sim", str(out / f"{stem}{ext}"), "--spec", str(spec), "-o",
                str(output), "--offset", *(str(v) for v in OFFSET)]
        assert main(args + (["--setup", setup] if setup else [])) == 0, stem
        outputs.append(str(output))
    res = tmp_path / "res"
    assert main(["-q", "ingest", *outputs, "--spec", str(spec), "-o", str(res)]) == ExitCode.OK
    results = json.loads((res / "results.json").read_text(encoding="utf-8"))
    got = {f["id"]: {c["name"]: c for c in f["characteristics"]} for f in results["features"]}
    assert sorted(got) == ["R1", "R2", "R3"]
    axes = {f"R{f.id}": np.asarray(f.axis) for f in revolved_features(cad.load_part(ODD))}
    for fid, c in got.items():
        shift = np.asarray(frames.apply_t(frames.FLIP_X, tuple(OFFSET))) if fid == "R2" \
            else OFFSET
        pos = 2.0 * float(np.linalg.norm(_across(shift, axes[fid])))
        assert c["POS"]["measured"] == pytest.approx(pos, abs=1e-3), fid
        assert c["D"]["deviation"] == pytest.approx(0.0, abs=1e-3), fid
    assert (got["R2"]["X"]["deviation"], got["R2"]["Y"]["deviation"]) == pytest.approx(
        (0.004, 0.003), abs=1e-3)


@settings(max_examples=examples(60))
@given(lines=st.lists(st.one_of(
    st.sampled_from(["FILNAM/'TWO BORES'", "FILNAM/'TWO BORES FLIPPED'", "FILNAM/'X'",
                     "FILNAM/", "UNITS/MM, ANGDEC", "ENDFIL", "OUTPUT/FA(TOP)",
                     "FA(TOP) = FEAT/CIRCLE, INNER, CART, 1, 2, 3, 0, 0, 1, 5",
                     "FA(BOTTOM) = FEAT/CYLNDR, INNER, CART, 1, 2, 3, 0, 0, 1, 5, 4",
                     "FA(Q_1) = FEAT/POINT, CART, 1, 2, 3, 0, 0, 1", ""]),
    st.text("FA(TOPBM)=/,'ILNC 0123456789.$\n", max_size=40)), max_size=8),
    count=st.integers(1, 3))
def test_random_dmis_outputs_pair_with_a_program_or_are_refused(lines: list[str],
                                                                 count: int) -> None:
    """Outputs of random lines: each read and paired with one setup program (by its
    FILNAM or its features), or a ProbegenError naming the file."""
    import tempfile
    from types import SimpleNamespace

    from probegen.evaluate.setups_dmis import pair_outputs
    from probegen.results import read_dmis_output

    programs = [SimpleNamespace(
        spec=SimpleNamespace(program_name=name, features=(SimpleNamespace(id=fid),)),
        name=setup) for name, fid, setup in (("TWO BORES", "TOP", "AS LOADED"),
                                            ("TWO BORES FLIPPED", "BOTTOM", "FLIPPED"))]
    with tempfile.TemporaryDirectory() as tmp:
        paths = []
        for k in range(count):
            path = Path(tmp) / f"{k}.dms"
            path.write_text("\n".join(lines[k:]) + "\n", encoding="latin-1")
            paths.append(path)
        try:
            outputs = [read_dmis_output(p) for p in paths]
            paired = pair_outputs(paths, outputs, programs)  # type: ignore[arg-type]
        except ProbegenError as exc:
            assert any(str(p) in str(exc) for p in paths), str(exc)
            return
        assert len(paired) == len(paths)
        for k, (_, output) in paired.items():
            own = {f.id for f in programs[k].spec.features}
            assert {fa.name for fa in output.features} <= own | {"Q_1"}
