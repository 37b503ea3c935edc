"""The collision check catches what it must, on the model mesh and on analytic spheres."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from probegen import ir
from probegen.errors import CollisionError
from probegen.planning import plan_program
from probegen.planning.collision import (
    MeshObstacle,
    SphereObstacle,
    Stylus,
    check_program,
    load_model,
    obstacle_for,
)
from probegen.spec import load_spec

SPEC = Path("samples/sphere25/sphere_test.toml")


@pytest.fixture(scope="module")
def planned():  # type: ignore[no-untyped-def]
    import os

    cwd = os.getcwd()
    os.chdir(REPO)
    try:
        spec = load_spec(SPEC)
        return spec, plan_program(spec, runtime_variables=True)
    finally:
        os.chdir(cwd)


def test_sample_plan_clears_with_margin(planned) -> None:  # type: ignore[no-untyped-def]
    _, p = planned
    assert p.clearance.minimum >= 0.0
    kinds = {s.kind for s in p.clearance.segments}
    assert {"rapid", "protected", "touch PT 25", "touch LOC 6"} <= kinds


def test_move_through_the_sphere_is_refused(planned) -> None:  # type: ignore[no-untyped-def]
    spec, p = planned
    body = (*p.program.body[:2], ir.Move((0.0, 0.0, -5.0), ir.MoveMode.PROTECTED))
    bad = ir.Program(p.program.setup, body)
    obstacle = obstacle_for(spec.model, [t.sphere for t in p.sphere_tests])
    with pytest.raises(CollisionError, match=r"segment 1 \(protected\).*cuts 2.015 mm into face 5"):
        check_program(bad, obstacle, p.sphere_tests, spec.machine)


def test_shank_is_checked(planned) -> None:  # type: ignore[no-untyped-def]
    # The ball passes beside the sphere but the shank above it would cut through it.
    spec, p = planned
    obstacle = obstacle_for(spec.model, [t.sphere for t in p.sphere_tests])
    stylus = Stylus(3.0, 2.25, 50.0)
    ball, shank = obstacle.clearance(np.array([0.0, 0.0, -20.0]), stylus)
    assert ball > 0.0 and shank == pytest.approx(-0.01, abs=1e-9)


def test_mesh_and_analytic_sphere_agree() -> None:
    model = load_model(str(REPO / "samples/sphere25/sphere25.step"))
    from probegen import cad

    mesh = MeshObstacle(cad.tessellate(model), None)
    sphere = SphereObstacle(np.zeros((1, 3)), np.array([12.5]))
    stylus = Stylus(3.0, 2.25, 50.0)
    for p in ([0, 0, 20.0], [17.0, 3.0, 2.0], [-10.0, 10.0, 9.0]):
        b_mesh, _ = mesh.clearance(np.array(p), stylus)
        b_sph, _ = sphere.clearance(np.array(p), stylus)
        assert b_mesh == pytest.approx(b_sph, abs=0.02)
