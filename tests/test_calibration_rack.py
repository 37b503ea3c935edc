"""Probe calibration per stylus and orientation (``machine/calibration.py``, issue 17):
``[[calibration]]`` entries with ``stylus`` and ``orientation``, ``entry_for`` and its
fallbacks, today's one-entry files unchanged, a spec's calibration switched with the
stylus, and random edits ending in a calibration or a SpecError."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen.errors import SpecError
from probegen.machine.calibration import (
    ProbeCalibration,
    calibration_toml,
    load_calibration,
    stylus_calibration,
)
from probegen.machine.profile import load_profile
from probegen.spec.model import load_spec

LEGACY = REPO / "tests" / "data" / "calibration" / "probe.cal.toml"
UP = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (-1.0, 0.0, 0.0), (0.0, -1.0, 0.0))


def entry(stylus: str, orientation: str, ball: float, shift: float) -> ProbeCalibration:
    radii = tuple(round(ball - shift - 0.0001 * i, 7) for i in range(len(UP)))
    return ProbeCalibration(ball, round(float(np.mean(radii)), 7), UP, radii, "sphere.log", 0.0002,
                            "2026-11-26", stylus, orientation)


def several(*entries: ProbeCalibration) -> ProbeCalibration:
    return ProbeCalibration(**{**_fields(entries[0]), "others": entries[1:]})


def _fields(c: ProbeCalibration) -> dict[str, object]:
    return {name: getattr(c, name) for name in ProbeCalibration.__dataclass_fields__}


SET = several(entry("D6", "", 3.0, 0.0010), entry("D2", "A0B0", 1.0, 0.0020),
              entry("D2", "A90B90", 1.0, 0.0030), entry("D3", "A90B0", 1.5, 0.0040))


def test_todays_file_loads_and_prints_unchanged(tmp_path: Path) -> None:
    cal = load_calibration(LEGACY)
    assert (cal.stylus, cal.orientation, cal.others) == ("", "", ())
    assert cal.fingerprint == "C79A9AFE3"  # as before issue 17
    assert calibration_toml(cal) == LEGACY.read_text(encoding="utf-8")
    # the one entry of a file that names no stylus serves every stylus and orientation
    assert cal.entry_for("D2", "A90B90") == cal
    assert stylus_calibration(cal, "PRB20", 3.0, "", "spec.toml") == cal
    with pytest.raises(SpecError, match=r"spec\.toml: expected a probe calibration of a 2 mm "
                                        r"ball \(the stylus used\), found one of a 6 mm ball"):
        stylus_calibration(cal, "D1", 1.0, "", "spec.toml")
    assert stylus_calibration(None, "D1", 1.0, "", "spec.toml") is None


def test_several_entries_round_trip(tmp_path: Path) -> None:
    text = calibration_toml(SET)
    assert text.count("[[calibration]]") == 4 and "[calibration]\n" not in text
    assert text.index('stylus = "D2"') < text.index('stylus = "D3"') < text.index(
        'stylus = "D6"')  # sorted: repeatable whatever the entry in use
    path = tmp_path / "cal.toml"
    path.write_text(text, encoding="utf-8")
    back = load_calibration(path)
    assert back.entries == SET.entries
    assert back.fingerprint == SET.fingerprint
    assert (back.stylus, back.orientation) == ("D2", "A0B0")  # the first in the file


def test_entry_for_exact_then_vertical() -> None:
    d2 = SET.entry_for("D2", "A90B90")
    assert (d2.stylus, d2.orientation, d2.ball_radius) == ("D2", "A90B90", 1.0)
    assert d2.radii[0] == pytest.approx(1.0 - 0.0030)
    assert len(d2.others) == 3 and d2.fingerprint == SET.fingerprint
    # an orientation not calibrated: the stylus's vertical entry (A0B0 = TILT0 = "")
    for name in ("A45B90", "", "A0B0", "TILT0"):
        assert SET.entry_for("D2", name).orientation == "A0B0"
    assert SET.entry_for("D6", "A0B0").stylus == "D6"
    # the entry in use gives the radius map: another entry, another map
    assert SET.entry_for("D2", "A90B90").radius([UP[0]])[0] != \
        SET.entry_for("D2", "").radius([UP[0]])[0]


def test_a_missing_pair_is_an_error_naming_what_the_file_holds() -> None:
    with pytest.raises(SpecError, match=r"spec\.toml: machine\.calibration: expected a probe "
                                        r"calibration of stylus D3 \(or of its vertical "
                                        r"orientation\), found entries for D2 A0B0, D2 A90B90, "
                                        r"D3 A90B0, D6 vertical only; run the sphere test"):
        SET.entry_for("D3", "TILT0", "spec.toml: machine.calibration")
    with pytest.raises(SpecError, match=r"of stylus D1 in orientation A90B90"):
        SET.entry_for("D1", "A90B90")


def test_describe_names_the_stylus_and_orientation() -> None:
    assert "calibrated: stylus D2 A90B90, sphere.log" in SET.entry_for("D2", "A90B90").describe()
    assert "calibrated: stylus D6 vertical, " in SET.entry_for("D6").describe()


FILE_HEAD = ('[[calibration]]\nstylus = "{s}"\n{o}ball_radius = {b}\neffective_radius = {b}\n'
             'directions = [[0.0, 0.0, 1.0]]\nradii = [{b}]\n')


def write(tmp: Path, *entries: tuple[str, str, float], extra: str = "") -> Path:
    text = "".join(FILE_HEAD.format(s=s, o=f'orientation = "{o}"\n' if o else "", b=b)
                   for s, o, b in entries) + extra
    path = tmp / "cal.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(("entries", "message"), [
    ((("D2", "A0B0", 1.0), ("D2", "", 1.0)),
     r"calibration\[1\]\.orientation: expected one entry per stylus and orientation, found "
     r"stylus D2 vertical again \(first at calibration\[0\]\)"),
    ((("D2", "A90B90", 1.0), ("D2", "A90B90", 1.0)), r"found stylus D2 A90B90 again"),
    ((("d2", "", 1.0),), r"calibration\[0\]\.stylus: expected 1-8 of A-Z 0-9 _"),
    ((("D2", "A90-B90", 1.0),), r"calibration\[0\]\.orientation: expected 1-16 of A-Z"),
])
def test_bad_entries(tmp_path: Path, entries: tuple[tuple[str, str, float], ...],
                     message: str) -> None:
    with pytest.raises(SpecError, match=message):
        load_calibration(write(tmp_path, *entries))


def test_an_entry_of_several_names_its_stylus(tmp_path: Path) -> None:
    path = write(tmp_path, ("D2", "", 1.0))
    path.write_text(path.read_text() + FILE_HEAD.replace('stylus = "{s}"\n', "").format(
        o="", b=1.5), encoding="utf-8")
    with pytest.raises(SpecError, match=r"calibration\[1\]\.stylus: required key is missing"):
        load_calibration(path)
    path.write_text("calibration = []\n", encoding="utf-8")
    with pytest.raises(SpecError, match=r"calibration: expected at least one"):
        load_calibration(path)


def test_one_table_may_name_its_stylus(tmp_path: Path) -> None:
    path = write(tmp_path, ("D2", "A0B0", 1.0))
    path.write_text(path.read_text().replace("[[calibration]]", "[calibration]"))
    cal = load_calibration(path)
    assert (cal.stylus, cal.orientation) == ("D2", "A0B0")
    assert calibration_toml(cal).startswith("# Probe calibration written by probegen "
                                            "(sphere test, method M1).\n[calibration]\n"
                                            'stylus = "D2"\norientation = "A0B0"\n')
    with pytest.raises(SpecError, match=r"of stylus D3"):
        cal.entry_for("D3")


SPEC = '''[part]
model = "{model}"

[machine]
profile = "{profile}"
calibration = "cal.toml"

[[feature]]
id = "BORE"
kind = "cylinder"
at = [75.0, 50.0, 25.0]
'''


def spec_file(tmp: Path) -> Path:
    path = tmp / "spec.toml"
    path.write_text(SPEC.format(
        model=(REPO / "samples/bore_block/bore_block.step").as_posix(),
        profile=(REPO / "samples/machines/vmc-5axis-fanuc.toml").as_posix()), encoding="utf-8")
    return path


def test_a_spec_takes_the_probe_styluss_entry_and_with_stylus_switches(tmp_path: Path) -> None:
    write(tmp_path, ("D2", "", 1.0), ("D6", "TILT0", 3.0), ("D6", "TILT1", 3.0))
    machine = load_spec(spec_file(tmp_path)).machine
    assert machine.calibration is not None
    assert (machine.calibration.stylus, machine.calibration.orientation) == ("D6", "TILT0")
    d2 = machine.with_stylus(machine.rack[2])
    assert d2.calibration is not None and d2.calibration.stylus == "D2"
    assert d2.calibration.fingerprint == machine.calibration.fingerprint
    with pytest.raises(SpecError, match=r"probe calibration C[0-9A-F]{8}: expected a probe "
                                        r"calibration of stylus D3"):
        machine.with_stylus(machine.rack[1])


def test_a_spec_whose_calibration_lacks_the_probe_stylus(tmp_path: Path) -> None:
    write(tmp_path, ("D2", "", 1.0))
    with pytest.raises(SpecError, match=r"spec\.toml: machine\.calibration: expected a probe "
                                        r"calibration of stylus D6"):
        load_spec(spec_file(tmp_path))


def test_a_profile_without_calibration_switches_nothing() -> None:
    m = load_profile(REPO / "samples/machines/vmc-5axis-fanuc.toml")
    assert m.with_stylus(m.rack[2]).calibration is None


LINES = st.sampled_from(['stylus = "D2"', 'stylus = "X"', 'orientation = "A90B90"',
                         'orientation = ""', "ball_radius = 1.0", "ball_radius = -1",
                         "radii = [1.0, 2.0]", "directions = [[1.0, 0.0, 0.0]]",
                         "[[calibration]]", "[calibration]", 'date = "2026-13-01"',
                         "u_radius = 2", "effective_radius = 0.999", "others = 1"])


@settings(max_examples=examples(80))
@given(cut=st.integers(0, 2000), lines=st.lists(LINES, max_size=4), at=st.integers(0, 60))
def test_random_edits_end_in_a_calibration_or_a_spec_error(cut: int, lines: list[str],
                                                           at: int) -> None:
    text = calibration_toml(SET).splitlines()
    text = text[: max(1, len(text) - cut % 7)]
    position = at % (len(text) + 1)
    text[position:position] = lines
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "cal.toml"
        path.write_text("\n".join(text) + "\n", encoding="utf-8")
        try:
            cal = load_calibration(path)
        except SpecError as exc:
            assert str(exc).startswith(str(path))
            return
    pairs = [(e.stylus, e.orientation) for e in cal.entries]
    assert len(set(pairs)) == len(pairs)
    for e in cal.entries:
        assert len(e.directions) == len(e.radii) and e.others == ()
        assert cal.entry_for(e.stylus or "ANY", e.orientation).entries == cal.entries
