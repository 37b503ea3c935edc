"""Golden error messages for bad specs: each must be a ProbegenError, never a traceback."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO, assert_golden

from probegen.cli.app import main
from probegen.errors import ProbegenError
from probegen.planning import plan_program
from probegen.spec.model import load_spec

BAD_SPECS = sorted((REPO / "tests" / "bad_inputs" / "spec").glob("*.toml"))


def message(path: Path) -> str:
    rel = path.relative_to(REPO)
    with pytest.raises(ProbegenError) as info:
        plan_program(load_spec(rel), runtime_variables=True)
    return str(info.value) + "\n"


def test_there_are_bad_specs() -> None:
    assert len(BAD_SPECS) >= 12


@pytest.mark.parametrize("path", BAD_SPECS, ids=lambda p: p.stem)
def test_bad_spec_message(in_repo: Path, path: Path) -> None:
    assert_golden(path.with_suffix(".err"), message(path))


@pytest.mark.parametrize("path", BAD_SPECS[:4], ids=lambda p: p.stem)
def test_cli_prints_message_without_traceback(in_repo: Path, path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["compile", str(path.relative_to(REPO)), "-o", "-"])
    err = capsys.readouterr().err
    assert code != 0
    assert err.startswith("probegen: error: tests/bad_inputs/spec/")
    assert "Traceback" not in err
