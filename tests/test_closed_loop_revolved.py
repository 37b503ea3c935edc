"""Closed loop for revolved features (method M2): bore_block program → virtual machine →
log → ingest, against the planted truth.

The part is placed 0.3 mm off in X and -0.2 mm in Y; a variant part (built here with
build123d) has a 50.02 mm bore.  The probe has no pre-travel and no noise, so the
recovered bore must match the planted position and diameter to 1e-4 mm (the DPRNT log
prints 4 decimals).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, sample_script

from probegen import cad
from probegen.dialects import get_dialect
from probegen.evaluate.ingest import ingest
from probegen.evaluate.outputs import to_json
from probegen.machine.probe_model import ProbeModel
from probegen.planning import plan_program
from probegen.results import parse_dmis_output
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import VirtualMachine, run_text
from probegen.spec.model import load_spec

TOL = 1e-4
SPEC = Path("samples/bore_block/bore_block.toml")
OFFSET = np.array([0.3, -0.2, 0.0])
BORE = np.array([50.0, 50.0])
BOSS = np.array([20.0, 20.0])


@pytest.fixture(scope="module")
def models(tmp_path_factory: pytest.TempPathFactory) -> dict[float, cad.Model]:
    make = sample_script("bore_block")
    variant = tmp_path_factory.mktemp("bore") / "bore_50_02.step"
    make.main(variant, bore_diameter=50.02)
    return {50.0: cad.load_step(REPO / "samples/bore_block/bore_block.step"),
            50.02: cad.load_step(variant)}


def program(dialect: str) -> str:
    d = get_dialect(dialect)
    planned = plan_program(load_spec(SPEC), runtime_variables=d.RUNTIME_VARIABLES)
    assert planned.clearance.minimum >= 0.0
    return d.generate(planned.program)


@pytest.mark.parametrize("diameter", [50.0, 50.02])
def test_fanuc_bore_block_recovers_planted_truth(in_repo: Path, tmp_path: Path,
                                                 models: dict[float, cad.Model],
                                                 diameter: float) -> None:
    text = program("fanuc")
    vm = VirtualMachine(PlacedPart.from_model(models[diameter], translation=OFFSET),
                        ProbeModel(3.0))
    res = run_text(text, vm, kind="macrob")
    # 22 planned, less the bore's touch at 45 deg in its 10 mm section: the OMP40
    # body of vmc-fanuc.toml would meet the boss there
    assert res.alarm is None and res.touches == 21
    log = tmp_path / "run.log"
    log.write_text(res.output)
    ing = ingest(log, load_spec(SPEC))
    assert ing.results == () and not ing.notes
    bore, boss = ing.revolved
    assert (bore.feature, bore.kind, boss.feature, boss.kind) == (
        "BORE", "cylinder", "BOSS", "circle")
    assert np.allclose(bore.centre[:2], BORE + OFFSET[:2], atol=TOL)
    assert bore.diameter == pytest.approx(diameter, abs=TOL)
    assert bore.form < 2 * TOL  # only the rounding of the log (4 decimals)
    assert np.allclose(boss.centre[:2], BOSS + OFFSET[:2], atol=TOL)
    assert boss.diameter == pytest.approx(20.0, abs=TOL)
    chars = {c.name: c for c in bore.characteristics}
    assert chars["POS"].measured == pytest.approx(2 * np.hypot(0.3, 0.2), abs=2 * TOL)
    assert chars["POS"].ok is False  # 0.72 mm zone, 0.05 allowed
    assert chars["D"].ok is True
    assert '"kind": "cylinder"' in to_json(ing)


@pytest.mark.parametrize("diameter", [50.0, 50.02])
def test_dmis_bore_block_on_the_virtual_cmm(in_repo: Path, models: dict[float, cad.Model],
                                            diameter: float) -> None:
    text = program("dmis")
    vm = VirtualMachine(PlacedPart.from_model(models[diameter], translation=OFFSET),
                        ProbeModel(3.0))
    res = run_text(text, vm, kind="dmis")
    assert res.alarm is None
    out = parse_dmis_output(res.output, strict=True)
    bore = out.feature("BORE")
    assert np.allclose(np.array(bore.position)[:2], BORE + OFFSET[:2], atol=TOL)
    assert bore.diameter == pytest.approx(diameter, abs=TOL)
    boss = out.feature("BOSS")
    assert np.allclose(np.array(boss.position)[:2], BOSS + OFFSET[:2], atol=TOL)
    assert boss.diameter == pytest.approx(20.0, abs=TOL)
