"""The wheel's package list names every package; grammars and templates are found."""

from __future__ import annotations

import tomllib

from conftest import REPO

from probegen import resources


def test_package_list_matches_the_source_tree() -> None:
    config = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(config["packages"])
    found = {".".join(p.parent.relative_to(REPO).parts)
             for p in (REPO / "probegen").rglob("__init__.py")}
    assert found | {"probegen._grammars", "probegen._templates"} == listed


def test_resources_find_grammars_and_templates() -> None:
    assert "statement" in resources.grammar_text("dmis")
    assert "G31" in resources.template_text("fanuc", "program.j2")
