"""A malformed colour or style entity is a warning naming it, not a refusal (issue 17, item 7).

The files are in ``tests/data/step_styles`` (made by its ``make_styles.py`` from the
sphere25 sample): the geometry is the sample's, so each must load with the sample's
faces, and say which entity it ignored.
"""

from __future__ import annotations

import importlib.util
import re
import warnings
from pathlib import Path
from types import ModuleType

import pytest
from conftest import REPO, SHARED
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from probegen import cad
from probegen.cli.app import main
from probegen.errors import ExitCode, ModelError, ModelWarning

DATA = REPO / "tests/data/step_styles"
SAMPLE = REPO / "samples/sphere25/sphere25.step"
BROKEN = {
    "unset_side": ("#906", "SURFACE_STYLE_USAGE", "side"),
    "unset_colour": ("#902", "FILL_AREA_STYLE_COLOUR", "fill_colour"),
    "unset_red": ("#901", "COLOUR_RGB", "red"),
    "unset_rendering": ("#909", "SURFACE_STYLE_RENDERING_WITH_PROPERTIES", "rendering_method"),
    "dangling_colour": ("#902", "FILL_AREA_STYLE_COLOUR", "#9999"),
}
"""File stem -> the entity warned of, its STEP type and a word of OCCT's reason."""


def _script() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_styles", DATA / "make_styles.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def sample() -> cad.Model:
    return cad.load_step(SAMPLE)


def _load(path: Path) -> tuple[cad.Model, list[str]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = cad.load_step(path)
    return model, [str(w.message) for w in caught if issubclass(w.category, ModelWarning)]


def test_committed_files_are_what_the_script_writes() -> None:
    script = _script()
    assert set(script.VARIANTS) == {"styled", *BROKEN}
    for stem, change in script.VARIANTS.items():
        assert (DATA / f"{stem}.step").read_text(encoding="ascii") == script.styled_text(change)


def test_well_formed_style_loads_without_warning(sample: cad.Model) -> None:
    model, said = _load(DATA / "styled.step")
    assert said == [] and model.warnings == ()
    assert model.faces == sample.faces


@pytest.mark.parametrize("stem", sorted(BROKEN))
def test_malformed_style_is_a_warning_naming_the_entity(stem: str, sample: cad.Model) -> None:
    ident, step_type, reason = BROKEN[stem]
    path = DATA / f"{stem}.step"
    model, said = _load(path)
    assert model.faces == sample.faces  # the geometry is all there
    assert model.bbox_min == sample.bbox_min and model.bbox_max == sample.bbox_max
    assert said == list(model.warnings) and len(said) == 1
    assert said[0].startswith(f"{path}: STEP entity {ident} ({step_type}) ignored: ")
    assert reason in said[0]


def test_the_part_carries_the_warnings() -> None:
    with pytest.warns(ModelWarning, match=r"#906 \(SURFACE_STYLE_USAGE\)"):
        part = cad.load_part(DATA / "unset_side.step")
    assert len(part.warnings) == 1 and "#906" in part.warnings[0]


def test_the_command_line_prints_one_line_and_goes_on(
        in_repo: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["features", "tests/data/step_styles/unset_rendering.step"]) == ExitCode.OK
    out, err = capsys.readouterr()
    assert "sphere" in out
    assert err == ("probegen: warning: tests/data/step_styles/unset_rendering.step: STEP "
                   "entity #909 (SURFACE_STYLE_RENDERING_WITH_PROPERTIES) ignored: a colour or "
                   "style record that does not parse (Parameter #1 (surface_style_rendering."
                   "rendering_method) is not enumeration); the geometry does not depend on it\n")


def test_many_broken_colours_are_counted_after_the_first_five(tmp_path: Path) -> None:
    extra = "".join(f"#{920 + k} = COLOUR_RGB('c{k}',$,0.5,0.5);\n" for k in range(7))
    text = _script().styled_text({}).replace("ENDSEC;\nEND-ISO", extra + "ENDSEC;\nEND-ISO")
    path = tmp_path / "colours.step"
    path.write_text(text, encoding="ascii")
    model, said = _load(path)
    assert [w.split(" ignored")[0] for w in model.warnings] == [
        f"{path}: STEP entity #{920 + k} (COLOUR_RGB)" for k in range(7)]
    assert said == [*model.warnings[:5], f"{path}: 2 more colour or style entities ignored "
                                         "likewise"]


def test_broken_geometry_is_still_refused_naming_the_entity(tmp_path: Path) -> None:
    """Only presentation entities are forgiven: an unset field in the geometry refuses."""
    text = SAMPLE.read_text(encoding="ascii")
    good = "#20 = ORIENTED_EDGE('',*,*,#21,.F.);"
    assert good in text
    path = tmp_path / "edge.step"
    path.write_text(text.replace(good, "#20 = ORIENTED_EDGE('',*,*,$,.F.);"), encoding="ascii")
    with pytest.raises(ModelError, match=r"corrupt STEP data: .*DATA entity #20 "
                                         r"\(ORIENTED_EDGE\)"):
        cad.load_step(path)


def test_dangling_geometry_reference_is_still_refused(tmp_path: Path) -> None:
    text = _script().styled_text({"colour": "#9999"})
    good = "#20 = ORIENTED_EDGE('',*,*,#21,.F.);"
    path = tmp_path / "both.step"
    path.write_text(text.replace(good, "#20 = ORIENTED_EDGE('',*,*,#8888,.F.);"),
                    encoding="ascii")
    with pytest.raises(ModelError, match=r"2 error\(s\), the first: Unresolved Reference, "
                                         r"Ent.Id.#20 .*#8888"):
        cad.load_step(path)


@pytest.mark.skipif(not (SHARED / "ref/parts").is_dir(), reason="no ../shared/ref/parts")
def test_the_inventor_heatsink_loads() -> None:
    """The Prusa MINI heatsink (Inventor 2019) was refused for its rendering record."""
    model, said = _load(SHARED / "ref/parts/prusa_mini_heatsink.step")
    assert len(model.faces) == 123
    assert len(said) == 1 and re.search(
        r"STEP entity #4372 \(SURFACE_STYLE_RENDERING_WITH_PROPERTIES\) ignored", said[0])


@st.composite
def _mutated_chain(draw: st.DrawFn) -> str:
    """The styled file with one field of its chain replaced by ``$``, junk or a bad #ref."""
    text = _script().styled_text({})
    lines = text.split("\n")
    chain = [i for i, line in enumerate(lines) if re.match(r"#9\d\d = ", line)]
    i = draw(st.sampled_from(chain))
    fields = list(re.finditer(r"(?<=[(,])[^(),]+(?=[),])", lines[i]))
    field = draw(st.sampled_from(fields))
    value = draw(st.sampled_from(["$", "*", "#9999", "#15", "'x'", "1.5", ".FOO.", ""]))
    lines[i] = lines[i][:field.start()] + value + lines[i][field.end():]
    return "\n".join(lines)


@settings(max_examples=examples(40), suppress_health_check=[HealthCheck.too_slow])
@given(text=_mutated_chain())
def test_any_broken_style_field_loads_the_geometry(
        tmp_path_factory: pytest.TempPathFactory, text: str) -> None:
    path = tmp_path_factory.mktemp("style") / "style.step"
    path.write_text(text, encoding="ascii")
    try:
        model, said = _load(path)
    except ModelError as exc:  # only a syntax error of the file as a whole may refuse it
        assert str(exc).startswith(f"{path}: corrupt STEP data")
        assert "the first: Undefined Parsing" in str(exc)
        return
    assert len(model.faces) == 5
    assert all(re.search(r"STEP entity #9\d\d \([A-Z_]+\) ignored", w) for w in said)
