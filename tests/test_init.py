"""``probegen init`` (issue 17, item 3): a spec skeleton that compiles unchanged.

Every sample model and every NIST model gets a skeleton that ``compile`` turns into a
Fanuc and a DMIS program without an error; the skeleton of the bore block is golden
(``tests/golden/init/bore_block.toml``, the two path lines as written from the test's
folder); an existing file is never overwritten.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from conftest import REPO, SHARED, assert_golden

from probegen.cli.app import main
from probegen.errors import ExitCode
from probegen.spec.actions import PlanarSpec
from probegen.spec.model import FreeformSpec, RevolvedSpec, load_spec

MACHINE = REPO / "samples/machines/vmc-fanuc.toml"
SAMPLES = {"sphere25": (1, 0, 0), "bore_block": (2, 6, 0), "revolved_block": (4, 6, 0),
           "freeform": (1, 4, 1)}
"""Sample -> revolved, plane and free-form features in its skeleton (sphere25's base disc,
its side and its top, is left out: with the profile's 50 mm stylus the probe body, 40 mm
across, would meet the reference sphere above it)."""
NIST = sorted((SHARED / "ref/nist-step").glob("*.stp"))
DCX = SHARED / "ref/nist-ippdme/DCXpart/STEP_AP214/DaimlerChryslerTestPartAP214.stp"
ID = re.compile(r"[A-Z][A-Z0-9]{0,11}\Z")


def _init(model: Path, spec: Path) -> str:
    assert main(["-q", "init", str(model), "--machine", str(MACHINE), "-o", str(spec)]) == 0
    return spec.read_text(encoding="ascii")


def _compiles(spec: Path, folder: Path) -> None:
    code = main(["-q", "compile", str(spec), "-d", "fanuc", "-d", "dmis", "-o", str(folder)])
    assert code == ExitCode.OK
    assert (folder / f"{spec.stem}.nc").is_file() and (folder / f"{spec.stem}.dmi").is_file()


def _kinds(spec: Path) -> tuple[int, int, int]:
    features = load_spec(spec).features
    ids = [f.id for f in features]
    assert len(set(ids)) == len(ids) and all(ID.match(i) for i in ids)
    return (sum(isinstance(f, RevolvedSpec) for f in features),
            sum(isinstance(f, PlanarSpec) for f in features),
            sum(isinstance(f, FreeformSpec) for f in features))


@pytest.mark.parametrize("sample", sorted(SAMPLES))
def test_sample_skeleton_compiles_unchanged(sample: str, tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / f"{sample}.toml"
    text = _init(REPO / f"samples/{sample}/{sample}.step", spec)
    said = capsys.readouterr().out
    assert said.startswith(f"wrote {spec}: ")
    assert _kinds(spec) == SAMPLES[sample]
    for block in text.split("\n\n[[feature]]")[1:]:  # each feature: its tolerance line
        assert "\n# tolerance = { " in block
    _compiles(spec, tmp_path / "out")


def test_bore_block_skeleton_golden(tmp_path: Path) -> None:
    text = _init(REPO / "samples/bore_block/bore_block.step", tmp_path / "bore_block.toml")
    assert "\nmodel = \"" in text and "\nprofile = \"" in text
    lines = [re.sub(r'^(model|profile) = ".*/(samples/.+)"$', r'\1 = "<repo>/\2"', line)
             for line in text.splitlines()]
    assert_golden(REPO / "tests/golden/init/bore_block.toml", "\n".join(lines) + "\n")


def test_skeleton_says_why_each_left_out_feature_is(tmp_path: Path) -> None:
    text = _init(REPO / "samples/bore_block/bore_block.step", tmp_path / "b.toml")
    left = [line for line in text.splitlines() if line.startswith("#   ")]
    assert left == ["#   P5 plane (face 5, normal (0.000, 0.000, -1.000)): faces down: the "
                    "probe (along Z) cannot reach it: needs an orientation or a setup"]


def test_init_never_overwrites(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "mine.toml"
    spec.write_text("# my edits\n", encoding="ascii")
    code = main(["init", str(REPO / "samples/bore_block/bore_block.step"), "--machine",
                 str(MACHINE), "-o", str(spec)])
    assert code == ExitCode.OUTPUT
    assert spec.read_text(encoding="ascii") == "# my edits\n"
    assert "never overwritten" in capsys.readouterr().err


def test_init_needs_a_machine() -> None:
    assert main(["init", str(REPO / "samples/bore_block/bore_block.step")]) == ExitCode.USAGE


@pytest.mark.skipif(not NIST, reason="no ../shared/ref/nist-step")
@pytest.mark.parametrize("model", [*NIST, DCX], ids=lambda p: p.stem)
def test_nist_skeleton_compiles_unchanged(model: Path, tmp_path: Path) -> None:
    """The whole planner on every NIST model and the DCX part: about 8 min for all
    twelve on the shared 2-core machine (CTC 2 and 4 the longest);
    benchmarks/bench_init.py prints the figures (docs/benchmarks.md)."""
    if not model.exists():
        pytest.skip(f"{model} is not here")
    spec = tmp_path / f"{model.stem}.toml"
    text = _init(model, spec)
    assert sum(_kinds(spec)) == text.count("\n[[feature]]\n")
    _compiles(spec, tmp_path / "out")


def test_plan_all_revolved_writes_the_programs(tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    model = SHARED / "ref/nist-step/nist_ftc_11_asme1_rb.stp"
    if not model.exists():
        pytest.skip("no NIST FTC 11")
    # the 1.5 mm plate on parallels 10 mm high (on the table its bore and boss would be
    # left out: the ball would reach into it; tests/test_nist_revolved.py)
    code = main(["-q", "plan", "--all-revolved", str(model), "--machine", str(MACHINE),
                 "--raised", "10", "-d", "fanuc", "-d", "dmis", "-o", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == ExitCode.OK
    assert out.startswith("feature  kind")  # the comparison table is kept
    for ext in ("nc", "dmi"):
        assert f"wrote {tmp_path / model.stem}.{ext}" in out
    total = re.search(r"^total +\d+ +(\d+) ", out, re.M)
    assert total is not None and int(total[1]) == 40  # FTC 11: 3 features, 40 touches
    written = (tmp_path / f"{model.stem}_all_revolved.toml").read_text()
    assert "\nraised = 10.0   # mm above the machine table\n" in written
    _runs_without_alarm(model, tmp_path / f"{model.stem}.nc", "macrob", 40)
    _runs_without_alarm(model, tmp_path / f"{model.stem}.dmi", "dmis", 40)


def _runs_without_alarm(model: Path, program: Path, kind: str, touches: int) -> None:
    """The program on the virtual machine (Macro B) or CMM (DMIS), the part at its
    nominal place and a perfect probe of the profile's ball: no alarm, every touch."""
    from probegen import cad
    from probegen.machine.probe_model import ProbeModel
    from probegen.machine.profile import load_profile
    from probegen.sim.contact import PlacedPart
    from probegen.sim.vm import VirtualMachine, run_text

    vm = VirtualMachine(PlacedPart.from_model(cad.load_step(model)),
                        ProbeModel(load_profile(MACHINE).probe.ball_radius))
    result = run_text(program.read_text(encoding="ascii"), vm, kind=kind)
    assert result.alarm is None
    assert result.touches == touches


def test_plan_dialect_needs_output(in_repo: Path) -> None:
    code = main(["plan", "samples/bore_block/bore_block.step", "--all-revolved",
                 "--machine", "samples/machines/vmc-fanuc.toml", "-d", "dmis"])
    assert code == ExitCode.ERROR


def test_a_model_with_nothing_measurable_says_so(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """The M6 screw (build123d docs): every face too narrow for the 6 mm ball, facing
    down or tilted: the skeleton has no feature, lists each one left out, and init says
    that such a spec does not compile."""
    model = SHARED / "ref/parts/build123d_m6x12_countersunk_screw.step"
    if not model.exists():
        pytest.skip("no ../shared/ref/parts")
    text = _init(model, tmp_path / "screw.toml")
    out = capsys.readouterr().out
    assert "0 features (0 revolved, 0 planes, 0 free-form), 18 left out" in out
    assert "a spec needs one [[feature]] at least to compile" in out
    assert "[[feature]]\n" not in text
    assert sum(line.startswith("#   ") for line in text.splitlines()) == 18
