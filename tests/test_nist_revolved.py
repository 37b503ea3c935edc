"""`plan --all-revolved` on NIST models and the DCX part, the Fanuc program on the virtual
machine (the part at its nominal placement): no alarm, every touch touches.

Features whose moves collide are left out with the collision in the notes, not the
whole model refused.  The models are the small ones (measured: FTC 11 about 1 s, CTC 3
about 3 s, DCX about 11 s with the simulation); `benchmarks/bench_revolved.py` runs all.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, SHARED

from probegen import cad
from probegen.dialects import get_dialect
from probegen.machine.probe_model import ProbeModel
from probegen.machine.profile import load_profile
from probegen.planning import plan_program
from probegen.planning.revolved_spec import all_revolved_spec
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import VirtualMachine, run_text

NIST = SHARED / "ref/nist-step"
DCX = SHARED / "ref/nist-ippdme/DCXpart/STEP_AP214/DaimlerChryslerTestPartAP214.stp"
MACHINE = REPO / "samples/machines/vmc-fanuc.toml"


def _need(path: Path) -> Path:
    if not path.exists():
        pytest.skip(f"{path} is not here")
    return path


@pytest.mark.parametrize(("model", "raised", "planned", "unsafe"), [
    # the 1.5 mm plate on parallels 10 mm high: its bore and boss measured through the
    # whole thickness; lying on the table, every touch of the ball (D6) at their
    # sections (z = -0.75) would reach into it: both left out, the table named
    (NIST / "nist_ftc_11_asme1_rb.stp", 10.0, 3, 0),
    (NIST / "nist_ftc_11_asme1_rb.stp", 0.0, 1, 2),
    # the sheet-metal part (3.2 mm sheet) on parallels; on the table its ten holes in the
    # sheet would be left out as FTC 11's
    (NIST / "nist_ctc_03_asme1_rc.stp", 10.0, 20, 0),
    # 33 before: +2 short arcs tried with the margin alone at their ends, -4 tori of two
    # tube positions refused (below); 7 unsafe: the three rounded edges under the 122
    # face, three tori whose every touch the OMP40-like body of vmc-fanuc.toml would
    # take into a wall (before the body was stated they were reached in two tube
    # positions, too few for ingest), and the torus R41 at the foot of the part (its
    # lowest touches 1.6 mm above the table; the ball would reach into it)
    (DCX, 0.0, 31, 7),
])
def test_all_revolved_runs_on_the_virtual_machine(model: Path, raised: float, planned: int,
                                                  unsafe: int) -> None:
    """Every feature that can be made safe is planned (rerouted where the collision
    check asks); the ones that cannot are reported with the move and the face or the
    table (DCX: the three rounded edges under the 122 face, their tube facing away from
    a vertical probe); the whole program clears and runs on the virtual machine."""
    machine = load_profile(MACHINE)
    part = cad.load_part(_need(model), raised=raised)
    spec, notes = all_revolved_spec(part, machine)
    result = plan_program(spec, runtime_variables=True, part=part)
    assert len(result.revolved) == planned
    assert result.clearance.minimum >= 0.0
    assert not [n for n in notes if "left out, it collides" in n]
    left = [n for n in notes if "no touch can be reached safely" in n]
    assert len(left) == unsafe
    assert all(re.search(r"approach from \(.+\) to \(.+\): the (stylus ball|stylus shank|"
                         r"probe body) .+ (face \d+|the table)", n) for n in left)
    tabled = {n.split()[0] for n in left if "into the table" in n}
    assert len(tabled) == (2 if raised == 0.0 and model != DCX else int(model == DCX))
    if raised == 0.0 and model != DCX:  # the reason says what to do
        assert all("): no room above the table: the stylus ball reaches 2.251 mm into the "
                   "table the part stands on (state how far it is raised: [part] raised, "
                   "--raised; or a smaller stylus)" in n for n in left), left
    assert not [n for n in notes if "too few touches to evaluate it" in n]
    touches = sum(len(p.normals) for p in result.revolved)
    text = get_dialect("fanuc").generate(result.program)
    vm = VirtualMachine(PlacedPart.from_model(cad.load_step(model)),
                        ProbeModel(machine.probe.ball_radius))
    res = run_text(text, vm, kind="macrob")
    assert res.alarm is None
    assert res.touches == touches


def test_model_without_a_plannable_feature_completes_and_names_the_reasons(
        capsys: pytest.CaptureFixture[str]) -> None:
    """FTC 9: every axis is horizontal, out of reach of a vertical probe: the spec has
    no feature, the program is empty, and `plan --all-revolved` exits 0 with the notes."""
    from probegen.cli.app import ExitCode, main

    model = _need(NIST / "nist_ftc_09_asme1_rd.stp")
    part = cad.load_part(model)
    spec, notes = all_revolved_spec(part, load_profile(MACHINE))
    assert spec.features == ()
    assert notes and all(re.fullmatch(r"R\d+ (bore|boss|inner cone) D[\d.]+ "
                                      r"\((cylinder|cone), faces [\d,]+\): axis "
                                      r"\(.+\) is 90\.0 deg from Z, not along the probe: "
                                      r"needs an orientation or a setup(; bore D[\d.]+: the "
                                      r"stylus ball D6\.000 needs D8\.000 or more, the ball and "
                                      r"1\.000 mm each side for the retract and safe circle: "
                                      r"a smaller stylus)?", n) for n in notes)
    planned = plan_program(spec, runtime_variables=True, part=part)
    assert planned.revolved == () and planned.program.body == ()
    assert main(["plan", str(model), "--all-revolved", "--machine",
                 str(MACHINE)]) == ExitCode.OK
    out = capsys.readouterr().out
    assert "no revolved feature of" in out and "can be measured safely" in out
    assert f"left out ({len(notes)} recognised features;" in out
    assert [line[2:] for line in out.splitlines() if line.startswith("  R")] == list(notes)


def test_retract_from_a_trigger_that_rounds_outside_the_surface() -> None:
    """CTC 1, feature 21 (a quarter bore, face 54): the trigger point lies 1.3e-15 mm
    outside the surface; backing away from it is not a collision."""
    part = PlacedPart.from_model(cad.load_step(_need(NIST / "nist_ctc_01_asme1_rd.stp")))
    vm = VirtualMachine(part, ProbeModel(3.0))
    safe, target = (-234.7426, -132.5334, -15.0), (-236.6911, -129.0401, -15.0)
    hit = vm.skip(safe, target, 300.0)
    assert hit is not None
    assert part.clearance(np.asarray(hit), 3.0) > 0.0  # the rounding this test is about
    vm.feed(hit, safe, 2000.0)  # no alarm
