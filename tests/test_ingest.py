"""The way back: sample log → compensate → fit → evaluate, against the documented truth."""

from __future__ import annotations

import dataclasses
import json
import os
import tempfile
import threading
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, assert_golden
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from mutations import mutate

from probegen.cli.app import ExitCode, main
from probegen.errors import ProbegenError
from probegen.evaluate.ingest import identified, ingest
from probegen.evaluate.outputs import to_csv, to_json
from probegen.evaluate.run_identity import IdentityOptions
from probegen.machine.calibration import (
    ProbeCalibration,
    calibration_toml,
    compensate,
    load_calibration,
)
from probegen.spec.model import load_spec

LOG = Path("samples/sphere25/sphere_test.log")
SPEC = Path("samples/sphere25/sphere_test.toml")
TRUTH = tomllib.loads((REPO / "samples/sphere25/sphere_test.truth.toml").read_text())
PRINT_RESOLUTION = 3e-5  # the log prints 4 decimals; the fit averages the rounding


def test_sample_log_reproduces_the_planted_truth(in_repo: Path) -> None:
    result = ingest(LOG, load_spec(SPEC))
    (r,) = result.results
    assert result.notes == ()
    assert np.allclose(r.fit.centre, TRUTH["centre"], atol=PRINT_RESOLUTION)
    assert 2 * r.fit.radius == pytest.approx(TRUTH["diameter"], abs=PRINT_RESOLUTION)
    assert r.p_ftu == pytest.approx(TRUTH["p_ftu"], abs=PRINT_RESOLUTION)
    assert r.p_stu == pytest.approx(TRUTH["p_stu"], abs=PRINT_RESOLUTION)
    assert r.effective_radius == pytest.approx(TRUTH["effective_radius"], abs=PRINT_RESOLUTION)


def test_results_files_are_golden(in_repo: Path) -> None:
    spec = load_spec(SPEC)
    who = IdentityOptions(part_number="SPH-25", serial="S001", operator="A. Smith",
                          time="2026-11-26T13:48:53+01:00", batch="B1")
    result = identified(ingest(LOG, spec), spec, who)
    assert_golden(REPO / "tests/golden/ingest/results.json", to_json(result))
    assert_golden(REPO / "tests/golden/ingest/results.csv", to_csv(result))


def test_cli_ingest_writes_files_and_calibration(in_repo: Path, tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    cal = tmp_path / "probe.toml"
    code = main(["ingest", str(LOG), "--spec", str(SPEC), "-o", str(tmp_path),
                 "--write-calibration", str(cal)])
    out = capsys.readouterr().out
    assert code == ExitCode.OK
    assert "SPH1     P_FTU    0.0016" in out
    doc = json.loads((tmp_path / "results.json").read_text())
    assert doc["features"][0]["n"] == 25 and doc["complete"] is True
    loaded = load_calibration(cal)
    assert len(loaded.directions) == 25
    assert loaded.effective_radius == pytest.approx(TRUTH["effective_radius"], abs=3e-5)
    assert "probe: uncalibrated, nominal ball radius" in out
    # re-evaluated with its own calibration the test still shows the probe's lobing
    # (the map is what it measures, not what it compensates) and gives the same map
    result = ingest(LOG, load_spec(SPEC), calibration=loaded)
    assert result.results[0].p_ftu == pytest.approx(0.0016, abs=1e-4)
    again = result.results[0].calibration(str(LOG))
    assert np.allclose(again.radii, loaded.radii, atol=1e-7)


def test_out_of_tolerance_sets_the_exit_code(in_repo: Path, tmp_path: Path) -> None:
    spec = tmp_path / "spec.toml"
    text = (REPO / SPEC).read_text().replace('"../machines', '"' + str(REPO / "samples/machines"))
    text = text.replace('"sphere25.step"', '"' + str(REPO / "samples/sphere25/sphere25.step") + '"')
    spec.write_text(text + "tolerance = { form = 0.001 }\n")
    code = main(["ingest", str(LOG), "--spec", str(spec), "-o", str(tmp_path)])
    assert code == ExitCode.NOT_OK
    doc = json.loads((tmp_path / "results.json").read_text())
    p_ftu = next(c for c in doc["features"][0]["characteristics"] if c["name"] == "P_FTU")
    assert p_ftu["ok"] is False and p_ftu["upper"] == 0.001


def test_missing_touches_are_noted(in_repo: Path, tmp_path: Path) -> None:
    lines = (REPO / LOG).read_text().splitlines()
    kept = [ln for ln in lines if not ln.startswith(("PT SPH1 17 ", "PT SPH1 18 ", "PGEND"))]
    log = tmp_path / "cut.log"
    log.write_text("\n".join(kept) + "\n")
    result = ingest(log, load_spec(SPEC))
    assert result.notes == ("the log has no PGEND line: the program did not finish",
                            "feature SPH1: no touch for points 17-18")
    # a partial feature is never signed: NOT EVALUATED, its 23-point fit for information
    assert result.results == ()
    (n,) = result.not_evaluated
    assert (n.feature, n.reason) == ("SPH1", "no touch for points 17-18")
    assert n.partial is not None and len(n.partial.points) == 23 and result.status == \
        "NOT EVALUATED"


def test_a_log_without_touches_is_an_error(in_repo: Path, tmp_path: Path) -> None:
    log = tmp_path / "empty.log"
    log.write_text("%\nPGSTART O1001 V1\nERR NOTOUCH SPH9 1\n")
    with pytest.raises(ProbegenError, match="found none usable.*ERR NOTOUCH SPH9 1"):
        ingest(log, load_spec(SPEC))
    # a run of this spec stopped at its first touch is not an input error: NOT EVALUATED
    log.write_text("%\nPGSTART O1001 V1\nERR NOTOUCH SPH1 1\n")
    ing = ingest(log, load_spec(SPEC))
    assert ing.status == "NOT EVALUATED"
    assert ing.not_evaluated[0].reason == ("no contact at point 1 (ERR NOTOUCH, line 3); "
                                           "no touch for points 2-25")


def test_capture_then_ingest_over_a_pty(in_repo: Path, tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    master, slave = os.openpty()
    data = (REPO / LOG).read_bytes()

    def machine() -> None:
        time.sleep(0.3)
        for k in range(0, len(data), 97):  # a slow serial line, in odd chunks
            os.write(master, data[k:k + 97])
            time.sleep(0.005)

    t = threading.Thread(target=machine)
    t.start()
    out = tmp_path / "run.log"
    code = main(["capture", "--port", os.ttyname(slave), "--out", str(out), "--timeout", "3",
                 "--bits", "8", "--parity", "N", "--stop-bits", "1", "--no-xonxoff"])
    t.join()
    os.close(master)
    os.close(slave)
    assert code == ExitCode.OK
    assert "capture ended: the program's end marker arrived" in capsys.readouterr().out
    assert out.read_bytes() == data
    assert ingest(out, load_spec(SPEC)).results[0].p_ftu == pytest.approx(0.0016, abs=3e-5)


def test_compensation_is_along_the_normal() -> None:
    n = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0]])
    o = np.array([[1.0, 2.0, 3.0], [10.0, 0.0, 10.0]])
    p = compensate(o, n, 3.0)
    assert np.allclose(p[0], [1.0, 2.0, 0.0])
    assert np.allclose(p[1], [10.0 - 3 / np.sqrt(2), 0.0, 10.0 - 3 / np.sqrt(2)])


def test_calibration_interpolates_and_round_trips(tmp_path: Path) -> None:
    cal = ProbeCalibration(3.0, 2.999, ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0)), (2.998, 3.0))
    r = cal.radius([[0, 0, 1], [1, 0, 0], [np.sqrt(0.5), 0, np.sqrt(0.5)]])
    assert r[0] == 2.998 and r[1] == 3.0 and r[2] == pytest.approx(2.999)
    path = tmp_path / "cal.toml"
    path.write_text(calibration_toml(cal))
    assert load_calibration(path) == cal


def test_bad_calibration_file(tmp_path: Path) -> None:
    path = tmp_path / "cal.toml"
    path.write_text("[calibration]\nball_radius = 3.0\neffective_radius = 2.9\n"
                    "directions = [[0.0, 0.0, 2.0]]\nradii = [2.9]\n")
    with pytest.raises(ProbegenError, match=r"calibration.directions: expected an array of"):
        load_calibration(path)


CAL_TEXT = (REPO / "tests/data/calibration/probe.cal.toml").read_text()


@settings(max_examples=examples(150))
@given(st.data())
def test_mutated_calibration_files_load_or_fail_cleanly(data: st.DataObject) -> None:
    """A calibration file with a few characters changed (the date, a radius, a bracket):
    a calibration whose map gives finite radii, or a ProbegenError naming the file."""
    text = data.draw(st.composite(lambda draw: mutate(draw, CAL_TEXT, "0123456789.-,[]=\"T:x "))())
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "cal.toml"
        path.write_text(text, encoding="utf-8")
        try:
            cal = load_calibration(path)
        except ProbegenError as exc:
            assert "cal.toml" in str(exc)
            return
    assert calibration_toml(cal).startswith("# Probe calibration")
    assert np.all(np.isfinite(cal.radius([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])))


def test_run_identity_from_the_log_the_spec_and_the_options(tmp_path: Path) -> None:
    lines = LOG.read_text().splitlines(keepends=True)
    start = next(i for i, line in enumerate(lines) if line.startswith("PGSTART"))
    log = tmp_path / "run.log"
    log.write_text("".join([*lines[:start + 1], "PGSERIAL   4711.\n", *lines[start + 1:]]))
    os.utime(log, (1_764_164_933, 1_764_164_933))  # 2025-11-26T13:48:53Z
    spec = load_spec(SPEC)
    spec = dataclasses.replace(spec, part_number="4711-020-A", part_name="Sphere artefact")
    run = identified(ingest(log, spec), spec).run
    assert run is not None
    assert (run.serial, run.time, run.part_number, run.part_name, run.program) == (
        "4711", "2025-11-26T13:48:53+00:00", "4711-020-A", "Sphere artefact",
        "O1001 H2DAFDB55")
    assert run.machine == spec.machine.name and run.operator is None
    given = IdentityOptions(serial=" S9 ", part_number="P-1", operator="B. Jones",
                            time="2026-01-02T03:04:05.678-05:00", batch="7")
    run = identified(ingest(log, spec), spec, given).run
    assert run is not None
    assert (run.serial, run.part_number, run.operator, run.time, run.batch) == (
        "S9", "P-1", "B. Jones", "2026-01-02T03:04:05-05:00", "7")
    for bad, message in (("2026-01-02", "expected a UTC offset"),
                         ("yesterday", "expected an ISO 8601 date and time")):
        with pytest.raises(ProbegenError, match=message):
            identified(ingest(log, spec), spec, IdentityOptions(time=bad))
