"""M5 grating programs: golden files, layout, collision check, the virtual grating."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, assert_golden

from probegen import ir
from probegen.cli.grating import grating_programs, readings_of, simulate_readings
from probegen.errors import CollisionError, SpecError, UnsupportedError
from probegen.machine.kinematics import Machine
from probegen.planning.grating import (
    GratingSetup,
    GratingSpec,
    build_program,
    check_clear,
    load_grating_spec,
    plan_setup,
)
from probegen.sim.grating import VirtualGrating, run_grating

SAMPLE = REPO / "samples" / "grating" / "grating.toml"


def test_sample_spec_is_the_default() -> None:
    assert load_grating_spec(str(SAMPLE)) == GratingSpec()


@pytest.mark.parametrize("dialect", ["fanuc", "haas"])
def test_programs_match_golden(in_repo: Path, dialect: str) -> None:
    programs = grating_programs(load_grating_spec("samples/grating/grating.toml"),
                                second_offset=True, dialect=dialect)
    assert [p.file_name.split(".")[0] for p in programs] == [
        "O7100_XY", "O7101_XZ", "O7102_YZ", "O7103_XY_riser", "O7104_XZ_riser",
        "O7105_YZ_riser"]
    for p in programs:
        assert_golden(REPO / "tests" / "golden" / "grating" / dialect / p.file_name, p.text)


def test_program_layout_one_dwell_per_stop() -> None:
    (xy, *_) = grating_programs(GratingSpec())
    lines = xy.text.splitlines()
    g1 = [k for k, line in enumerate(lines) if line.startswith("G1 ")]
    assert len(g1) == len(xy.plan.stops) == 1 + 6 * 10
    assert all(lines[k + 1] == "G4 P500" for k in g1)
    assert lines.count("G4 P500") == len(g1)
    # the approach comes from above A, the program ends back at the clearance height
    assert lines[g1[0] - 1] == "G0 X-100.0000 Y-100.0000 Z-170.0000"
    assert "G0 G43 H30 Z-170.0000" in lines and lines[-2] == "M30"


def test_seed_path_lines_and_corners() -> None:
    plan = plan_setup(GratingSpec(), GratingSetup("XY", -200.0, 0.0, 100.0))
    names = [name for name, _ in plan.lines]
    assert names == ["L10", "L11", "L12", "L13", "L14"]
    lines = dict(plan.lines)
    assert len(lines["L11"]) == 22  # the diagonal twice
    a, b = plan.stops[lines["L10"][0]], plan.stops[lines["L10"][-1]]
    assert tuple(a[:2]) == (-100.0, -100.0) and tuple(b[:2]) == (100.0, -100.0)
    assert lines["L10"][-1] == lines["L11"][0]  # corner B: one stop, two lines
    assert tuple(plan.stops[lines["L14"][-1]][:2]) == (-100.0, -100.0)


def test_a_move_into_the_plate_is_refused() -> None:
    spec = GratingSpec()
    plan = plan_setup(spec, GratingSetup("XZ", 50.0, 0.0, 100.0))
    program = build_program(spec, plan, 1)
    body = list(program.body)
    check_clear(plan, body)
    body.append(ir.Move((0.0, 50.5, -200.0), ir.MoveMode.RETRACT))  # +Y: into the plate
    with pytest.raises(CollisionError, match="into the grating plate"):
        check_clear(plan, body)


def test_other_dialects_and_bad_specs_are_refused(tmp_path: Path) -> None:
    with pytest.raises(UnsupportedError, match="expected one of fanuc, haas"):
        grating_programs(GratingSpec(), dialect="dmis")
    text = SAMPLE.read_text(encoding="utf-8").replace(
        "u = [-100.0, 100.0]    # Y", "u = [-90.0, 100.0]    # Y")
    bad = tmp_path / "g.toml"
    bad.write_text(text, encoding="utf-8")
    with pytest.raises(SpecError, match=r"grating.YZ: expected the Y range"):
        load_grating_spec(str(bad))
    no_riser = dataclasses.replace(GratingSpec(), planes=tuple(
        dataclasses.replace(p, riser=None) for p in GratingSpec().planes))
    with pytest.raises(SpecError, match="riser"):
        grating_programs(no_riser, second_offset=True)


def test_perfect_machine_reads_zero_and_stops_are_the_plan() -> None:
    readings = simulate_readings(GratingSpec(), Machine(), second_offset=True)
    assert len(readings) == 6 * (5 * 11 + 11)
    assert max(abs(r.du) + abs(r.dv) for r in readings) == 0.0


def test_virtual_grating_reads_the_program_text() -> None:
    """A program that leaves out a stop is caught: the run is paired with the plan."""
    (prog, *_) = grating_programs(GratingSpec())
    lines = prog.text.splitlines(keepends=True)
    k = next(i for i, line in enumerate(lines) if line.startswith("G1 X20.0000"))
    text = "".join(lines[:k] + lines[k + 2:])
    grating = VirtualGrating(Machine(), "XY", -200.0, 100.0)
    stops = run_grating(text, grating, tool=30)
    assert len(stops) == len(prog.plan.stops) - 1
    with pytest.raises(Exception, match="expected 61 sampling stops, found 60"):
        readings_of(prog.plan, [(s.point, s.du, s.dv) for s in stops])
    assert np.allclose(stops[0].point, prog.plan.stops[0])
