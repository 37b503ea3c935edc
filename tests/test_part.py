"""One Part: a command loads the STEP model once and hands it down; nothing keeps a
cache of part models of its own."""

from __future__ import annotations

import ast
from pathlib import Path
from typing import Any

import pytest
from conftest import REPO

from probegen import cad
from probegen.cad import part as part_module
from probegen.cli.app import main

SPECS = ["samples/bore_block/bore_block_actions.toml",  # line, plane, circles
         "samples/revolved_block/revolved_block.toml",  # cone, sphere, torus
         "samples/freeform/freeform.toml"]
ROOMS = ("cad", "planning", "post", "sim", "evaluate", "cli")
"""The packages that load or receive the part."""


class Counted:
    """Wraps a function and counts its calls."""

    def __init__(self, function: Any) -> None:
        self.function = function
        self.calls = 0

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        self.calls += 1
        return self.function(*args, **kwargs)


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: Path(s).stem)
def test_compile_loads_and_meshes_the_model_once(spec: str, tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """``compile`` for two dialects: one STEP load and one tessellation in all (every
    feature planner, the collision check and the second dialect share the part)."""
    loads = Counted(part_module.load_step)
    meshes = Counted(part_module.tessellate)
    monkeypatch.setattr(part_module, "load_step", loads)
    monkeypatch.setattr(part_module, "tessellate", meshes)
    monkeypatch.chdir(REPO)
    assert main(["compile", spec, "-d", "fanuc", "-d", "haas", "-o", str(tmp_path)]) == 0
    assert (loads.calls, meshes.calls) == (1, 1)
    names = {p.name for p in tmp_path.iterdir()}  # both programs and the library they call
    assert names == {f"{Path(spec).stem}.nc", f"{Path(spec).stem}.haas.nc", "O8000.nc",
                     "O8001.nc", "O8002.nc"}


def test_ingest_loads_and_meshes_the_model_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """``ingest`` plans the program, then each feature again: all on one part."""
    from probegen.evaluate.ingest import ingest
    from probegen.spec.model import load_spec

    loads = Counted(part_module.load_step)
    meshes = Counted(part_module.tessellate)
    monkeypatch.setattr(part_module, "load_step", loads)
    monkeypatch.setattr(part_module, "tessellate", meshes)
    sample = REPO / "samples/sphere25"
    result = ingest(sample / "sphere_test.log", load_spec(sample / "sphere_test.toml"),
                    with_path=True)
    assert len(result.results) == 1 and result.path
    assert (loads.calls, meshes.calls) == (1, 1)


def test_the_part_builds_each_derived_value_once(monkeypatch: pytest.MonkeyPatch) -> None:
    meshes = Counted(part_module.tessellate)
    monkeypatch.setattr(part_module, "tessellate", meshes)
    part = cad.load_part(REPO / "samples/sphere25/sphere25.step")
    assert part.mesh() is part.mesh() and meshes.calls == 1
    coarse = part.mesh(0.05)
    assert coarse is not part.mesh() and meshes.calls == 2
    assert len(coarse.faces) < len(part.mesh().faces)
    assert part.exact is part.exact
    built: list[int] = []
    assert part.memo(("x", 1), lambda: built.append(1) or 7) == 7
    assert part.memo(("x", 1), lambda: built.append(1) or 8) == 7 and built == [1]
    other = cad.load_part(REPO / "samples/sphere25/sphere25.step")
    assert other != part and other.memo(("x", 1), lambda: 9) == 9  # nothing shared


def _module_caches(path: Path) -> list[str]:
    """Module-level names bound to an empty dict: a cache filled at run time that outlives
    what it was built from (a weak dictionary, whose entries die with their key, is not
    one)."""
    found = []
    for node in ast.parse(path.read_text()).body:
        value = node.value if isinstance(node, ast.Assign | ast.AnnAssign) else None
        empty = (isinstance(value, ast.Dict) and not value.keys) or (
            isinstance(value, ast.Call) and ast.unparse(value.func) in ("dict", "OrderedDict",
                                                                        "defaultdict"))
        if empty:
            found.append(f"{path.relative_to(REPO)}:{node.lineno}")
    return found


def test_no_module_keeps_a_cache_of_part_models() -> None:
    """What is derived from a part lives on the part (``Part.memo``): no module of the
    rooms that load or receive it keeps a dict of its own, and the path-keyed loader is
    gone."""
    sources = [p for room in ROOMS for p in sorted((REPO / "probegen" / room).rglob("*.py"))]
    assert len(sources) > 50
    assert [c for p in sources for c in _module_caches(p)] == []
    text = "\n".join(p.read_text() for p in sources)
    assert "file_key" not in text and "load_model" not in text
