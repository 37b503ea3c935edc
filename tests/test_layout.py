"""The house's layout: rooms without import circles, few modules at the top, the layering
contracts of ``[tool.importlinter]`` in pyproject.toml kept (``lint-imports``)."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path

import pytest
from conftest import REPO

PACKAGE = REPO / "probegen"

GROUND_LIMIT = 4
"""Modules directly under ``probegen/`` besides ``__init__.py`` (errors, constants, ...)."""

def module_names(root: Path) -> dict[str, Path]:
    """Every module under the package directory ``root``, by dotted name (a package by
    its own name, not ``.__init__``)."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = path.relative_to(root.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def imports_of(name: str, path: Path, modules: Mapping[str, Path]) -> set[str]:
    """The package's modules ``name`` imports anywhere in its text: at the top, inside
    functions and under ``TYPE_CHECKING`` (as import-linter counts them).  ``from a
    import b`` is an import of module ``a.b`` when there is one, else of ``a``."""
    top = name.split(".")[0]
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[:len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                found.add(sub if sub in modules else target)
    return {m for m in found if m.split(".")[0] == top and m in modules and m != name}


def import_graph(root: Path) -> dict[str, set[str]]:
    """The package's module import graph: module -> the modules it imports."""
    modules = module_names(root)
    return {name: imports_of(name, path, modules) for name, path in modules.items()}


def cycles(graph: Mapping[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_circle() -> None:
    graph = import_graph(PACKAGE)
    assert len(graph) > 100 and "probegen.errors" in graph["probegen.files"]
    circles = cycles(graph)
    assert circles == [], "modules importing each other (move the shared part down into a " \
                          f"module both import): {circles}"


def _write(root: Path, files: Mapping[str, str]) -> Path:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root / "pkg"


def test_the_circle_finder_sees_function_local_and_relative_imports(tmp_path: Path) -> None:
    """The finder behind ``test_no_import_circle`` reports a circle closed only by a
    function-local import, and by a relative ``from . import``; not a one-way chain."""
    root = _write(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/a.py": "from pkg.b import thing\n",
        "pkg/b.py": "def thing():\n    from pkg import a\n    return a\n",
        "pkg/sub/__init__.py": "",
        "pkg/sub/c.py": "from . import d\n",
        "pkg/sub/d.py": "from .c import x\n",
        "pkg/sub/e.py": "from pkg.sub import c\n",
    })
    graph = import_graph(root)
    assert graph["pkg.sub.e"] == {"pkg.sub.c"}
    assert cycles(graph) == [["pkg.a", "pkg.b"], ["pkg.sub.c", "pkg.sub.d"]]


def test_few_modules_at_the_top() -> None:
    top = sorted(p.name for p in PACKAGE.glob("*.py") if p.name != "__init__.py")
    assert 0 < len(top) <= GROUND_LIMIT, f"modules at the top of probegen/: {top}; a " \
                                         f"stage's module belongs in its room"


def test_lint_imports_keeps_the_contracts() -> None:
    """``lint-imports`` (import-linter, the ``test`` extra) passes on this checkout."""
    tool = Path(sys.executable).parent / "lint-imports"
    if not tool.exists():
        pytest.skip("import-linter is not installed in this venv (pip install -e '.[test]')")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    run = subprocess.run([str(tool), "--no-cache", "--no-logo"], cwd=REPO, env=env,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "0 broken" in run.stdout and "kept" in run.stdout
