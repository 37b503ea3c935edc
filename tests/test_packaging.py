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


def test_every_source_directory_is_a_package() -> None:
    """A directory of modules without ``__init__.py`` would escape the package list above
    (and the wheel): every directory under probegen/ holding modules is a package."""
    dirs = {p.parent for p in (REPO / "probegen").rglob("*.py")}
    missing = sorted(str(d.relative_to(REPO)) for d in dirs if not (d / "__init__.py").exists())
    assert len(dirs) > 10 and missing == []
