"""``probegen grating plan | simulate | identify`` end to end, outputs checked."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO

from probegen.cli.app import main

SPEC = str(REPO / "samples" / "grating" / "grating.toml")
ERRORS = str(REPO / "samples" / "grating" / "machine-errors.toml")


def test_plan_simulate_identify(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    progs = tmp_path / "progs"
    assert main(["grating", "plan", "--spec", SPEC, "--second-offset", "-o", str(progs)]) == 0
    assert sorted(p.name for p in progs.iterdir())[:2] == ["O7100_XY.nc", "O7101_XZ.nc"]
    readings = tmp_path / "readings.csv"
    assert main(["grating", "simulate", "--spec", SPEC, "--errors", ERRORS,
                 "--second-offset", "-o", str(readings)]) == 0
    raw = readings.read_bytes()
    out = tmp_path / "m5"
    assert main(["grating", "identify", str(readings), "-o", str(out)]) == 0
    assert readings.read_bytes() == raw  # the raw readings are never modified
    printed = capsys.readouterr().out
    assert "ECZ  roll         NOT IDENTIFIABLE (it does not move the read point" in printed
    assert "EAX  roll         rms" in printed  # the riser setups determine the rolls
    names = {p.name for p in out.iterdir()}
    assert {"summary.txt", "volumetric_map.csv", "errors_x.csv", "pitch_x_fanuc.csv",
            "map_XY.svg", "plot_EAX.svg"} <= names
    assert "plot_ECZ.svg" not in names  # nothing is plotted for what is not determined
    pitch = (out / "pitch_x_fanuc.csv").read_text(encoding="utf-8").splitlines()
    assert "# parameter 3624 (interval, 0.001 mm) = 10000" in pitch
    rows = [ln.split(",") for ln in pitch if ln[:1].isdigit()]
    assert len(rows) == 21 and rows[0][3] == "0"
    assert all(-7 <= int(r[3]) <= 7 for r in rows)
    table = (out / "errors_z.csv").read_text(encoding="utf-8")
    assert "# not identifiable (no column): EXZ EYZ EAZ EBZ ECZ" in table
    svg = (out / "map_XY.svg").read_text(encoding="utf-8")
    assert svg.startswith('<svg xmlns="http://www.w3.org/2000/svg" ') and "<line" in svg


def test_bad_readings_exit_with_a_message(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text("plane,line\nXY,L10\n", encoding="utf-8")
    assert main(["grating", "identify", str(bad), "-o", str(tmp_path / "o")]) == 6
    assert "bad.csv: header: expected columns" in capsys.readouterr().err


def test_pitch_values_sum_to_the_rounded_compensation() -> None:
    import numpy as np

    from probegen.calibrate.grating_out import _pitch_values

    compensation = np.array([0.0, 1.4, 2.8, 4.2, 5.6, 30.0])  # 0.001 mm
    values, magnification = _pitch_values(compensation)
    assert magnification == 4  # 24.4 / 7 > 3
    assert np.all(np.abs(values) <= 7)
    assert np.cumsum(values).tolist() == np.rint(compensation / 4).astype(int).tolist()
    values, magnification = _pitch_values(compensation[:5])
    assert (magnification, values.tolist()) == (1, [0, 1, 2, 1, 2])
