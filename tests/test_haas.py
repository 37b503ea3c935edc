"""The Haas dialect: Fanuc's program but for the overrides ``Haas`` documents."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from conftest import REPO

from probegen import ir
from probegen.dialects import Fanuc, Haas, get_dialect
from probegen.errors import UnsupportedError
from probegen.machine.probe_model import ProbeModel
from probegen.planning import plan_program
from probegen.results import parse_dprnt
from probegen.sim.contact import PlacedPart
from probegen.sim.macrob.machine import Settings, run_program
from probegen.sim.vm import HOME, VirtualMachine
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
    reset = ("G90 G17 G40 G49 G80 G94 G69 G15 G50.1", "G90 G17 G40 G49 G80 G94 G69 G100")
    # and a radius wear correction: Haas D offsets are diameters
    wear = [(f, h) for f, h in differ[1:]
            if "G10 L13" in f and h == re.sub(r" R(#\d+)$", r" R[2.0*\1]", f)]
    assert differ[0] == reset and len(wear) == len(differ) - 1
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
    """The Haas text measures as Fanuc's does; the VM reads Haas G100 as Fanuc G50.1."""
    spec = load_spec(Path("samples/sphere25/sphere_test_iso.toml"))
    program = plan_program(spec, runtime_variables=True).program
    logs = []
    for name, aliases in (("fanuc", {}), ("haas", {100.0: 50.1})):
        part = PlacedPart.from_spheres([[0.1, -0.2, 0.05]], [12.5])
        vm = VirtualMachine(part, ProbeModel(3.0))
        res = run_program(get_dialect(name).generate(program), vm,
                          variables={11020: 0.0, 10020: 0.0},
                          settings=Settings(home=HOME, g_aliases=aliases))
        assert res.alarm is None, res.alarm
        logs.append(parse_dprnt(res.output, strict=True))
    fanuc, haas = logs
    assert len(haas.touches) == 25 and haas.complete
    assert [t.xyz for t in haas.touches] == [t.xyz for t in fanuc.touches]
