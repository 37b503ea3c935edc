"""Dialects: capabilities, number formatting, and UnsupportedError for what they lack."""

from __future__ import annotations

import pytest

from probegen import ir
from probegen.dialects import get_dialect
from probegen.errors import UnsupportedError

SETUP = ir.Setup(
    program_number=7, program_name="T", units="mm", work_offset="G54", clearance_z=50.0,
    ball_diameter=6.0, shank_diameter=4.0, tool_number=20, tool_change=False,
    position_feed=2000.0, probe_feed=300.0, probe_on=(), probe_off=(), variable_base=500,
    reset_codes=("G17",), probe_length=40.0,
)


def program(*nodes: ir.Node) -> ir.Program:
    return ir.Program(SETUP, nodes)


@pytest.mark.parametrize(
    ("node", "expected"),
    [
        (ir.Move((ir.Var("A"), 0.0, 0.0), ir.MoveMode.PROTECTED),
         {"fanuc": None, "dmis": UnsupportedError}),
        (ir.LocalFrame("C", "F"), {"fanuc": UnsupportedError, "dmis": None}),
        (ir.Assign("A", 1.0), {"fanuc": None, "dmis": UnsupportedError}),
        (ir.ReportCentre("F", (ir.Var("A"), ir.Var("B"), ir.Var("C"))),
         {"fanuc": None, "dmis": UnsupportedError}),
        (ir.ReportCentre("F", (ir.Var("A", 1.0), ir.Var("B"), ir.Var("C"))),
         {"fanuc": UnsupportedError, "dmis": UnsupportedError}),
    ],
    ids=["var-move", "local-frame", "assign", "centre", "centre-offset"],
)
def test_capabilities(node: ir.Node, expected: dict[str, type[Exception] | None]) -> None:
    for name, outcome in expected.items():
        dialect = get_dialect(name)
        if outcome is None:
            assert dialect.generate(program(node))
        else:
            with pytest.raises(outcome, match=f"dialect '{name}' cannot express"):
                dialect.generate(program(node))


def test_unknown_dialect_suggests() -> None:
    with pytest.raises(UnsupportedError, match="did you mean 'fanuc'"):
        get_dialect("fanc")


@pytest.mark.parametrize(("value", "text"), [(-0.00001, "0.0000"), (-0.0, "0.0000"),
                                             (1e-7, "0.0000"), (-1.23456, "-1.2346"),
                                             (1e6, "1000000.0000"), (12.5, "12.5000")])
def test_numbers_fixed_no_negative_zero_no_exponent(value: float, text: str) -> None:
    assert get_dialect("fanuc").num(value) == text


def test_inch_program_scales_lengths_and_feeds() -> None:
    setup = ir.Setup(**{**{f: getattr(SETUP, f) for f in SETUP.__slots__}, "units": "inch"})
    text = get_dialect("fanuc").generate(
        ir.Program(setup, (ir.Move((25.4, 0.0, 50.8), ir.MoveMode.RETRACT),)))
    assert "G20\n" in text
    assert "G1 X1.00000 Y0.00000 Z2.00000 F79.\n" in text


def test_fanuc_variables_start_at_the_profile_base() -> None:
    text = get_dialect("fanuc").generate(program(ir.Assign("A", 1.0), ir.Assign("B", 2.0)))
    assert "#500=1.0000\n#501=2.0000\n" in text
    assert "(USES #500-#593)" in text


def test_line_length_is_enforced() -> None:
    long_comment = ir.Comment("X" * 90)
    with pytest.raises(UnsupportedError, match="expected at most 80"):
        get_dialect("fanuc").generate(program(long_comment))
