"""The stylus rack, the CMM head, the tilted plane and named setups of a machine profile
(``machine/rack.py``, issue 17): the two sample profiles as written, inch profiles, the
checks (their messages are golden in tests/bad_inputs/cli/rack_*, head_*, tilt_*,
setup_*), the spec's ``stylus`` key, and random edits ending in a profile or a
SpecError."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen.constants import MM_PER_INCH
from probegen.errors import ExitCode, SpecError
from probegen.ir import frames
from probegen.machine.profile import Head, NamedSetup, Stylus, Tilt, load_profile
from probegen.machine.rack import rotation_problem
from probegen.spec.model import RevolvedSpec, load_spec

MACHINES = REPO / "samples" / "machines"
CMM = MACHINES / "cmm.toml"
FIVE = MACHINES / "vmc-5axis-fanuc.toml"


def edited(tmp: Path, source: Path, *pairs: tuple[str, str]) -> Path:
    """``source`` with each ``old`` text replaced by ``new`` (each must be there)."""
    text = source.read_text(encoding="utf-8")
    for old, new in pairs:
        assert old in text, old
        text = text.replace(old, new, 1)
    path = tmp / source.name
    path.write_text(text, encoding="utf-8")
    return path


def test_cmm_sample_has_a_rack_of_five_and_a_ph10_head() -> None:
    m = load_profile(CMM)
    assert m.dialect == "dmis" and m.tilt is None
    # one setup: the part turned over about X (docs/setups.md), with its fixture note
    assert m.setups == (NamedSetup("FLIPPED", frames.FLIP_X, (0.0, 0.0, 0.0),
                                   "part turned over about X, top face down on parallels; "
                                   "align at the datum again"),)
    assert [(s.label, s.ball_diameter, s.shank_diameter, s.length, s.tool_number)
            for s in m.rack] == [("D1", 1.0, 0.7, 20.0, 0), ("D2", 2.0, 1.4, 30.0, 0),
                                 ("D3", 3.0, 2.0, 40.0, 0), ("D6", 6.0, 4.5, 50.0, 0),
                                 ("D3L", 3.0, 2.5, 100.0, 0)]
    # the TP20-like probe body, on every stylus (docs/spec.md)
    assert (m.probe.body_diameter, m.probe.body_length) == (13.2, 65.0)
    assert m.head == Head((0.0, 105.0), (-180.0, 180.0), 7.5, 14.0, 65.0)
    # the [probe] stylus is the rack's D3 (same ball, shank, length; no tool numbers)
    assert m.stylus.label == "D3"
    assert [s.label for s in m.styli()] == ["D3", "D1", "D2", "D6", "D3L"]
    # every index position of the head: 15 A positions, 49 B positions
    assert round((m.head.a[1] - m.head.a[0]) / m.head.step) + 1 == 15
    assert round((m.head.b[1] - m.head.b[0]) / m.head.step) + 1 == 49


def test_five_axis_sample_has_a_tilt_and_five_tools() -> None:
    m = load_profile(FIVE)
    assert m.dialect == "fanuc" and m.head is None
    assert m.tilt == Tilt("G68.2", "A", "C", (-110.0, 110.0), (-360.0, 360.0))
    assert m.controller.has("G68.2") and m.controller.tool_change
    assert [(s.label, s.ball_diameter, s.tool_number) for s in m.styli()] == [
        ("D6", 6.0, 20), ("D3", 3.0, 21), ("D2", 2.0, 22), ("D6L", 6.0, 23), ("D1", 1.0, 24)]
    assert (m.probe.body_diameter, m.probe.body_length) == (40.0, 50.0)   # OMP40-2-like
    assert m.stylus == m.rack[0] and m.probe.tool_number == 20
    assert [(s.name, s.rotation, s.origin) for s in m.setups] == [
        ("FLIPPED", frames.FLIP_X, (0.0, 0.0, 0.0))]


def test_profile_without_the_new_tables_is_as_before() -> None:
    m = load_profile(MACHINES / "vmc-fanuc.toml")
    assert (m.rack, m.head, m.tilt, m.setups) == ((), None, None, ())
    assert m.styli() == (Stylus("PRB20", 6.0, 4.5, 50.0, 20),)


def test_with_stylus_plans_with_the_rack_entry() -> None:
    m = load_profile(FIVE)
    d2 = m.rack[2]
    other = m.with_stylus(d2)
    assert (other.probe.ball_diameter, other.probe.shank_diameter, other.probe.length,
            other.probe.tool_number) == (2.0, 1.4, 30.0, 22)
    assert other.probe.approach == m.probe.approach and other.feeds == m.feeds
    assert other.stylus == d2


def test_inch_profile_converts_every_length(tmp_path: Path) -> None:
    text = CMM.read_text(encoding="utf-8").replace('units = "mm"', 'units = "inch"')
    text += ('\n[[setup]]\nname = "SIDE"\neuler_zxz = [0.0, 90.0, 0.0]\n'
             'origin = [1.0, 2.0, 0.5]\nnote = "on its side"\n')
    path = tmp_path / "inch.toml"
    path.write_text(text, encoding="utf-8")
    m = load_profile(path)
    d1 = next(s for s in m.rack if s.label == "D1")
    assert d1.ball_diameter == pytest.approx(MM_PER_INCH)
    assert d1.shank_diameter == pytest.approx(0.7 * MM_PER_INCH)
    assert d1.length == pytest.approx(20.0 * MM_PER_INCH)
    assert m.head is not None and m.head.step == 7.5  # angles are not lengths
    assert m.head.body_diameter == pytest.approx(14.0 * MM_PER_INCH)
    assert [s.name for s in m.setups] == ["FLIPPED", "SIDE"]
    assert m.setups[1].origin == pytest.approx((MM_PER_INCH, 2 * MM_PER_INCH,
                                                0.5 * MM_PER_INCH))
    assert m.stylus.label == "D3"  # the [probe] stylus still found in the converted rack


def test_setups_by_rotation_or_euler_angles(tmp_path: Path) -> None:
    path = edited(tmp_path, CMM, ('name = "FLIPPED"', 'name = "SAMPLE"'), ("[feeds]", '''[[setup]]
name = "FLIPPED"
rotation = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]
note = "part turned over about X, datum face B on the table"

[[setup]]
name = "SIDE_X"
euler_zxz = [90.0, 90.0, 0.0]
origin = [10.0, 0.0, 5.0]

[feeds]'''))
    sample, flipped, side = load_profile(path).setups
    assert sample.name == "SAMPLE"  # the sample's own, renamed
    assert flipped == NamedSetup("FLIPPED", frames.FLIP_X, (0.0, 0.0, 0.0),
                                 "part turned over about X, datum face B on the table")
    assert side.rotation == ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    assert frames.euler_zxz(side.rotation) == pytest.approx((90.0, 90.0, 0.0))
    assert side.origin == (10.0, 0.0, 5.0) and side.note == ""


@pytest.mark.parametrize(("pair", "message"), [
    (('label = "D2"', 'label = "D2_456789"'), r"probe\.stylus\[1\]\.label: expected 1-8"),
    (("shank_diameter = 1.4", "shank_diameter = 0.0"), r"stylus\[1\]\.shank_diameter: .*pos"),
    (("step = 7.5", "step = 7.0"), r"head\.b: expected \[low, high\] on the head's 7 deg"),
    (("a = [0.0, 105.0]", "a = [15.0, 105.0]"), r"head\.a: .*low <= 0 <= high"),
    (("b = [-180.0, 180.0]", "b = [-400.0, 180.0]"), r"head\.b: .*-360 <= low"),
    # the setup added is the profile's second (the sample declares FLIPPED)
    (("[feeds]", '[[setup]]\nname = "side"\neuler_zxz = [0, 90, 0]\n[feeds]'),
     r"setup\[1\]\.name: expected 1-16 of A-Z"),
    (("[feeds]", '[[setup]]\nname = "S"\n[feeds]'),
     r"setup\[1\]\.rotation: expected exactly one of rotation, euler_zxz, found none"),
    (("[feeds]", '[[setup]]\nname = "S"\nrotation = [[1, 0], [0, 1]]\n[feeds]'),
     r"setup\[1\]\.rotation: expected 3 rows of 3 numbers"),
    (("[feeds]", '[[setup]]\nname = "S"\neuler_zxz = [0, 90, 0]\nnote = "a\\nb"\n[feeds]'),
     r"setup\[1\]\.note: expected one line"),
    (("[feeds]", '[[setup]]\nname = "S"\neuler_zxz = [0, 90, 0]\nturn = 1\n[feeds]'),
     r"setup\[1\]\.turn: unknown key"),
    (("[head]", "[head]\nc = [0.0, 90.0]"), r"head\.c: unknown key"),
])
def test_cmm_profile_checks(tmp_path: Path, pair: tuple[str, str], message: str) -> None:
    with pytest.raises(SpecError, match=message):
        load_profile(edited(tmp_path, CMM, pair))


@pytest.mark.parametrize(("pair", "message"), [
    (('label = "D3"', 'label = "D6"'), r"stylus\[1\]\.label: expected a label no other"),
    (("tool_number = 22", "tool_number = 0"), r"stylus\[2\]\.tool_number: expected an int.* >= 1"),
    (('tilt_axis = "A"', 'tilt_axis = "C"'), r"tilt\.tilt_axis: expected one of A, B"),
    (("rotary_range = [-360.0, 360.0]", "rotary_range = [0.0, 0.0]"),
     r"tilt\.rotary_range: .*low < high"),
    (('command = "G68.2"', 'command = "G68"'), r"tilt\.command: expected one of G68\.2, G268"),
])
def test_five_axis_profile_checks(tmp_path: Path, pair: tuple[str, str], message: str) -> None:
    with pytest.raises(SpecError, match=message):
        load_profile(edited(tmp_path, FIVE, pair))


def test_a_rack_label_is_not_the_implicit_probe_label(tmp_path: Path) -> None:
    path = edited(tmp_path, MACHINES / "vmc-fanuc.toml", ("[feeds]", """[[probe.stylus]]
label = "PRB20"
ball_diameter = 3.0
shank_diameter = 2.0
length = 40.0
tool_number = 21

[feeds]"""))
    with pytest.raises(SpecError, match=r"probe\.stylus\[0\]\.label: expected a label no "
                                        r"other stylus has \(the labels so far: PRB20\)"):
        load_profile(path)


def test_haas_tilt_takes_g268(tmp_path: Path) -> None:
    path = edited(tmp_path, FIVE, ('dialect = "fanuc"', 'dialect = "haas"'),
                  ('command = "G68.2"', 'command = "G268"'))
    tilt = load_profile(path).tilt
    assert tilt is not None and tilt.command == "G268"


def test_star_stylus_offset_and_a_cmm_tool_number(tmp_path: Path) -> None:
    path = edited(tmp_path, CMM, ('label = "D2"', 'label = "STAR1"\noffset = [0.0, 10.0, 0.0]'),
                  ('label = "D6"', 'label = "D6"\ntool_number = 4'))
    m = load_profile(path)
    assert m.rack[1].offset == (0.0, 10.0, 0.0) and m.rack[3].tool_number == 4


def test_a_star_stylus_is_never_planned(tmp_path: Path) -> None:
    """A star stylus (a tip offset) is read but never taken: the collision check models
    a stylus along the probe axis, so the planner leaves it out of the rack's order and
    a spec that forces it is refused, saying why."""
    from probegen.planning.styli import rack_order, stylus_named

    profile = edited(tmp_path, FIVE, ('label = "D2"', 'label = "STAR1"\noffset = [0.0, 10.0, 0.0]'))
    m = load_profile(profile)
    assert "STAR1" in [s.label for s in m.styli()]
    assert [s.label for s in rack_order(m)] == ["D6", "D6L", "D3", "D1"]
    with pytest.raises(SpecError, match=r"where: stylus STAR1 .*\(a star stylus\).*: expected "
                                        r"one of D6, D6L, D3, D1"):
        stylus_named(m, "STAR1", "where")
    with pytest.raises(SpecError, match=r"feature\[0\]\.stylus: stylus STAR1 \(.*"
                                        r"\[\[probe\.stylus\]\]\) has a tip offset off the "
                                        r"probe axis \(a star stylus\)"):
        load_spec(spec_with(tmp_path, "STAR1", profile))


def test_rotation_problem() -> None:
    assert rotation_problem(frames.from_euler_zxz(30.0, 60.0, -45.0)) == ""
    assert "mirror" in rotation_problem(((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, -1.0)))
    c, s = math.cos(0.1), math.sin(0.1)
    assert rotation_problem(((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0 + 2e-6))) != ""
    assert rotation_problem(((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0 + 2e-7))) == ""


SPEC = '''[part]
model = "{model}"

[machine]
profile = "{profile}"

[[feature]]
id = "BORE"
kind = "cylinder"
at = [75.0, 50.0, 25.0]
stylus = "{label}"

[[feature]]
id = "TOP"
kind = "plane"
at = [80.0, 80.0, 50.0]
contacts = [[80.0, 20.0, 50.0], [80.0, 80.0, 50.0], [20.0, 80.0, 50.0]]
stylus = "D3"

[[feature]]
id = "BOSS"
kind = "circle"
face = 7
'''


def spec_with(tmp: Path, label: str, profile: Path = FIVE) -> Path:
    path = tmp / "spec.toml"
    path.write_text(SPEC.format(model=(REPO / "samples/bore_block/bore_block.step").as_posix(),
                                profile=profile.as_posix(), label=label), encoding="utf-8")
    return path


def test_spec_stylus_key(tmp_path: Path) -> None:
    spec = load_spec(spec_with(tmp_path, "D2"))
    assert [getattr(f, "stylus", "-") for f in spec.features] == ["D2", "D3", None]
    assert isinstance(spec.features[0], RevolvedSpec)


def test_spec_stylus_key_names_the_labels(tmp_path: Path) -> None:
    with pytest.raises(SpecError, match=r"feature\[0\]\.stylus: expected a stylus of the "
                                        r"machine's rack \(D6, D3, D2, D6L, D1; .*found 'D22' "
                                        r"\(did you mean 'D2'\?\)"):
        load_spec(spec_with(tmp_path, "D22"))


def test_spec_stylus_key_on_a_profile_without_a_rack(tmp_path: Path) -> None:
    with pytest.raises(SpecError, match=r"rack \(PRB20; "):
        load_spec(spec_with(tmp_path, "D2", MACHINES / "vmc-fanuc.toml"))


SECTIONS = ("[[probe.stylus]]", "[head]", "[[setup]]")
KEYS = ("label", "ball_diameter", "shank_diameter", "length", "tool_number", "offset", "a",
        "b", "step", "body_diameter", "name", "rotation", "euler_zxz", "origin", "note",
        "tilt_range", "command")
VALUES = st.one_of(st.integers(-400, 400), st.floats(allow_nan=True, width=32),
                   st.text("ADZ019_ .-\n", max_size=10), st.booleans(),
                   st.lists(st.floats(-200, 200, width=16), max_size=4),
                   st.lists(st.lists(st.integers(-1, 1), min_size=3, max_size=3),
                            min_size=3, max_size=3))


@settings(max_examples=examples(60))
@given(section=st.sampled_from(SECTIONS), key=st.sampled_from(KEYS), value=VALUES,
       drop=st.integers(0, 40))
def test_random_edits_end_in_a_profile_or_a_spec_error(section: str, key: str, value: object,
                                                       drop: int) -> None:
    """A key of a rack entry, the head or a setup set to a random value (or a line of the
    sample dropped): a profile, or a SpecError naming the file."""
    import tempfile
    import tomllib

    text = CMM.read_text(encoding="utf-8") + (
        '\n[[setup]]\nname = "FLIPPED"\nrotation = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]\n')
    lines = text.splitlines()
    candidates = [i for i, line in enumerate(lines) if re.match(r"\w+ = ", line)]
    del lines[candidates[drop % len(candidates)]]
    text = "\n".join(lines) + "\n"
    literal = _toml(value)
    text = text.replace(section, f"{section}\n{key} = {literal}", 1)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "p.toml"
        path.write_text(text, encoding="utf-8")
        try:
            tomllib.loads(text)
        except tomllib.TOMLDecodeError:
            return
        try:
            m = load_profile(path)
        except SpecError as exc:
            assert str(exc).startswith(str(path))
            return
    for s in m.styli():
        assert 0 < s.shank_diameter < s.ball_diameter or s is m.styli()[0]
    labels = [s.label for s in m.styli()]
    assert len(set(labels)) == len(labels)
    for setup in m.setups:
        assert rotation_problem(setup.rotation) == ""


def _toml(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf") \
            if math.isinf(value) else repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace("\n", "\\n") + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return str(value)


@pytest.mark.parametrize(("profile", "dialect", "message"), [
    (CMM, "fanuc", r"found 'fanuc': its \[head\] is a CMM's \(dialect dmis\)"),
    (FIVE, "haas", r"found 'haas': its \[tilt\] command G68\.2 is not a haas command"),
    (FIVE, "dmis", r"its \[tilt\] command G68\.2 is not a dmis command"),
])
def test_a_spec_dialect_the_profile_cannot_drive(tmp_path: Path, profile: Path, dialect: str,
                                                 message: str) -> None:
    path = spec_with(tmp_path, "D2", profile)
    path.write_text(path.read_text().replace(f'profile = "{profile.as_posix()}"',
                                             f'profile = "{profile.as_posix()}"\n'
                                             f'dialect = "{dialect}"', 1))
    with pytest.raises(SpecError, match=r"machine\.dialect: expected a dialect the machine "
                                        r"profile .*" + message):
        load_spec(path)


def test_a_cmm_rack_without_tool_numbers_is_no_machine_tools(tmp_path: Path) -> None:
    text = CMM.read_text(encoding="utf-8")
    path = tmp_path / "headless.toml"
    path.write_text(text[:text.index("[head]")] + text[text.index("[feeds]"):],
                    encoding="utf-8")
    spec = spec_with(tmp_path, "D2", path)
    spec.write_text(spec.read_text().replace(f'profile = "{path.as_posix()}"',
                                             f'profile = "{path.as_posix()}"\n'
                                             'dialect = "linuxcnc"'))
    with pytest.raises(SpecError, match=r"found 'linuxcnc': its \[\[probe.stylus\]\] entries "
                                        r"have no tool_number"):
        load_spec(spec)


def sample_spec(tmp: Path, profile: Path) -> Path:
    """The bore_block sample spec on ``profile``."""
    source = REPO / "samples" / "bore_block" / "bore_block.toml"
    spec = tmp / "spec.toml"
    spec.write_text(source.read_text(encoding="utf-8").replace(
        '"bore_block.step"', f'"{(source.parent / "bore_block.step").as_posix()}"').replace(
        '"../machines/vmc-fanuc.toml"', f'"{profile.as_posix()}"'), encoding="utf-8")
    return spec


def test_the_five_axis_sample_measures_the_bore_block(tmp_path: Path) -> None:
    """Today's bore_block spec on the five-axis sample (its [probe] stylus D6): compiled,
    run on the virtual machine with the part in place, ingested: every diameter within
    1 um of nominal (the bore's tolerance, [0, +0.025], starts at nominal: a tenth of a
    micrometre under it is NOT OK, the ingest's exit code 8)."""
    import json

    from probegen.cli.app import main

    spec = sample_spec(tmp_path, FIVE)
    program, log = tmp_path / "prog.nc", tmp_path / "run.log"
    assert main(["-q", "compile", str(spec), "-o", str(program)]) == ExitCode.OK
    assert main(["-q", "sim", str(program), "--spec", str(spec), "-o", str(log)]) == 0
    assert main(["-q", "ingest", str(log), "--spec", str(spec), "-o", str(tmp_path)]) in (
        ExitCode.OK, ExitCode.NOT_OK)
    results = json.loads((tmp_path / "results.json").read_text(encoding="utf-8"))
    features = results["features"]
    assert [f["id"] for f in features] == ["BORE", "BOSS"]
    diameters = [c for f in features for c in f["characteristics"]
                 if c["name"].startswith("D")]
    assert len(diameters) == 4 and all(abs(c["deviation"]) < 0.001 for c in diameters)


def test_the_cmm_sample_runs_the_bore_block_on_the_virtual_cmm(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The same spec on the CMM sample (its [probe] stylus D3) to DMIS: the virtual CMM
    runs it without an alarm, every planned touch made, an output the strict reader
    takes."""
    from probegen.cli.app import main
    from probegen.results import parse_dmis_output

    spec = sample_spec(tmp_path, CMM)
    program, output = tmp_path / "prog.dmi", tmp_path / "out.dms"
    assert main(["-q", "compile", str(spec), "-o", str(program)]) == ExitCode.OK
    assert main(["-q", "sim", str(program), "--spec", str(spec), "-o", str(output)]) == 0
    assert "(22 touches)" in capsys.readouterr().err
    assert parse_dmis_output(output.read_text(encoding="latin-1"), strict=True) is not None
