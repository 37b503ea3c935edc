"""Closed loop in the Haas dialect: every sample spec's Haas program runs on the virtual
machine as a Haas control (``control="haas"``: G100 cancels mirror image, G15 and G50.1
are not there) and gives the Fanuc program's touches and results.

Planted truth: the part sits 0.03, -0.02, 0.01 mm off the G54 origin (G54 itself at
300, 200, -100 mm from machine zero), turned 0.05 degrees about Z; the probe has
direction-dependent pre-travel (lobing); the bore_block specs measure a block whose bore
is 0.03 mm oversize, so the in-process actions correct tool 12's radius.

Tolerance: none, the logs are compared byte for byte and ``results.json`` as text.  The
two programs differ only in words that do not move the machine (the reset block: G100
for G15 G50.1) and in the value written to the D wear register (a Haas D offset is a
diameter: ``R[2.0*#]``), so the virtual machine commands the same positions in the same
order: the skip positions, and every 4-decimal number DPRNT prints from them, are the
same floating-point numbers, and ingest is deterministic.  Any difference is a bug.
That the Fanuc results are right against the planted truth is the other closed-loop
tests' business (test_closed_loop*.py, test_actions_closed_loop.py,
test_freeform_closed_loop.py).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, sample_script

from probegen import cad
from probegen.dialects import get_dialect
from probegen.evaluate.ingest import ingest
from probegen.evaluate.outputs import to_json
from probegen.machine.probe_model import Lobing, ProbeModel
from probegen.planning import plan_program
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import SimResult, VirtualMachine, run_text
from probegen.spec.model import Spec, SphereTest, load_spec

SPECS = sorted(p.relative_to(REPO) for p in (REPO / "samples").glob("*/*.toml")
               if "[[feature]]" in p.read_text(encoding="utf-8"))
WORK = (300.0, 200.0, -100.0)             # G54 before the run, machine coordinates
SHIFT = np.array([0.03, -0.02, 0.01])     # where the part really is, from G54
ANGLE = math.radians(0.05)
LOBING = Lobing(0.0012, 0.0008, 0.0005)
D_REGISTERS = range(12001, 14000)         # memory C: D wear 12001-, D geometry 13001-


def test_every_sample_spec_is_here() -> None:
    """The specs the issue names (sphere test, bore_block actions, revolved_block,
    free-form) are all among the ones looped over."""
    names = {p.stem for p in SPECS}
    assert {"sphere_test", "bore_block_actions", "revolved_block", "freeform"} <= names
    assert len(SPECS) == 10


@pytest.fixture(scope="module")
def oversize_bore_block(tmp_path_factory: pytest.TempPathFactory) -> cad.Model:
    path = tmp_path_factory.mktemp("haas") / "bore+0.03.step"
    sample_script("bore_block").main(path, bore_diameter=50.03, boss_diameter=20.0)
    return cad.load_step(path)


def placed_part(spec: Spec, bore_block: cad.Model) -> PlacedPart:
    """The spec's part placed with the planted shift and turn (module docstring)."""
    c, s = math.cos(ANGLE), math.sin(ANGLE)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    translation = np.array(WORK) + SHIFT
    if spec.model is None:
        spheres = [f for f in spec.features if isinstance(f, SphereTest) and f.centre]
        return PlacedPart.from_spheres([f.centre for f in spheres],
                                       [(f.diameter or 0.0) / 2.0 for f in spheres],
                                       rotation=rotation, translation=translation)
    model = bore_block if spec.model.name == "bore_block.step" else cad.load_step(spec.model)
    return PlacedPart.from_model(model, rotation=rotation, translation=translation)


def run(text: str, part: PlacedPart, ball: float, control: str) -> SimResult:
    vm = VirtualMachine(part, ProbeModel(ball, LOBING))
    return run_text(text, vm, kind="macrob", work_offset=WORK, control=control)


def results(res: SimResult, spec: Spec, folder: Path) -> dict[str, object]:
    """``results.json`` of a run's log, without the log's path."""
    folder.mkdir()
    log = folder / "run.log"
    log.write_text(res.output, encoding="ascii")
    doc = json.loads(to_json(ingest(log, spec)))
    assert doc.pop("source") == str(log)
    return dict(doc)


@pytest.mark.parametrize("spec_path", SPECS, ids=lambda p: p.stem)
def test_haas_program_measures_as_the_fanuc_program(
        spec_path: Path, oversize_bore_block: cad.Model, tmp_path: Path) -> None:
    spec = load_spec(REPO / spec_path)
    program = plan_program(spec, runtime_variables=True).program
    fanuc_text, haas_text = (get_dialect(d).generate(program) for d in ("fanuc", "haas"))
    assert "G50.1" not in haas_text  # Haas has no G50.1 (G100 where it cancels mirroring)
    part = placed_part(spec, oversize_bore_block)
    ball = spec.machine.probe.ball_radius
    fanuc = run(fanuc_text, part, ball, "fanuc")
    haas = run(haas_text, part, ball, "haas")
    assert fanuc.alarm is None and haas.alarm is None, (fanuc.alarm, haas.alarm)
    assert haas.touches == fanuc.touches > 0
    assert haas.output == fanuc.output and "PGEND" in haas.output
    # what the program left in the control: a Haas D register holds a diameter
    d_written = {k for k in fanuc.variables if k in D_REGISTERS}
    assert set(haas.variables) == set(fanuc.variables)
    for key, value in fanuc.variables.items():
        assert haas.variables[key] == (2.0 * value if key in d_written else value), key
    assert (12012 in d_written) == (spec_path.stem == "bore_block_actions")
    haas_doc = results(haas, spec, tmp_path / "haas")
    assert haas_doc == results(fanuc, spec, tmp_path / "fanuc")
    assert haas_doc["complete"] and haas_doc["features"]
