"""`plan --all-revolved` on NIST models and the DCX part, the Fanuc program on the virtual
machine (the part at its nominal placement): no alarm, every touch touches.

Features whose moves collide are left out with the collision in the notes, not the
whole model refused.  The models are the small ones (measured: FTC 11 about 1 s, CTC 3
about 3 s, DCX about 11 s with the simulation); `benchmarks/bench_revolved.py` runs all.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, SHARED

from probegen import cad
from probegen.dialects import get_dialect
from probegen.errors import ProbegenError
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


@pytest.mark.parametrize(("model", "planned", "collides"), [
    (NIST / "nist_ftc_11_asme1_rb.stp", 2, 0),
    (NIST / "nist_ctc_03_asme1_rc.stp", 20, 0),
    (DCX, 11, 10),
])
def test_all_revolved_runs_on_the_virtual_machine(model: Path, planned: int,
                                                  collides: int) -> None:
    machine = load_profile(MACHINE)
    spec, notes = all_revolved_spec(_need(model), machine)
    result = plan_program(spec, runtime_variables=True)
    assert len(result.revolved) == planned
    assert result.clearance.minimum >= 0.0
    left = [n for n in notes if "left out, it collides" in n]
    assert len(left) == collides
    assert all("expected a clearance of at least" in n for n in left)
    touches = sum(len(p.normals) for p in result.revolved)
    text = get_dialect("fanuc").generate(result.program)
    vm = VirtualMachine(PlacedPart.from_model(cad.load_step(model)),
                        ProbeModel(machine.probe.ball_radius))
    res = run_text(text, vm, kind="macrob")
    assert res.alarm is None
    assert res.touches == touches


def test_model_without_a_plannable_feature_names_the_reasons() -> None:
    with pytest.raises(ProbegenError, match="is not parallel to Z"):
        all_revolved_spec(_need(NIST / "nist_ftc_09_asme1_rd.stp"), load_profile(MACHINE))


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
