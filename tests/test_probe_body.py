"""The probe body is part of the collision check: a ball deeper in a bore than its stylus
is long takes the body (or the head) into the part, and the check refuses it
(``[probe] body_diameter``/``body_length``, docs/spec.md "Machine profile")."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from probegen import ir
from probegen.cad import load_part
from probegen.errors import CollisionError, SpecError
from probegen.machine.profile import load_profile
from probegen.planning.collision import (
    SphereObstacle,
    Stylus,
    check_program,
    obstacle_for,
    probe_stylus,
)
from probegen.planning.heightmap import clear_paths
from probegen.planning.setup import setup_for

MACHINES = REPO / "samples" / "machines"


@pytest.fixture(scope="module")
def deep(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 60 x 60 x 50 block, top at z = 0, with a bore of 20 mm 40 mm deep."""
    from build123d import Align, Box, Cylinder, Pos, export_step

    part = Box(60, 60, 50, align=(Align.CENTER, Align.CENTER, Align.MAX)) - Pos(0, 0, -40) \
        * Cylinder(10, 40, align=(Align.CENTER, Align.CENTER, Align.MIN))
    path = tmp_path_factory.mktemp("deep") / "deep.step"
    export_step(part, str(path))
    return path


def profile_with(tmp_path: Path, probe: str, source: str = "vmc-fanuc.toml") -> Path:
    """The sample profile ``source`` with ``probe`` (TOML lines) in its ``[probe]`` table
    instead of the body the sample states."""
    lines = (MACHINES / source).read_text(encoding="utf-8").splitlines(keepends=True)
    at = next(k for k, line in enumerate(lines) if line.startswith("[probe]"))
    end = next((k for k in range(at + 1, len(lines)) if lines[k].startswith("[")), len(lines))
    table = [line for line in lines[at + 1:end] if not line.startswith("body_")]
    text = "".join([*lines[:at + 1], f"{probe}\n", *table, *lines[end:]])
    path = tmp_path / "profile.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_the_body_is_checked_where_the_profile_states_it(tmp_path: Path) -> None:
    stated = load_profile(MACHINES / "vmc-fanuc.toml").probe   # the sample's OMP40-2-like
    assert (stated.body_diameter, stated.body_length) == (40.0, 50.0)
    plain = load_profile(profile_with(tmp_path, "")).probe
    assert (plain.body_diameter, plain.body_length) == (0.0, 0.0)  # none stated: none
    given = load_profile(profile_with(tmp_path, "body_diameter = 63.0\nbody_length = 80.0"))
    assert (given.probe.body_diameter, given.probe.body_length) == (63.0, 80.0)
    with pytest.raises(SpecError, match=r"probe\.body_diameter: expected at least "
                                        r"shank_diameter \(4\.5\)"):
        load_profile(profile_with(tmp_path, "body_diameter = 3.0\nbody_length = 50.0"))
    with pytest.raises(SpecError, match=r"probe\.body_length: expected a body_length with "
                                        r"body_diameter"):
        load_profile(profile_with(tmp_path, "body_diameter = 40.0"))


def plunge(depth: float, machine_path: Path, length: float) -> tuple[ir.Program, object]:
    """A program that takes a ball of 1 mm on a ``length`` stylus down the bore's wall
    side to ``depth`` below the top, off the axis as a touch would leave it."""
    machine = load_profile(machine_path)
    setup = setup_for(machine, 1, "DEEP", 60.0)
    body = (ir.SelectStylus("D1", 0, 1.0, 0.7, length),
            ir.Move((8.0, 0.0, 60.0), ir.MoveMode.RAPID),
            ir.Move((8.0, 0.0, -depth), ir.MoveMode.PROTECTED))
    return ir.Program(setup, body), machine


def test_a_ball_below_its_stylus_length_takes_the_body_into_the_part(deep: Path) -> None:
    part = load_part(deep)
    obstacle = obstacle_for(part, [])
    machine_path = profile_with(deep.parent, "body_diameter = 40.0\nbody_length = 50.0")
    shallow, machine = plunge(15.0, machine_path, 20.0)
    check_program(shallow, obstacle, [], machine, part=part)  # the body stays above z=0
    program, machine = plunge(35.0, machine_path, 20.0)
    with pytest.raises(CollisionError, match="the probe body cuts .* into face"):
        check_program(program, obstacle, [], machine, part=part)
    longer, machine = plunge(35.0, machine_path, 50.0)
    check_program(longer, obstacle, [], machine, part=part)


def test_the_fast_check_never_clears_what_the_body_hits(deep: Path) -> None:
    """The height map's fast check (which fills the exact check's memo of sweeps) leaves
    to the exact check a plunge whose ball and shank clear but whose body does not."""
    part = load_part(deep)
    machine = load_profile(profile_with(deep.parent,
                                        "body_diameter = 40.0\nbody_length = 50.0"))
    for length, clears in ((20.0, False), (50.0, True)):
        m = replace(machine, probe=replace(machine.probe, length=length))
        setup = setup_for(m, 1, "DEEP", 60.0)
        down = (ir.Move((6.0, 0.0, 10.0), ir.MoveMode.RAPID),
                ir.Move((6.0, 0.0, -35.0), ir.MoveMode.PROTECTED))
        obstacle = obstacle_for(part, [])
        fast = clear_paths([down], obstacle, setup, m).tolist()
        assert fast in ([clears], [False])
        if clears:
            check_program(ir.Program(setup, down), obstacle, [], m, part=part)
        else:
            with pytest.raises(CollisionError, match="the probe body"):
                check_program(ir.Program(setup, down), obstacle, [], m, part=part)


def test_the_body_of_an_analytic_sphere_check() -> None:
    sphere = SphereObstacle(np.array([[0.0, 0.0, 0.0]]), np.array([12.5]))
    bare = Stylus(1.0, 0.5, 10.0)
    bodied = Stylus(1.0, 0.5, 10.0, 10.0, 30.0)
    centre = np.array([14.0, 0.0, -13.0])  # beside the sphere, below its equator
    assert sphere.clearance(centre, bare)[1] > 0.0
    assert sphere.clearance(centre, bodied)[1] < 0.0   # the body at z = -3 .. 27 cuts it


def test_every_stylus_of_a_profile_carries_its_body(tmp_path: Path) -> None:
    m = load_profile(profile_with(tmp_path, "body_diameter = 14.0\nbody_length = 65.0",
                                  "cmm.toml"))
    s = probe_stylus(m, 0.5, 0.35, 20.0)
    assert s.cylinders() == ((0.35, 0.5, 20.0), (7.0, 20.0, 85.0))
