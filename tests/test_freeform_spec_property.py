"""Property test: a mutated free-form spec ends in a Spec or a ProbegenError, never another
exception (the ``freeform`` keys: grid, points, spacing, margin, direction, method,
extra_spacing, tolerance.deviation)."""

from __future__ import annotations

from pathlib import Path

from conftest import REPO
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from probegen.errors import ProbegenError
from probegen.spec.model import FreeformSpec, load_spec

SAMPLE = (REPO / "samples/freeform/freeform_2d.toml").read_text()
BASE = SAMPLE.replace('"../machines/vmc-fanuc.toml"',
                      f'"{REPO / "samples/machines/vmc-fanuc.toml"}"').replace(
    'model = "freeform.step"', f'model = "{REPO / "samples/freeform/freeform.step"}"').replace(
    "margin = 4.0", "direction = [0.0, 0.1, 1.0]\nmargin = 4.0")


@st.composite
def mutated(draw: st.DrawFn) -> str:
    text = BASE
    start = text.index("[[feature]]")
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(start, len(text)))
        j = draw(st.integers(i, min(len(text), i + 12)))
        text = text[:i] + draw(st.text(alphabet='[]="=.,-0123456789uvxyz \n', max_size=8)) \
            + text[j:]
    return text


@settings(max_examples=examples(150),
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(mutated())
def test_mutated_freeform_specs(tmp_path: Path, text: str) -> None:
    path = tmp_path / "spec.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        spec = load_spec(path)
    except ProbegenError:
        return
    for f in spec.features:
        if isinstance(f, FreeformSpec):
            assert (f.counts is None) != (f.spacing is None)
            assert 0.05 - 1e-12 <= f.extra_spacing <= 0.5 + 1e-12
            assert abs(sum(v * v for v in f.direction) - 1.0) < 1e-12


def test_base_spec_loads(tmp_path: Path) -> None:
    path = tmp_path / "spec.toml"
    path.write_text(BASE)
    f = load_spec(path).features[0]
    assert isinstance(f, FreeformSpec)
    assert f.spacing == 12.0 and f.method == "vertical2d" and f.direction[1] > 0.09
