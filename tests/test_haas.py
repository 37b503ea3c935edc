"""The Haas dialect: Fanuc's program but for the overrides ``Haas`` documents."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest
from conftest import REPO

from probegen import ir
from probegen.cli.app import ExitCode, main
from probegen.dialects import Fanuc, Haas, get_dialect
from probegen.errors import UnsupportedError
from probegen.machine.probe_model import ProbeModel
from probegen.planning import plan_program
from probegen.results import parse_dprnt
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import VirtualMachine, program_control, run_text
from probegen.spec.model import load_spec

SPECS = sorted(p for p in (REPO / "samples").glob("*/*.toml")
               if "[[feature]]" in p.read_text(encoding="utf-8"))
SETUP = ir.Setup(
    program_number=7, program_name="T", units="mm", work_offset="G54", clearance_z=50.0,
    ball_diameter=6.0, shank_diameter=4.0, tool_number=20, tool_change=False,
    position_feed=2000.0, probe_feed=300.0, probe_on=(), probe_off=(), variable_base=100,
    reset_codes=("G17", "G69", "G15", "G50.1"), probe_length=40.0,
)


def setup(**changes: object) -> ir.Setup:
    return ir.Setup(**{**{f: getattr(SETUP, f) for f in SETUP.__slots__}, **changes})


def test_haas_is_a_registered_fanuc_variant() -> None:
    haas = get_dialect("haas")
    assert isinstance(haas, Haas) and isinstance(haas, Fanuc)
    assert haas.RUNTIME_VARIABLES and not haas.LOCAL_FRAMES
    assert haas.EXTENSION.endswith(".nc") and haas.EXTENSION != Fanuc.EXTENSION


@pytest.mark.parametrize("spec_path", SPECS, ids=lambda p: p.stem)
def test_only_the_reset_codes_differ_from_fanuc(in_repo: Path, spec_path: Path) -> None:
    program = plan_program(load_spec(spec_path.relative_to(REPO)),
                           runtime_variables=True).program
    fanuc = get_dialect("fanuc").generate(program).splitlines()
    haas = get_dialect("haas").generate(program).splitlines()
    differ = [(f, h) for f, h in zip(fanuc, haas, strict=True) if f != h]
    # the sample profile lists G15 and G50.1 among its reset codes but declares neither
    # option: both programs leave them out, so the reset blocks are the same (the Haas
    # words for them: test_reset_codes_in_haas_words)
    assert "G90 G17 G40 G49 G80 G94 G69" in fanuc and "G90 G17 G40 G49 G80 G94 G69" in haas
    # only a radius wear correction differs: Haas D offsets are diameters
    wear = [(f, h) for f, h in differ
            if "G10 L13" in f and h == re.sub(r" R(#\d+)$", r" R[2.0*\1]", f)]
    assert len(wear) == len(differ)
    assert len(wear) == (1 if "update_tool" in spec_path.read_text(encoding="utf-8") else 0)


def test_haas_refuses_a_flag_in_its_reserved_variables() -> None:
    check = ir.Check("B", "plane", (), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.0, False, 3.0, 0.0,
                     (), "flag", 560)
    with pytest.raises(UnsupportedError, match="cannot write #560 .on_out_of_tolerance of "
                                               "feature B.: Haas keeps #550-#599"):
        get_dialect("haas").generate(ir.Program(setup(), (check,)))


def test_reset_codes_in_haas_words() -> None:
    text = get_dialect("haas").generate(ir.Program(setup(), ()))
    assert "\nG90 G17 G69 G100\n" in text


@pytest.mark.parametrize("base", [100, 600, 800])
def test_free_variable_ranges_are_used(base: int) -> None:
    text = get_dialect("haas").generate(ir.Program(setup(variable_base=base),
                                                   (ir.Assign("A", 1.0),)))
    assert f"(USES #{base}-#{base + 93})" in text and f"#{base}=1.0000" in text


@pytest.mark.parametrize(("base", "reserved"), [(500, "#550-#599"), (520, "#550-#599"),
                                                (650, "#700-#749"), (700, "#700-#749")])
def test_reserved_variable_ranges_are_refused(base: int, reserved: str) -> None:
    with pytest.raises(UnsupportedError, match=f"Haas keeps {reserved}"):
        get_dialect("haas").generate(ir.Program(setup(variable_base=base), ()))


def test_haas_program_runs_on_the_virtual_machine(in_repo: Path) -> None:
    """The Haas text measures on a Haas control as Fanuc's does on a Fanuc control; with
    the polar and mirror options declared (G15 and G50.1 in the reset block) each stops on
    the other's control with alarm 10 at its reset block (line 7); without them
    (the sample profile) the Fanuc program runs on the Haas control too."""
    spec = load_spec(Path("samples/sphere25/sphere_test_iso.toml"))
    plain = plan_program(spec, runtime_variables=True).program
    res = run_text(get_dialect("fanuc").generate(plain), vm(), kind="macrob", control="haas")
    assert res.alarm is None and res.touches == 25
    program = dataclasses.replace(plain, setup=dataclasses.replace(
        plain.setup, options=(*(plain.setup.options or ()), "G15", "G50.1")))
    texts = {name: get_dialect(name).generate(program) for name in ("fanuc", "haas")}
    logs = []
    for name in ("fanuc", "haas"):
        res = run_text(texts[name], vm(), kind="macrob", control=name)
        assert res.alarm is None, res.alarm
        logs.append(parse_dprnt(res.output, strict=True))
    fanuc, haas = logs
    assert len(haas.touches) == 25 and haas.complete
    assert [t.xyz for t in haas.touches] == [t.xyz for t in fanuc.touches]
    for name, control, word in (("haas", "fanuc", "G100"), ("fanuc", "haas", "G15")):
        res = run_text(texts[name], vm(), kind="macrob", control=control)
        assert res.alarm == f"10 IMPROPER G-CODE ({word}) (line 7)" and res.touches == 0


def vm() -> VirtualMachine:
    """A 25 mm sphere near the origin, a 3 mm ball."""
    return VirtualMachine(PlacedPart.from_spheres([[0.1, -0.2, 0.05]], [12.5]), ProbeModel(3.0))


@pytest.mark.parametrize(("block", "alarm"), [
    ("G100", None), ("G50", None), ("G69", None), ("G101 X0 Y0", "9010"),
    ("G50.1", "10"), ("G15", "10"), ("G16", "10"), ("G51.1 X0", "10")])
def test_the_haas_control_knows_the_haas_g_codes(block: str, alarm: str | None) -> None:
    """Haas G-code list: G100/G101 cancel/set mirror image (G101 is not modelled: 9010),
    no G50.1/G51.1, no polar coordinates G15/G16 (alarm 10, as the control's)."""
    res = run_text(f"%\nO1\nG21 G90\n{block}\nM30\n%\n", vm(), kind="macrob",
                   control="haas")
    assert (None if res.alarm is None else res.alarm.split()[0]) == alarm, res.alarm


def test_sim_picks_the_haas_control_by_the_file_name(in_repo: Path, tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    spec = str(mirror_option_spec(tmp_path))  # G50.1 declared: G100 in the reset block
    assert main(["compile", spec, "-d", "haas", "-o", str(tmp_path), "-q"]) == ExitCode.OK
    program = tmp_path / "spec.haas.nc"
    assert program_control(program) == "haas"
    assert main(["sim", str(program), "--spec", spec, "-o", str(tmp_path / "run.log"),
                 "-q"]) == ExitCode.OK
    assert "PGEND" in (tmp_path / "run.log").read_text()
    renamed = tmp_path / "O01002.nc"
    renamed.write_bytes(program.read_bytes())
    capsys.readouterr()
    assert main(["sim", str(renamed), "--spec", spec, "-o", "-", "-q"]) == ExitCode.SIM_ALARM
    assert "alarm 10 IMPROPER G-CODE (G100)" in capsys.readouterr().err
    assert main(["sim", str(renamed), "--control", "haas", "--spec", spec,
                 "-o", str(tmp_path / "renamed.log"), "-q"]) == ExitCode.OK


def mirror_option_spec(tmp_path: Path) -> Path:
    """The ISO sphere test on the sample machine with the mirror option declared."""
    machines = REPO / "samples" / "machines"
    profile = (machines / "vmc-fanuc.toml").read_text(encoding="utf-8")
    assert "\noptions = [" in profile
    profile = profile.replace("\noptions = [", '\noptions = ["G50.1", ', 1)
    (tmp_path / "machine.toml").write_text(profile, encoding="utf-8")
    source = REPO / "samples" / "sphere25" / "sphere_test_iso.toml"
    spec = source.read_text(encoding="utf-8").replace("../machines/vmc-fanuc.toml",
                                                      "machine.toml")
    (tmp_path / "spec.toml").write_text(spec, encoding="utf-8")
    return tmp_path / "spec.toml"


def test_rotary_sim_runs_the_haas_rotary_program(in_repo: Path, tmp_path: Path) -> None:
    """``rotary sim`` picks the Haas control by the file name as ``sim`` does: the Haas
    M4 program gives the Fanuc program's log."""
    spec, logs = "samples/rotary/m4.toml", []
    for dialect in ("fanuc", "haas"):
        out = tmp_path / dialect
        assert main(["rotary", "plan", spec, "-d", dialect, "-o", str(out), "-q"]) == 0
        (program,) = out.glob("m4*.nc")
        assert main(["rotary", "sim", str(program), "--spec", spec, "--errors",
                     "samples/machines/five-axis-bc.toml", "-o", str(out / "run.log"),
                     "-q"]) == ExitCode.OK
        logs.append((out / "run.log").read_text())
    assert logs[0] == logs[1] and "PGEND" in logs[1]
