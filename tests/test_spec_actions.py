"""The spec's in-process decisions (``spec_actions``): what they read and how they fail."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from probegen.errors import ProbegenError, SpecError
from probegen.ir.actions import describe, point_index, point_names
from probegen.spec.actions import Actions, AlignAction, PlanarSpec, ToolAction, WorkOffsetAction
from probegen.spec.model import load_spec

SAMPLE = (REPO / "samples/bore_block/bore_block_actions.toml").read_text()
BASE = (SAMPLE.replace('"../machines/vmc-fanuc.toml"',
                       repr(str(REPO / "samples/machines/vmc-fanuc.toml")).replace("'", '"'))
        .replace('"bore_block.step"',
                 repr(str(REPO / "samples/bore_block/bore_block.step")).replace("'", '"')))


def load(tmp: Path, text: str) -> object:
    path = tmp / "spec.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    return load_spec(path)


def test_sample_actions_are_read(tmp_path: Path) -> None:
    spec = load(tmp_path, BASE)
    edge, top, bore, boss = spec.features  # type: ignore[attr-defined]
    assert isinstance(edge, PlanarSpec) and edge.kind == "line" and len(edge.contacts) == 2
    assert edge.actions.align == AlignAction("g68", 520) and edge.tolerance.angle == 1.0
    assert top.actions.work_offset == WorkOffsetAction("G54", "Z")
    assert bore.actions == Actions(WorkOffsetAction("G54", "XY"),
                                   ToolAction(12, "radius", 0.005, 0.1, 1.0), None, "alarm",
                                   None, True)
    assert boss.actions.on_fail == "flag" and boss.actions.flag == 510


def test_form_tolerance_of_a_face(tmp_path: Path) -> None:
    """``form`` of a plane in the part's units, the method from ``[evaluation]`` unless
    the feature names its own."""
    top = 'tolerance = { position = [-0.5, 0.5] }'
    assert top in BASE
    three = "[20.0, 80.0, 50.0]]"
    assert three in BASE
    text = BASE.replace(top, 'tolerance = { position = [-0.5, 0.5], form = 0.001 }').replace(
        three, "[20.0, 80.0, 50.0], [30.0, 30.0, 50.0]]")
    spec = load(tmp_path, text.replace('units = "mm"', 'units = "inch"'))
    tol = spec.features[1].tolerance  # type: ignore[attr-defined]
    assert tol.form == pytest.approx(0.0254) and tol.form_method == "minimum_zone"
    spec = load(tmp_path, text.replace("[program]", '[evaluation]\nform_method = '
                                       '"least_squares"\n\n[program]'))
    assert spec.features[1].tolerance.form_method == "least_squares"  # type: ignore[attr-defined]
    spec = load(tmp_path, text.replace("form = 0.001", 'form = 0.001, form_method = '
                                       '"least_squares"'))
    assert spec.features[1].tolerance.form_method == "least_squares"  # type: ignore[attr-defined]
    assert spec.features[0].tolerance.form_method == "minimum_zone"  # type: ignore[attr-defined]


def test_inch_spec_scales_corrections(tmp_path: Path) -> None:
    spec = load(tmp_path, BASE.replace('units = "mm"', 'units = "inch"'))
    bore = spec.features[2]  # type: ignore[attr-defined]
    assert bore.actions.tool.dead_band == pytest.approx(0.127)
    assert bore.actions.tool.max_correction == pytest.approx(2.54)


@pytest.mark.parametrize("offset", ["G54", "G59", "G54.1 P1", "G54.1 P300"])
def test_work_offsets_accepted(tmp_path: Path, offset: str) -> None:
    spec = load(tmp_path, BASE.replace('offset = "G54", axes = "XY"',
                                       f'offset = "{offset}", axes = "YX"'))
    assert spec.features[2].actions.work_offset == WorkOffsetAction(offset, "XY")  # type: ignore[attr-defined]


@pytest.mark.parametrize(("old", "new", "message"), [
    ('offset = "G54", axes = "XY"', 'offset = "G54.1 P301", axes = "XY"', "n 1-300"),
    ('offset = "G54", axes = "XY"', 'offset = "G54", axes = "XZ"', "one or more of 'XY'"),
    ('offset = "G54", axes = "XY"', 'offset = "G54", axes = "XX"', "each once"),
    ("feedback = 1.0", "feedback = 1.5", "a number <= 1"),
    ("flag = 510", "flag = 100", "an integer >= 500"),
    ('on_out_of_tolerance = "alarm"\nalign', 'on_out_of_tolerance = "alrm"\nalign',
     "did you mean 'alarm'"),
    ('align = { mode = "g68", variable = 520 }', 'align = { mode = "variable" }',
     "required with mode"),
    ("tolerance = { angle = 1.0 }", "tolerance = { angle = 50.0 }", "a number <= 45"),
    ("contacts = [[10.0, 0.0, 25.0], [90.0, 0.0, 25.0]]", "contacts = [[10.0, 0.0, 25.0]]",
     "an array of 2-50 points"),
    ("tolerance = { angle = 1.0 }", "tolerance = { angle = 1.0, form = 0.0 }",
     "tolerance.form: expected a positive number, found 0.0"),
    ("tolerance = { angle = 1.0 }", 'tolerance = { angle = 1.0, form_method = "minzone" }',
     "minimum_zone"),
    ("tolerance = { angle = 1.0 }", "tolerance = { angle = 1.0, form = 0.01 }",
     r"contacts: a form tolerance needs at least 3 contacts on a line, found 2"),
])
def test_bad_actions_name_key_and_value(tmp_path: Path, old: str, new: str,
                                        message: str) -> None:
    assert old in BASE
    with pytest.raises(SpecError, match=message) as info:
        load(tmp_path, BASE.replace(old, new, 1))
    assert str(info.value).startswith(str(tmp_path / "spec.toml") + ": feature[")


def test_point_names_round_trip() -> None:
    names = point_names("BORE", 12, "XY")
    assert names == ("BORE.X12", "BORE.Y12", None)
    assert point_index("BORE.Y12") == 12


def test_describe_names_the_spec_key() -> None:
    from probegen.ir.actions import UpdateTool
    assert describe(UpdateTool("B", 1, "radius", "B.E", 0.0, 0.1, 1.0)) == \
        "update_tool of feature B"


@st.composite
def mutated(draw: st.DrawFn) -> str:
    text = BASE
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(text)))
        j = draw(st.integers(i, min(len(text), i + 12)))
        text = text[:i] + draw(st.text(alphabet='[]{}="=.,-0123456789abcdefglpxyz \n',
                                       max_size=8)) + text[j:]
    return text


@settings(max_examples=examples(150),
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(mutated())
def test_mutated_action_specs(tmp_path: Path, text: str) -> None:
    try:
        load(tmp_path, text)
    except ProbegenError:
        pass
