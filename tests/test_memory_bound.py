"""Planning keeps a bounded memory (issue 17: NIST CTC 2 went past 20 GB): the collision
geometry of each frame the part is turned into (``Part.turned``: every head index, tilt,
setup and off-grid feature axis has its obstacle), its FCL tree and its height map, is
kept for the :data:`probegen.cad.part.RECENT_KEPT` most recently used frames only
(:meth:`probegen.cad.Part.recent`), and the programs are the same bytes whatever the
bound (a tree or map dropped is built again from the same mesh).

Part: ``samples/parts/five_face_block.step`` with the CMM sample profile (holes on five
faces: the part turned to several head indexes).
"""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np
import pytest
from conftest import REPO

from probegen import cad
from probegen.cad import part as part_module
from probegen.cli.plan import program_text
from probegen.dialects import get_dialect
from probegen.machine.profile import load_profile
from probegen.planning import collision, heightmap, revolved_spec
from probegen.planning.setups import all_revolved_setups, plan_setups

BLOCK = REPO / "samples/parts/five_face_block.step"
CMM = REPO / "samples/machines/cmm.toml"
BUILD_TREE = collision.MeshObstacle._build
BUILD_MAP = heightmap.HeightMap.__init__


def plan_texts(monkeypatch: pytest.MonkeyPatch, kept: int, grouped: bool = True
               ) -> tuple[list[str], Counter[str]]:
    """The DMIS programs of ``plan BLOCK --all-revolved --machine CMM`` (one per setup)
    planned on a fresh load with ``kept`` values of a kind kept, the features planned
    ``grouped`` by frame or in the recognised order (``revolved_spec.GROUPED``), and how
    many trees and height maps were built.  Checks that no more than ``kept`` of either
    are alive at any time."""
    monkeypatch.setattr(part_module, "RECENT_KEPT", kept)
    monkeypatch.setattr(revolved_spec, "GROUPED", grouped)
    part = cad.load_part(BLOCK)
    built: Counter[str] = Counter()

    def alive() -> None:
        for kind in ("collision tree", "height map"):
            assert len(part.recent(kind)) <= kept

    def counting_tree(self: collision.MeshObstacle) -> tuple[Any, Any]:
        alive()
        built["trees"] += 1
        return BUILD_TREE(self)

    def counting_map(self: heightmap.HeightMap, vertices: np.ndarray,
                     faces: np.ndarray) -> None:
        alive()
        built["maps"] += 1
        BUILD_MAP(self, vertices, faces)

    monkeypatch.setattr(collision.MeshObstacle, "_build", counting_tree)
    monkeypatch.setattr(heightmap.HeightMap, "__init__", counting_map)
    machine = load_profile(CMM)
    spec, notes = all_revolved_setups(part, machine)
    setups = plan_setups(spec, runtime_variables=get_dialect("dmis").RUNTIME_VARIABLES,
                         part=part)
    texts = [program_text("dmis", planned, notes) for _setup, planned in setups]
    alive()
    obstacles = [p for p in [part, *turned_parts(part)]
                 if ("collision obstacle",) in p._memo]
    built["obstacles"] = len(obstacles)
    return texts, built


def turned_parts(part: cad.Part) -> list[cad.Part]:
    """The turned parts kept on ``part``."""
    return [v for k, v in part._memo.items() if isinstance(k, tuple) and k[0] == "turned"]


def test_collision_geometry_is_bounded_and_the_programs_do_not_change(
        monkeypatch: pytest.MonkeyPatch) -> None:
    free, free_built = plan_texts(monkeypatch, 1000)
    # the block is planned in more frames (obstacles) than the bound below keeps
    assert free_built["obstacles"] >= 4
    assert free_built["trees"] == 1  # the loaded part's: every frame places it
    assert free_built["maps"] >= 3
    bound, bound_built = plan_texts(monkeypatch, 1)
    # maps dropped and built again when their frame came back
    assert bound_built["maps"] > free_built["maps"]
    assert bound_built["trees"] == 1
    assert len(bound) == len(free) >= 1 and "MEAS/" in free[0]
    assert bound == free


def test_frames_with_trees_of_their_own_plan_the_same(monkeypatch: pytest.MonkeyPatch
                                                      ) -> None:
    shared, shared_built = plan_texts(monkeypatch, 1000)
    monkeypatch.setattr(collision, "SHARED_TREE", False)  # before stop 33
    own, own_built = plan_texts(monkeypatch, 1000)
    assert own_built["trees"] >= 4 and shared_built["trees"] == 1
    assert own == shared


def test_features_grouped_by_frame_plan_the_same_with_fewer_builds(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # one frame kept: every change of frame between two features builds again
    recognised, recognised_built = plan_texts(monkeypatch, 1, grouped=False)
    grouped, grouped_built = plan_texts(monkeypatch, 1, grouped=True)
    assert grouped == recognised
    assert grouped_built["maps"] < recognised_built["maps"]
