"""Shared test fixtures: the repository root, the shared reference folder, goldens."""

from __future__ import annotations

import difflib
import importlib.util
import os
from pathlib import Path
from types import ModuleType

import pytest
from hypothesis import HealthCheck, settings

# Property-based tests (tests/fuzzing.py): `make test` runs the derandomised profile `ci`
# (same commit, same answer; no deadline); `make fuzz` sets PROBEGEN_HYPOTHESIS=fuzz.
settings.register_profile(
    "ci", derandomize=True, deadline=None, database=None, print_blob=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.register_profile(
    "fuzz", derandomize=False, deadline=None, print_blob=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.load_profile(os.environ.get("PROBEGEN_HYPOTHESIS", "ci"))

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
REGEN = os.environ.get("PROBEGEN_REGEN") == "1"


@pytest.fixture
def in_repo(monkeypatch: pytest.MonkeyPatch) -> Path:
    """Run the test with the repository root as the working directory."""
    monkeypatch.chdir(REPO)
    return REPO


def sample_script(sample: str) -> ModuleType:
    """The STEP-making script ``samples/<sample>/make_model.py``, loaded as a module."""
    spec = importlib.util.spec_from_file_location(
        f"{sample}_make_model", REPO / "samples" / sample / "make_model.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def assert_golden(path: Path, actual: str) -> None:
    """Compare ``actual`` with the golden file; ``PROBEGEN_REGEN=1`` rewrites it."""
    if REGEN:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(actual, encoding="ascii", newline="\n")
        return
    assert path.exists(), f"missing golden file {path}: run `make goldens`"
    expected = path.read_text(encoding="ascii")
    if actual != expected:
        diff = "".join(difflib.unified_diff(
            expected.splitlines(keepends=True), actual.splitlines(keepends=True),
            fromfile=str(path), tofile="generated"))
        pytest.fail(f"{path} differs from the generated text (make goldens rewrites it):\n"
                    f"{diff}", pytrace=False)
