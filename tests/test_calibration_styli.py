"""One calibration file for the whole rack (issue 17, item 1): a sphere test names the
stylus it calibrates (``stylus = "D3"``), the program takes that stylus for the test and
gives the ``[probe]`` stylus back, and ``ingest --write-calibration FILE`` adds the
stylus's entry to FILE, keeping the entries of the other styli it holds
(docs/results.md, "Probe calibration")."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from conftest import REPO

from probegen.cli.app import ExitCode, main
from probegen.errors import SpecError
from probegen.machine.calibration import ProbeCalibration, combined, load_calibration

MACHINES = REPO / "samples" / "machines"
SPEC = """[part]
units = "mm"

[machine]
profile = "{profile}"

[program]
number = {number}
name = "SPHERE {stylus}"

[[feature]]
id = "SPH1"
kind = "sphere_test"
centre = [0.0, 0.0, 0.0]
diameter = 25.0
layout = "iso"
locate = false
{key}
"""


def spec(folder: Path, profile: str, stylus: str | None, number: int) -> Path:
    path = folder / f"{stylus or 'probe'}.toml"
    key = f'stylus = "{stylus}"' if stylus else ""
    path.write_text(SPEC.format(profile=MACHINES / profile, number=number,
                                stylus=stylus or "PROBE", key=key), encoding="utf-8")
    return path


def measure(folder: Path, path: Path, suffix: str = ".nc") -> Path:
    """Compile ``path`` (inline), run it on the virtual machine, return the log."""
    program = path.with_suffix(suffix)
    assert main(["compile", str(path), "--inline", "-o", str(program), "-q"]) == 0
    log = path.with_suffix(".log")
    assert main(["sim", str(program), "--spec", str(path), "-o", str(log), "-q"]) == 0
    return log


def test_each_stylus_of_the_rack_calibrates_into_one_file(tmp_path: Path) -> None:
    d6 = spec(tmp_path, "vmc-5axis-fanuc.toml", None, 1002)
    d3 = spec(tmp_path, "vmc-5axis-fanuc.toml", "D3", 1003)
    cal = tmp_path / "rack.toml"
    for path in (d6, d3):
        log = measure(tmp_path, path)
        assert main(["ingest", "--spec", str(path), str(log), "-o", str(tmp_path / "out"),
                     "--write-calibration", str(cal), "--calibration-date", "2026-11-26",
                     "-q"]) == 0
    text = d3.with_suffix(".nc").read_text(encoding="ascii")
    skips = [m.start() for m in re.finditer("G31", text)]
    assert text.index("T21 M6") < skips[0] < skips[-1] < text.rindex("T20 M6")
    loaded = load_calibration(cal)
    assert [(e.stylus, e.ball_radius) for e in loaded.entries] == [("D3", 1.5), ("D6", 3.0)]
    for e in loaded.entries:  # a perfect probe: the nominal ball within 0.1 um
        assert abs(e.effective_radius - e.ball_radius) < 1e-4, e
        assert e.source.endswith(".log") and e.date == "2026-11-26"
    assert loaded.entry_for("D3").source.endswith("D3.log")
    assert loaded.entry_for("D6").source.endswith("probe.log")


def test_the_cmm_takes_the_named_stylus_at_the_index_height(tmp_path: Path) -> None:
    """On a CMM with a head a stylus change is routed at the index height: without a
    model, above the reference sphere; the program runs on the virtual CMM."""
    d2 = spec(tmp_path, "cmm.toml", "D2", 1004)
    measure(tmp_path, d2, ".dmi")
    text = d2.with_suffix(".dmi").read_text(encoding="ascii")
    lines = text.splitlines()
    at = lines.index("SNSLCT/S(D2_A0B0)")
    assert at < next(k for k, line in enumerate(lines) if line.startswith("MEAS/"))
    up = [float(v) for v in lines[at - 2].removeprefix("GOTO/").split(",")]
    # the sphere's top 12.5 + D2's 30 mm + its ball 1 + the head's 65 + the margin 0.3
    assert up[2] >= 12.5 + 30.0 + 1.0 + 65.0 + 0.3 - 1e-9


def test_a_log_is_never_overwritten_by_the_calibration(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]
                                                        ) -> None:
    d3 = spec(tmp_path, "vmc-5axis-fanuc.toml", "D3", 1003)
    log = measure(tmp_path, d3)
    before = log.read_bytes()
    assert main(["ingest", "--spec", str(d3), str(log), "-o", str(tmp_path / "out"),
                 "--write-calibration", str(log)]) == ExitCode.OUTPUT
    assert log.read_bytes() == before
    assert "found one of this command's inputs" in capsys.readouterr().err


def entry(stylus: str, radius: float = 1.0, orientation: str = "") -> ProbeCalibration:
    return ProbeCalibration(radius, radius, (), (), f"{stylus}.log", stylus=stylus,
                            orientation=orientation)


def test_an_entry_replaces_its_own_stylus_and_keeps_the_others() -> None:
    old, _ = combined((entry("D1"), entry("D2", 2.0), entry("D3", 3.0, "A90B0")))
    new, kept = combined((entry("D2", 2.0), entry("D3", 3.0)), old)
    assert [(e.stylus, e.orientation) for e in kept] == [("D1", ""), ("D3", "A90B0")]
    assert [(e.stylus, e.orientation) for e in new.entries] == [
        ("D1", ""), ("D2", ""), ("D3", ""), ("D3", "A90B0")]
    assert new.entry_for("D2").source == "D2.log"


def test_an_unnamed_entry_replaces_the_file_whole() -> None:
    rack, _ = combined((entry("D1"), entry("D2", 2.0)))
    alone, kept = combined((entry(""),), rack)
    assert kept == () and len(alone.entries) == 1
    named, kept = combined((entry("D1"),), alone)
    assert kept == () and [e.stylus for e in named.entries] == ["D1"]


@pytest.mark.parametrize(("entries", "found"), [
    ((entry("D1"), entry("D1")), "one sphere test per stylus and orientation, found several "
                                 "of stylus D1"),
    ((entry("D1"), entry("")), "to name its stylus"),
    ((), "at least one sphere test's calibration"),
])
def test_runs_that_cannot_be_one_file_are_refused(entries: tuple[ProbeCalibration, ...],
                                                  found: str) -> None:
    with pytest.raises(SpecError, match=found):
        combined(entries, None, "--write-calibration")
