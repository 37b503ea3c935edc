"""Planning keeps a bounded memory (issue 17: NIST CTC 2 went past 20 GB): the collision
height maps and the FCL trees, one per obstacle and so one per turned part
(``Part.turned``: every head index, tilt and setup), are kept for the most recently used
:data:`probegen.planning.heightmap.MAPS_KEPT` and
:data:`probegen.planning.collision.GEOMETRY_KEPT` obstacles only, and the programs are the
same bytes whatever the bounds (a map or tree dropped is built again from the same mesh).

Part: ``samples/parts/five_face_block.step`` with the CMM sample profile (holes on five
faces: the part turned to several head indexes, and its FLIPPED setup).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from conftest import REPO

from probegen import cad
from probegen.cli.plan import program_text
from probegen.dialects import get_dialect
from probegen.machine.profile import load_profile
from probegen.planning import collision, heightmap
from probegen.planning.setups import all_revolved_setups, plan_setups

BLOCK = REPO / "samples/parts/five_face_block.step"
CMM = REPO / "samples/machines/cmm.toml"


def plan_texts(monkeypatch: pytest.MonkeyPatch, kept: int) -> tuple[list[str], int, int]:
    """The DMIS programs of ``plan BLOCK --all-revolved --machine CMM`` (one per setup)
    planned with ``kept`` height maps and FCL trees kept on a fresh load; with the number
    of maps built and the most maps kept at once.  Checks that no more than ``kept`` trees
    are kept at any time."""
    monkeypatch.setattr(heightmap, "MAPS_KEPT", kept)
    monkeypatch.setattr(heightmap, "_MAPS", type(heightmap._MAPS)())
    monkeypatch.setattr(collision, "GEOMETRY_KEPT", kept)
    monkeypatch.setattr(collision, "_GEOMETRY", type(collision._GEOMETRY)())
    trees: list[Any] = []
    build = collision.MeshObstacle._build

    def counting_trees(self: collision.MeshObstacle) -> tuple[Any, Any]:
        assert len(collision._GEOMETRY) <= kept
        trees.append(self)
        return build(self)

    monkeypatch.setattr(collision.MeshObstacle, "_build", counting_trees)
    built: list[Any] = []
    most = [0]
    init = heightmap.HeightMap.__init__

    def counting(self: heightmap.HeightMap, vertices: np.ndarray, faces: np.ndarray) -> None:
        built.append(self)
        init(self, vertices, faces)

    real = heightmap.height_map

    def watched(obstacle: Any) -> heightmap.HeightMap:
        out = real(obstacle)
        most[0] = max(most[0], len(heightmap._MAPS))
        return out

    monkeypatch.setattr(heightmap.HeightMap, "__init__", counting)
    monkeypatch.setattr(heightmap, "height_map", watched)
    import probegen.planning.reroute as reroute
    monkeypatch.setattr(reroute, "height_map", watched)
    part = cad.load_part(BLOCK)
    machine = load_profile(CMM)
    spec, notes = all_revolved_setups(part, machine)
    setups = plan_setups(spec, runtime_variables=get_dialect("dmis").RUNTIME_VARIABLES,
                         part=part)
    texts = [program_text("dmis", planned, notes) for _setup, planned in setups]
    assert len(collision._GEOMETRY) <= kept
    assert len(trees) > min(kept, 3)  # trees of more obstacles than kept, or built again
    return texts, len(built), most[0]


def test_height_maps_are_bounded_and_the_programs_do_not_change(
        monkeypatch: pytest.MonkeyPatch) -> None:
    free, free_built, free_most = plan_texts(monkeypatch, 1000)
    # the block needs maps of more obstacles (frames) than the bound below keeps
    assert free_most >= 3
    assert free_built == free_most
    bound, bound_built, bound_most = plan_texts(monkeypatch, 1)
    assert bound_most == 1
    assert bound_built > free_built  # maps dropped and built again when needed
    assert len(bound) == len(free) >= 1
    assert bound == free
