"""probegen's Macro B macro library and the compact program form that calls it.

Planted truth and tolerance as in test_haas_closed_loop.py (the part off G54 by a small
shift and turn, a lobing probe), compared exactly: a compact program (G65 calls to
O8000-O8002) and the inline program of the same spec command the same positions in the
same order, so their DPRNT logs read to the same records (touches with kind, feature,
index and X Y Z, centres, results, errors: the compact log is format V2, its touches
name their feature by number, so the text differs), ``results.json`` is the same text,
their touches the same count and the variables they leave the same, save the commons
#base+90..#base+96 each form uses in its own way.  When a move fails (no touch, an
unexpected trigger) both print the same ``ERR`` record and stop on the same macro alarm.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, assert_golden
from test_haas_closed_loop import LOBING, SPECS, WORK, placed_part, results

from probegen import cad
from probegen.cli.app import ExitCode, main
from probegen.dialects import get_dialect
from probegen.dialects.macro_library import COMMONS
from probegen.errors import UnsupportedError
from probegen.machine.probe_model import ProbeModel
from probegen.planning import plan_program
from probegen.results import DprntLog, parse_dprnt
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import SimResult, VirtualMachine, run_text
from probegen.spec.model import load_spec

GOLDEN = REPO / "tests" / "golden" / "macros"
SPHERE = REPO / "samples" / "sphere25" / "sphere_test.toml"


def library(tmp: Path, dialect: str = "fanuc", options: tuple[str, ...] = ()) -> Path:
    """The default library (O8000, #100, mm) for a control with ``options``, written
    into ``tmp``."""
    tmp.mkdir(exist_ok=True)
    for name, text in get_dialect(dialect).library_files(8000, 100, "mm", options).items():
        (tmp / name).write_text(text, encoding="ascii")
    return tmp


def forms(spec_path: Path, dialect: str) -> tuple[str, str]:
    """The inline and the compact program of a spec."""
    program = plan_program(load_spec(spec_path), runtime_variables=True).program
    inline = get_dialect(dialect).generate(program)
    d = get_dialect(dialect)
    d.compact = True
    return inline, d.generate(program)


def records(log: DprntLog) -> tuple[object, ...]:
    """What a log says, without the lines it said it on: the program and its runs'
    identities, every touch (kind, feature, index, X Y Z), centre, result and error."""
    return (log.program, log.complete, [(r.program, r.identity) for r in log.runs],
            [(t.kind, t.feature, t.index, t.xyz, t.run) for t in log.touches],
            [(c.feature, c.xyz) for c in log.centres], [(r.feature, r.values)
                                                       for r in log.results],
            [(e.code, e.feature, e.index) for e in log.errors],
            [c.fingerprint for c in log.calibrations])


def same_records(inline: SimResult, compact: SimResult) -> DprntLog:
    """Both logs read without a diagnostic to the same records; the compact one is V2."""
    a, b = (parse_dprnt(res.output, strict=True) for res in (inline, compact))
    assert records(b) == records(a)
    assert [line.split()[2] for line in (inline.output, compact.output)
            for line in line.splitlines() if line.startswith("PGSTART")] == ["V1", "V2"]
    assert not a.features and {f.feature for f in b.features} >= {t.feature for t in b.touches}
    return b


def run(text: str, part: PlacedPart, ball: float, control: str,
        lib: Path | None) -> SimResult:
    vm = VirtualMachine(part, ProbeModel(ball, LOBING))
    return run_text(text, vm, kind="macrob", work_offset=WORK, control=control,
                    program_dir=lib)


def sphere_part(dz: float) -> PlacedPart:
    """The sphere test's part at G54, ``dz`` mm higher than the spec says."""
    model = load_spec(SPHERE).model
    assert model is not None
    return PlacedPart.from_model(cad.load_step(model), rotation=np.eye(3),
                                 translation=np.array(WORK) + (0.0, 0.0, dz))


@pytest.fixture(scope="module")
def bore_block(tmp_path_factory: pytest.TempPathFactory) -> cad.Model:
    from conftest import sample_script

    path = tmp_path_factory.mktemp("macros") / "bore+0.03.step"
    sample_script("bore_block").main(path, bore_diameter=50.03, boss_diameter=20.0)
    return cad.load_step(path)


@pytest.mark.parametrize("dialect", ["fanuc", "haas"])
def test_library_matches_golden(dialect: str) -> None:
    """The library as whole files, as the sample profile (option #3004) has it written;
    Haas runs the Fanuc text, so it is the same one."""
    files = get_dialect(dialect).library_files(8000, 100, "mm", ("#3004", "G68"))
    assert list(files) == ["O8000.nc", "O8001.nc", "O8002.nc"]
    for name, text in files.items():
        assert_golden(GOLDEN / name, text)


def test_at_most_9999_features_in_a_compact_program() -> None:
    """The library prints a feature's number with 4 digits: the 10000th is refused."""
    d = get_dialect("fanuc")
    d.compact = True
    d.lib = d.library_for(8000, 100, "mm")
    calls = [{"call": True, "feature": f"F{k}", "move": 1} for k in range(1, 10001)]
    bound = d.bind(calls[:-1])
    assert bound[-4:] == [{"kind": "bind", "feature": "F9999", "number": 9999},
                          {"kind": "assign", "var": "#192", "value": "0"},  # move counter
                          {"kind": "assign", "var": "#194", "value": "9999"}, calls[-2]]
    with pytest.raises(UnsupportedError, match="at most 9999 features .* found more at F10000"):
        d.bind(calls)


def test_library_follows_the_profile() -> None:
    """Numbers, variable base and units move the text; the program number is its name."""
    files = get_dialect("fanuc").library_files(7100, 600, "inch")
    assert list(files) == ["O7100.nc", "O7101.nc", "O7102.nc"]
    text = files["O7101.nc"]
    assert "O7101(PROBEGEN TOUCH)" in text and "F#690" in text and "#693=#693+1" in text
    assert "GE0.00020" in text and "X#5061[35]" in text  # the check sum and prints in inch
    assert "#3004" not in text  # no option #3004: no lock
    with pytest.raises(UnsupportedError, match="no macro library"):
        get_dialect("dmis").library_files(8000, 100, "mm")


def test_compact_program_matches_golden() -> None:
    inline, compact = forms(SPHERE, "fanuc")
    assert_golden(GOLDEN / "sphere_test.compact.nc", compact)
    # one call per inline touch (alarm 3001) and per protected move (alarm 3002)
    points = compact.count("G65P8002")
    assert compact.count("G65P8001") + points == inline.count("#3000=1(") > points > 0
    assert compact.count("G65P8000") + points == inline.count("#3000=2(") > 0
    assert "G31" not in compact and len(compact) < len(inline) / 2


@pytest.mark.parametrize("dialect", ["fanuc", "haas"])
@pytest.mark.parametrize("spec_path", SPECS, ids=lambda p: p.stem)
def test_compact_measures_as_inline(spec_path: Path, dialect: str, bore_block: cad.Model,
                                    tmp_path: Path) -> None:
    spec = load_spec(REPO / spec_path)
    inline_text, compact_text = forms(REPO / spec_path, dialect)
    assert "G65P800" in compact_text and "G31" not in compact_text
    part = placed_part(spec, bore_block)
    ball = spec.machine.probe.ball_radius
    inline = run(inline_text, part, ball, dialect, None)
    lib = library(tmp_path / "lib", dialect, spec.machine.controller.options)
    compact = run(compact_text, part, ball, dialect, lib)
    assert inline.alarm is None and compact.alarm is None, (inline.alarm, compact.alarm)
    assert compact.touches == inline.touches > 0
    log = same_records(inline, compact)
    assert log.complete and len(log.touches) == inline.touches
    base = spec.machine.controller.variable_base
    own = range(base + COMMONS[0], base + COMMONS[-1] + 1)
    assert {k: v for k, v in compact.variables.items() if k not in own and k > 33} == \
        {k: v for k, v in inline.variables.items() if k not in own and k > 33}
    compact_doc = results(compact, spec, tmp_path / "compact")
    assert compact_doc == results(inline, spec, tmp_path / "inline")
    assert compact_doc["complete"] and compact_doc["features"]


@pytest.mark.parametrize(("shift", "code", "alarm"), [
    (-20.0, "NOTOUCH", "3001 PROBE DID NOT TOUCH"),
    (5.0, "COLLISION", "3002 UNEXPECTED PROBE TRIGGER")])
def test_failed_move_as_inline(shift: float, code: str, alarm: str, tmp_path: Path) -> None:
    """The sphere lowered (no touch) or raised (the approach hits it): the same ERR line
    with the feature and the move's number, the same alarm."""
    spec = load_spec(SPHERE)
    inline_text, compact_text = forms(SPHERE, "fanuc")
    part = sphere_part(shift)
    ball = spec.machine.probe.ball_radius
    inline = run(inline_text, part, ball, "fanuc", None)
    compact = run(compact_text, part, ball, "fanuc", library(tmp_path))
    assert inline.alarm is not None and compact.alarm is not None
    assert compact.alarm.split(" (line")[0] == inline.alarm.split(" (line")[0] == alarm
    log = same_records(inline, compact)
    assert [(e.code, e.feature) for e in log.errors] == [(code, "SPH1")]
    assert f"\nFEAT SPH1 1\nERR {code} 1 1\n" in compact.output  # printed by the library


def test_missing_library_is_named(tmp_path: Path) -> None:
    _, compact_text = forms(SPHERE, "fanuc")
    spec = load_spec(SPHERE)
    res = run(compact_text, sphere_part(0.0), spec.machine.probe.ball_radius, "fanuc", tmp_path)
    assert res.alarm is not None and res.alarm.startswith("76 PROGRAM NOT FOUND (O8002)")
    assert res.touches == 0


def test_cli_compact_compile_and_sim(in_repo: Path, tmp_path: Path,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    """compile --compact writes the library beside the program; sim finds it there or
    through --library; probegen macros writes the same files."""
    out = tmp_path / "c"
    assert main(["compile", str(SPHERE), "--compact", "-d", "fanuc", "-o", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["O8000.nc", "O8001.nc", "O8002.nc",
                                                        "sphere_test.nc"]
    assert (out / "O8001.nc").read_text() == (GOLDEN / "O8001.nc").read_text()
    log = tmp_path / "run.log"
    assert main(["sim", str(out / "sphere_test.nc"), "--spec", str(SPHERE),
                 "-o", str(log)]) == ExitCode.OK
    alone = tmp_path / "alone"
    alone.mkdir()
    (alone / "p.nc").write_text((out / "sphere_test.nc").read_text())
    capsys.readouterr()
    assert main(["sim", str(alone / "p.nc"), "--spec", str(SPHERE),
                 "-o", str(tmp_path / "x.log")]) == ExitCode.SIM_ALARM
    assert "PROGRAM NOT FOUND (O8002)" in capsys.readouterr().err
    assert main(["sim", str(alone / "p.nc"), "--spec", str(SPHERE), "--library", str(out),
                 "-o", str(tmp_path / "y.log")]) == ExitCode.OK
    assert (tmp_path / "y.log").read_text() == log.read_text()
    both = tmp_path / "b"
    assert main(["compile", str(SPHERE), "--compact", "-d", "dmis", "-d", "haas",
                 "-o", str(both)]) == 0
    assert sorted(p.name for p in both.iterdir()) == ["O8000.nc", "O8001.nc", "O8002.nc",
                                                      "sphere_test.dmi", "sphere_test.haas.nc"]
    inline = tmp_path / "i"
    assert main(["compile", str(SPHERE), "--inline", "-d", "fanuc", "-o", str(inline)]) == 0
    assert [p.name for p in inline.iterdir()] == ["sphere_test.nc"]
    assert main(["macros", "-d", "haas", "-o", str(tmp_path / "m")]) == ExitCode.OK
    assert (tmp_path / "m" / "O8000.nc").read_text() == (GOLDEN / "O8000.nc").read_text()
    assert main(["macros", "-d", "dmis", "-o", str(tmp_path / "d")]) == ExitCode.UNSUPPORTED
    capsys.readouterr()
    assert main(["compile", str(SPHERE), "--compact", "-o", "-"]) == ExitCode.ERROR
    assert "macro library" in capsys.readouterr().err


def test_library_numbers_are_checked(in_repo: Path, tmp_path: Path,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    """A library in O9000-O9999 is refused unless the profile's range allows it."""
    profile = (REPO / "samples" / "machines" / "vmc-fanuc.toml").read_text()
    assert "[controller]" in profile
    bad = tmp_path / "m.toml"
    bad.write_text(profile.replace("[controller]", "[controller]\nlibrary_number = 9000"))
    capsys.readouterr()
    assert main(["macros", "-o", str(tmp_path / "o"), "--machine", str(bad)]) == ExitCode.SPEC
    err = capsys.readouterr().err
    assert "controller.library_number (O9000)" in err and "protected" in err
    assert not (tmp_path / "o").exists()
    good = tmp_path / "g.toml"
    good.write_text(profile.replace("[controller]", "[controller]\nlibrary_number = 7000"))
    assert main(["macros", "-o", str(tmp_path / "o"), "--machine", str(good)]) == ExitCode.OK
    names = sorted(p.name for p in (tmp_path / "o").iterdir())
    assert names == ["O7000.nc", "O7001.nc", "O7002.nc"]
