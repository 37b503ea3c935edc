"""Whole-program golden tests: every sample spec x every dialect."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO, assert_golden

from probegen.dialects import get_dialect
from probegen.dmis import parse_dmis
from probegen.planning import plan_program
from probegen.spec import load_spec

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
    text = generate(spec_path, dialect)
    ext = get_dialect(dialect).EXTENSION
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
    parsed = parse_dmis(generate(spec_path, "dmis"), source=spec_path.name)
    majors = [s.major for s in parsed.statements]
    assert majors[0] == "DMISMN" and majors[-1] == "ENDFIL"
    assert majors.count("MEAS") == majors.count("ENDMES") >= 1
