"""The run-time locating sequence finds a sphere placed up to 2 mm off nominal.

An ideal controller (no machine errors, exact skip) walks the planned IR: a touch moves
the ball centre from its start along -normal and stops where the ball meets the real
sphere (a line/sphere intersection), stores what the plan asks for, and the Assign nodes
compute as the control would.  The text-level check of the same programs is the virtual
machine's job; this test pins the geometry of the locating method itself.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from probegen import ir
from probegen.planning import plan_program
from probegen.spec.model import load_spec

R, BALL = 12.5, 3.0


def run(program: ir.Program, true_centre: np.ndarray) -> list[tuple[ir.Touch, np.ndarray]]:
    values: dict[str, float] = {}

    def val(c: ir.Coord) -> float:
        return values[c.name] + c.offset if isinstance(c, ir.Var) else c

    touches = []
    for node in ir.walk(program.body):
        if isinstance(node, ir.Assign):
            a = val(node.a)
            values[node.name] = (a + val(node.b)) / 2 if node.b is not None else a + node.offset
        elif isinstance(node, ir.Touch):
            n = np.array(node.normal)
            contact = np.array([val(c) for c in node.contact])
            start = contact + (BALL + node.approach) * n
            # ball centre p = start - s*n meets the offset sphere |p - c| = R + r
            w = start - true_centre
            b = float(w @ n)
            disc = b * b - (float(w @ w) - (R + BALL) ** 2)
            assert disc >= 0, f"touch {node.role.value} {node.index} misses the sphere"
            s = b - math.sqrt(disc)
            assert 0 <= s <= node.approach + node.overtravel, "out of the touch's reach"
            hit = start - s * n
            for axis, name in enumerate(node.store):
                if name is not None:
                    values[name] = float(hit[axis])
            touches.append((node, hit))
    return touches


@pytest.fixture(scope="module")
def program() -> ir.Program:
    import os

    cwd = os.getcwd()
    os.chdir(REPO)
    try:
        spec = load_spec(Path("samples/sphere25/sphere_test.toml"))
        return plan_program(spec, runtime_variables=True).program
    finally:
        os.chdir(cwd)


OFFSETS = [(0.0, 0.0, 0.0), (1.5, -1.2, 0.4), (-1.4, 0.0, -1.4), (0.0, 1.99, 0.0),
           (1.15, 1.15, -1.15)]


@pytest.mark.parametrize("offset", OFFSETS, ids=str)
def test_measuring_touches_land_along_the_real_normals(program: ir.Program,
                                                       offset: tuple[float, ...]) -> None:
    centre = np.array(offset)
    assert np.linalg.norm(centre) <= 2.0 + 1e-9
    touches = run(program, centre)
    measure = [(t, hit) for t, hit in touches if t.role is ir.TouchRole.MEASURE]
    assert len(measure) == 25
    for touch, hit in measure:
        direction = (hit - centre) / np.linalg.norm(hit - centre)
        # the ball centre lies on the offset sphere along the planned direction: the
        # located centre equals the real one to rounding
        assert np.linalg.norm(direction - np.array(touch.normal)) < 1e-9
        assert np.linalg.norm(hit - centre) == pytest.approx(R + BALL, abs=1e-9)


def test_locating_uses_six_touches(program: ir.Program) -> None:
    touches = run(program, np.array([0.3, -0.2, 0.1]))
    roles = [t.role for t, _ in touches]
    assert roles[:6] == [ir.TouchRole.LOCATE] * 6 and roles[6:] == [ir.TouchRole.MEASURE] * 25
