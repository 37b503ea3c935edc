"""The command line: compile, features, sphere-points; exit codes."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO

from probegen.cli.app import ExitCode, main


def test_compile_writes_both_dialects(in_repo: Path, tmp_path: Path,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    """Fanuc compact (the default: the program and its macro library, as the golden
    files), DMIS inline; --inline gives the self-contained golden program."""
    code = main(["compile", "samples/sphere25/sphere_test.toml", "-d", "fanuc", "-d", "dmis",
                 "-o", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == ExitCode.OK
    golden = REPO / "tests/golden"
    assert (tmp_path / "sphere_test.nc").read_text() == (
        golden / "macros/sphere_test.compact.nc").read_text()
    for name in ("O8000.nc", "O8001.nc", "O8002.nc"):
        assert (tmp_path / name).read_text() == (golden / "macros" / name).read_text()
    assert (tmp_path / "sphere_test.dmi").exists()
    assert "retract 2.000 mm (safe minimum 1.605 mm)" in out
    assert "wrote the macro library O8000.nc, O8001.nc, O8002.nc" in out
    inline = tmp_path / "inline"
    assert main(["compile", "samples/sphere25/sphere_test.toml", "-d", "fanuc", "--inline",
                 "-o", str(inline)]) == ExitCode.OK
    assert [p.name for p in inline.iterdir()] == ["sphere_test.nc"]
    assert (inline / "sphere_test.nc").read_text() == (
        golden / "sphere25/sphere_test.nc").read_text()


def test_compile_to_stdout_prints_the_inline_form(in_repo: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """-o -: one self-contained program (a compact one would not run without its
    library), and a note on stderr saying so; --compact -o - is refused."""
    assert main(["compile", "samples/sphere25/sphere_test.toml", "-d", "fanuc", "-d", "dmis",
                 "-o", "-"]) == ExitCode.OK
    out, err = capsys.readouterr()
    inline = (REPO / "tests/golden/sphere25/sphere_test.nc").read_text()
    assert out.startswith(inline) and "G65" not in out and "DMISMN" in out
    assert err == ("note: the fanuc program on stdout is the inline form (every skip move in "
                   "it); with -o FOLDER compile writes the compact form and its macro library\n")
    assert main(["compile", "samples/sphere25/sphere_test.toml", "--compact",
                 "-o", "-"]) == ExitCode.ERROR
    assert "found stdout; the program calls the macro library" in capsys.readouterr().err


def test_sphere_points_reports_figures(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sphere-points", "--layout", "octahedral"]) == ExitCode.OK
    out = capsys.readouterr().out.splitlines()
    assert out[1:4] == ["min d / R     0.518", "min d / max d 0.796",
                        "largest step  41.41 deg (zigzag order)"]
    assert len(out) == 5 + 25


def test_features_lists_the_sample(in_repo: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["features", "samples/sphere25/sphere25.step"]) == ExitCode.OK
    rows = capsys.readouterr().out.splitlines()
    assert any(r.split()[:3] == ["5", "sphere", "outer"] for r in rows)


def test_missing_model_is_a_model_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["features", "nope.step"]) == ExitCode.MODEL
    assert capsys.readouterr().err == ("probegen: error: nope.step: expected a STEP file, "
                                           "found no such file\n")


def test_usage_error() -> None:
    assert main(["compile"]) == ExitCode.USAGE


def test_unknown_dialect(in_repo: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["compile", "samples/sphere25/sphere_test.toml", "-d", "fanc", "-o", "-"])
    assert code == ExitCode.UNSUPPORTED
    assert "did you mean 'fanuc'" in capsys.readouterr().err


def test_qif_from_the_sample_log_validates(in_repo: Path, tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    from conftest import SHARED

    out = tmp_path / "r.qif"
    code = main(["qif", "samples/sphere25/sphere_test.log", "--spec",
                 "samples/sphere25/sphere_test.toml", "-o", str(out), "--validate",
                 "--schema", str(SHARED / "ref/qif/schema/QIFDocument.xsd")])
    assert code == ExitCode.OK
    assert "valid against the QIF 3 schema" in capsys.readouterr().out
    assert "<SphereFeatureMeasurement" in out.read_text()


def test_qif_needs_a_spec_for_a_log(in_repo: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["qif", "samples/sphere25/sphere_test.log", "-o", "-"]) == ExitCode.ERROR
    assert "needs --spec" in capsys.readouterr().err
