"""Whole-program golden tests: every sample spec x every dialect."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO, assert_golden

from probegen.dialects import get_dialect
from probegen.dmis.reader import parse_dmis
from probegen.errors import UnsupportedError
from probegen.planning import plan_program
from probegen.spec.model import load_spec

SPECS = sorted(p for p in (REPO / "samples").glob("*/*.toml")
               if "[[feature]]" in p.read_text(encoding="utf-8"))
DIALECTS = ("fanuc", "dmis", "linuxcnc", "haas")


def generate(spec_path: Path, dialect_name: str) -> str:
    spec = load_spec(spec_path.relative_to(REPO))
    dialect = get_dialect(dialect_name)
    planned = plan_program(spec, runtime_variables=dialect.RUNTIME_VARIABLES)
    return dialect.generate(planned.program)


@pytest.mark.parametrize("dialect", DIALECTS)
@pytest.mark.parametrize("spec_path", SPECS, ids=lambda p: p.stem)
def test_program_matches_golden(in_repo: Path, spec_path: Path, dialect: str) -> None:
    """The program; for a spec the dialect cannot express (a run-time decision on a CMM),
    the error, in ``<stem><ext>.unsupported``."""
    ext = get_dialect(dialect).EXTENSION
    try:
        text = generate(spec_path, dialect)
    except UnsupportedError as exc:
        text, ext = f"UnsupportedError: {exc}\n", f"{ext}.unsupported"
    assert_golden(REPO / "tests" / "golden" / spec_path.parent.name / f"{spec_path.stem}{ext}",
                  text)


def test_samples_exist() -> None:
    assert len(SPECS) >= 3


@pytest.mark.parametrize("spec_path", SPECS[:1], ids=lambda p: p.stem)
def test_output_is_repeatable(in_repo: Path, spec_path: Path) -> None:
    for dialect in DIALECTS:
        assert generate(spec_path, dialect) == generate(spec_path, dialect)


@pytest.mark.parametrize("spec_path", SPECS, ids=lambda p: p.stem)
def test_dmis_output_parses(in_repo: Path, spec_path: Path) -> None:
    try:
        text = generate(spec_path, "dmis")
    except UnsupportedError as exc:  # golden-tested above
        assert "on_out_of_tolerance" in str(exc) or "update_tool" in str(exc)
        return
    parsed = parse_dmis(text, source=spec_path.name)
    majors = [s.major for s in parsed.statements]
    assert majors[0] == "DMISMN" and majors[-1] == "ENDFIL"
    assert majors.count("MEAS") == majors.count("ENDMES") >= 1
