"""Property test: any spec text ends in a Spec or a ProbegenError, never another exception."""

from __future__ import annotations

from pathlib import Path

from conftest import REPO
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from probegen.errors import ProbegenError
from probegen.spec.model import load_spec

SAMPLE = (REPO / "samples/sphere25/sphere_test_iso.toml").read_text()
PROFILE = str(REPO / "samples/machines/vmc-fanuc.toml")
BASE = SAMPLE.replace('"../machines/vmc-fanuc.toml"', repr(PROFILE).replace("'", '"'))


def outcome(tmp: Path, text: str) -> None:
    path = tmp / "spec.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        load_spec(path)
    except ProbegenError:
        pass


@st.composite
def mutated(draw: st.DrawFn) -> str:
    text = BASE
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(text)))
        j = draw(st.integers(i, min(len(text), i + 12)))
        text = text[:i] + draw(st.text(alphabet='[]="=.,-0123456789abcdefxyz \n', max_size=8)) \
            + text[j:]
    return text


SETTINGS = settings(max_examples=examples(150),
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


@SETTINGS
@given(mutated())
def test_mutated_specs(tmp_path: Path, text: str) -> None:
    outcome(tmp_path, text)


@SETTINGS
@given(st.text(max_size=200))
def test_random_text(tmp_path: Path, text: str) -> None:
    outcome(tmp_path, text)


def test_base_spec_loads(tmp_path: Path) -> None:
    path = tmp_path / "spec.toml"
    path.write_text(BASE)
    assert load_spec(path).features[0].layout == "iso"
