"""Closed loop with planted form errors: program → virtual machine with a perturbed part
(``sim.form``) → log → ingest, against the planted truth.

Parts: ``samples/bore_block`` (the 50 mm bore gets a size error, a taper and a 3-lobe
roundness error; the 20 mm boss a size error) and ``samples/revolved_block`` (a cone
with a size error and 3 lobes, a dome with a size error and 4 lobes, a rounded bore
edge, a torus, with a thinner tube), each placed 0.3 / -0.2 mm off.

Truth: the planted ``δ`` at the points the virtual machine really touched (its contact
records), fitted by *linear* least squares to the first-order model of each fit
(``δ ≈ a0 + a1·cos θ + a2·sin θ`` per section; a cylinder adds the tilt terms
``h·cos θ, h·sin θ``, a cone the size slope ``h``, a sphere the centre terms): the
linearisation errs by ``δ²/R`` (< 1e-6 mm here), so this is an independent truth for
the non-linear fits in ``evaluate_revolved``.  Form is by the minimum zone (the default):
its truth is the same linear model's minimax range, one linear program (``zone``).
No pre-travel, no noise: the only error
left is the 4-decimal print of the DPRNT log (±5e-5 mm per coordinate), hence 1e-4 mm
for sizes and positions and 2e-4 mm for ranges (roundness, the difference of two
rounded residuals).  The torus's tube diameter comes from three rings on a quarter
of a 4 mm tube; the fit magnifies the print rounding about tenfold there (the
condition of the fit), so it is checked to 1e-3 mm, and to 1e-6 mm from the exact
ball centres.

DMIS: the virtual CMM fits the exact ball centres itself and prints five decimals, so
its actuals (the dome, and the torus's centre, axis, major and tube diameter) are
checked to 1e-4 mm against the truth.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from scipy.optimize import linprog

from probegen import cad
from probegen.cli.plan import checked_library
from probegen.dialects import get_dialect
from probegen.evaluate.ingest import ingest, nominal_of
from probegen.evaluate.outputs import to_json
from probegen.evaluate.revolved import evaluate_revolved
from probegen.machine.probe_model import ProbeModel
from probegen.planning import part_of, plan_program
from probegen.planning.revolved_spec import plan_revolved
from probegen.results import parse_dmis_output, parse_dprnt
from probegen.sim.contact import ContactHit, PlacedPart
from probegen.sim.form import FormError, Lobe
from probegen.sim.vm import VirtualMachine, run_text
from probegen.spec.model import load_spec

SIZE, RANGE = 1e-4, 2e-4
OFFSET = np.array([0.3, -0.2, 0.0])
BORE_BLOCK = REPO / "samples/bore_block/bore_block.toml"
REVOLVED_BLOCK = REPO / "samples/revolved_block/revolved_block.toml"
BORE = FormError(8, offset=0.004, taper=2e-4, lobes=(Lobe(3, 0.004, math.radians(20.0)),))
BOSS = FormError(7, offset=-0.006)
CONE = FormError(7, offset=0.003, lobes=(Lobe(3, 0.004, 0.3),))
DOME = FormError(8, offset=0.005, lobes=(Lobe(4, 0.002, 0.2),))
RIM = FormError(6, offset=-0.002)


def run(spec_path: Path, forms: tuple[FormError, ...], dialect: str,
        tmp_path: Path, *, compact: bool = False) -> tuple[str, VirtualMachine]:
    """The spec's program (``compact``: calling the macro library, written into
    ``tmp_path/lib`` as compile writes it) run on the part with the planted forms."""
    spec = load_spec(spec_path)
    d = get_dialect(dialect)
    d.compact = compact
    text = d.generate(plan_program(spec, runtime_variables=d.RUNTIME_VARIABLES).program)
    lib = None
    if compact:
        lib = tmp_path / "lib"
        lib.mkdir()
        for name, body in checked_library(d, spec.machine).items():
            (lib / name).write_text(body, encoding="ascii")
    assert spec.model is not None
    part = PlacedPart.from_model(cad.load_step(spec.model), translation=OFFSET, forms=forms)
    vm = VirtualMachine(part, ProbeModel(3.0))
    res = run_text(text, vm, kind="dmis" if dialect == "dmis" else "macrob", program_dir=lib)
    assert res.alarm is None
    return res.output, vm


def planted(vm: VirtualMachine, form: FormError, centre: tuple[float, float, float],
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """θ (about the true axis through ``centre``), h and δ at every touch of the face."""
    hits: list[ContactHit] = [t for t in vm.touches if t.face_id == form.face]
    rel = np.array([t.point for t in hits]) - OFFSET - np.asarray(centre)
    theta = np.arctan2(rel[:, 1], rel[:, 0])
    h = np.array([t.point[2] for t in hits]) - OFFSET[2]
    if form is DOME:
        h = rel[:, 2]  # a sphere's h runs from its centre
    delta = np.array([form.delta(a, b) for a, b in zip(theta, h, strict=True)])
    return theta, h, delta


def lsq(columns: list[np.ndarray], delta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear least squares: coefficients and residuals."""
    a = np.column_stack(columns)
    coef = np.linalg.lstsq(a, delta, rcond=None)[0]
    return coef, delta - a @ coef


def zone(columns: list[np.ndarray], delta: np.ndarray) -> float:
    """The minimum zone (ISO 1101) of ``delta`` under the same first-order model (the
    constant, the size, drops out of a range): ``min over c of range(delta - A c)``,
    one linear program (variables ``c``, upper ``u``, lower ``l``)."""
    a = np.column_stack(columns)
    n, k = a.shape
    ones = np.ones((n, 1))
    a_ub = np.vstack([np.hstack([-a, -ones, np.zeros((n, 1))]),
                      np.hstack([a, np.zeros((n, 1)), ones])])
    b_ub = np.concatenate([-delta, delta])
    cost = np.concatenate([np.zeros(k), [1.0, -1.0]])
    out = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=[(None, None)] * (k + 2),
                  method="highs")
    assert out.status == 0
    return float(out.fun)


def rings(theta: np.ndarray, h: np.ndarray, delta: np.ndarray
          ) -> dict[float, tuple[float, float]]:
    """Per section height: (size change a0, minimum-zone roundness); the least-squares
    roundness is never smaller."""
    out = {}
    for z in sorted(set(np.round(h, 3)), reverse=True):
        m = np.isclose(h, z, atol=0.01)
        coef, res = lsq([np.ones(m.sum()), np.cos(theta[m]), np.sin(theta[m])], delta[m])
        ron = zone([np.cos(theta[m]), np.sin(theta[m])], delta[m])
        assert ron <= float(np.ptp(res)) + 1e-12
        out[float(z)] = (float(coef[0]), ron)
    return out


def chars(result: object) -> dict[str, float]:
    return {c.name: c.measured for c in result.characteristics}  # type: ignore[attr-defined]


def test_fanuc_bore_block_size_taper_roundness(tmp_path: Path) -> None:
    output, vm = run(BORE_BLOCK, (BORE, BOSS), "fanuc", tmp_path)
    log = tmp_path / "run.log"
    log.write_text(output)
    ing = ingest(log, load_spec(BORE_BLOCK))
    assert not ing.notes
    bore, boss = (chars(r) for r in ing.revolved)
    theta, h, delta = planted(vm, BORE, (50.0, 50.0, 0.0))
    sections = rings(theta, h, delta)
    (a_top, ron_top), (a_bottom, ron_bottom) = sections[40.0], sections[10.0]
    assert bore["D_S1"] == pytest.approx(50.0 + 2 * a_top, abs=SIZE)
    assert bore["D_S2"] == pytest.approx(50.0 + 2 * a_bottom, abs=SIZE)
    assert bore["TAPER"] == pytest.approx(2 * (a_top - a_bottom), abs=SIZE)
    # as planted: the bore's 10 mm section has 7 touches of 8 (the OMP40 body of
    # vmc-fanuc.toml would meet the boss at the eighth), and the least-squares circle of 7
    # points on a 3-lobed ring is not the ring's mean: off the planted taper by the
    # sampling, within the stated uncertainty
    taper = next(c for c in ing.revolved[0].characteristics if c.name == "TAPER")
    assert taper.U is not None and 0.0 < taper.U < 0.02
    assert bore["TAPER"] == pytest.approx(2 * 2e-4 * 30.0, abs=taper.U)
    assert bore["RON_S1"] == pytest.approx(ron_top, abs=RANGE)
    assert bore["RON_S2"] == pytest.approx(ron_bottom, abs=RANGE)
    # the 3 lobes (2 x 0.004 peak to valley) sampled at 8 points: least squares 0.0075,
    # the minimum zone of those 8 points 0.0063
    assert ron_top > 0.006
    z = h - 25.0
    coef, res = lsq([np.ones_like(z), np.cos(theta), np.sin(theta), z * np.cos(theta),
                     z * np.sin(theta)], delta)
    assert bore["D"] == pytest.approx(50.0 + 2 * coef[0], abs=SIZE)
    cylindricity = zone([np.cos(theta), np.sin(theta), z * np.cos(theta), z * np.sin(theta)],
                        delta)
    assert cylindricity < np.ptp(res)
    assert bore["FORM"] == pytest.approx(cylindricity, abs=RANGE)
    shift = OFFSET[:2] + coef[1:3]
    assert bore["X"] == pytest.approx(50.0 + shift[0], abs=SIZE)
    assert bore["Y"] == pytest.approx(50.0 + shift[1], abs=SIZE)
    assert bore["POS"] == pytest.approx(2 * float(np.hypot(*shift)), abs=2 * SIZE)
    assert boss["D"] == pytest.approx(20.0 - 0.012, abs=SIZE)
    assert boss["X"] == pytest.approx(20.3, abs=SIZE)
    js = to_json(ing)
    assert '"name": "TAPER"' in js and '"name": "RON_S2"' in js
    from probegen.report.html import render_report

    html = render_report(json.loads(js))
    assert all(f">{name}<" in html for name in ("D_S1", "TAPER", "TILT"))
    assert ">RON_S1 <small>minimum zone</small><" in html


@pytest.mark.parametrize(("spec_path", "forms"), [(BORE_BLOCK, (BORE, BOSS)),
                                                 (REVOLVED_BLOCK, (CONE, DOME, RIM))],
                         ids=["bore_block", "revolved_block"])
def test_compact_form_measures_the_forms_as_inline(
        spec_path: Path, forms: tuple[FormError, ...], tmp_path: Path) -> None:
    """The compact program (G65 calls, the library prints a V2 log) on the same perturbed
    part: the same touches, exactly, and the same results.json as the inline program
    whose results the tests above check against the planted truth."""
    docs, touches = [], []
    for compact in (False, True):
        folder = tmp_path / str(compact)
        folder.mkdir()
        output, _ = run(spec_path, forms, "fanuc", folder, compact=compact)
        log = folder / "run.log"
        log.write_text(output)
        read = parse_dprnt(output, strict=True)
        touches.append([(t.kind, t.feature, t.index, t.xyz) for t in read.touches])
        doc = json.loads(to_json(ingest(log, load_spec(spec_path))))
        assert doc.pop("source") == str(log)
        docs.append(doc)
    assert touches[1] == touches[0] and len(touches[0]) >= 21
    assert docs[1] == docs[0] and docs[0]["features"]


def test_dmis_bore_block_with_forms_on_the_virtual_cmm(tmp_path: Path) -> None:
    output, vm = run(BORE_BLOCK, (BORE, BOSS), "dmis", tmp_path)
    bore = parse_dmis_output(output, strict=True).feature("BORE")
    theta, h, delta = planted(vm, BORE, (50.0, 50.0, 0.0))
    z = h - 25.0
    coef, _ = lsq([np.ones_like(z), np.cos(theta), np.sin(theta), z * np.cos(theta),
                   z * np.sin(theta)], delta)
    assert bore.diameter == pytest.approx(50.0 + 2 * coef[0], abs=SIZE)
    assert np.allclose(np.array(bore.position)[:2], 50.0 + OFFSET[:2] + coef[1:3], atol=SIZE)


@pytest.fixture(scope="module")
def revolved_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[object, VirtualMachine]:
    tmp = tmp_path_factory.mktemp("revolved")
    output, vm = run(REVOLVED_BLOCK, (CONE, DOME, RIM), "fanuc", tmp)
    log = tmp / "run.log"
    log.write_text(output)
    ing = ingest(log, load_spec(REVOLVED_BLOCK))
    assert not ing.notes and [r.kind for r in ing.revolved] == ["cone", "sphere", "torus"]
    return ing, vm


def test_fanuc_cone_gauge_diameters_and_roundness(
        revolved_run: tuple[object, VirtualMachine]) -> None:
    ing, vm = revolved_run
    cone = chars(ing.revolved[0])  # type: ignore[attr-defined]
    theta, h, delta = planted(vm, CONE, (25.0, 75.0, 0.0))
    coef, _ = lsq([np.ones_like(h), h, np.cos(theta), np.sin(theta), h * np.cos(theta),
                   h * np.sin(theta)], delta)
    for name, z, nominal in (("D_S1", 45.0, 18.0), ("D_S2", 35.0, 22.0)):
        assert cone[name] == pytest.approx(nominal + 2 * (coef[0] + coef[1] * z), abs=SIZE)
    # the ring heights differ a little (the part is off), so the section roundness is
    # compared with the planted lobes' range over each ring
    sections = rings(theta, np.where(h > 40.0, 45.0, 35.0), delta)
    assert len(sections) == 2
    for k, (_, ron) in enumerate(sections.values(), start=1):
        assert cone[f"RON_S{k}"] == pytest.approx(ron, abs=RANGE)
    assert cone["ANGLE"] == pytest.approx(math.degrees(math.atan(0.2)), abs=1e-3)
    assert cone["X"] == pytest.approx(25.3, abs=SIZE)
    assert cone["Y"] == pytest.approx(74.8, abs=SIZE)


def test_fanuc_sphere_and_torus(revolved_run: tuple[object, VirtualMachine]) -> None:
    ing, vm = revolved_run
    _, dome, rim = (chars(r) for r in ing.revolved)  # type: ignore[attr-defined]
    theta, h, delta = planted(vm, DOME, (75.0, 75.0, 30.0))
    polar = np.arccos(np.clip(h / 15.0, -1.0, 1.0))
    u = [np.sin(polar) * np.cos(theta), np.sin(polar) * np.sin(theta), np.cos(polar)]
    coef, res = lsq([np.ones_like(h), *u], delta)
    assert dome["D"] == pytest.approx(30.0 + 2 * coef[0], abs=SIZE)
    assert dome["FORM"] == pytest.approx(zone(u, delta), abs=RANGE)
    assert dome["X"] == pytest.approx(75.3 + coef[1], abs=SIZE)
    assert dome["Z"] == pytest.approx(30.0 + coef[3], abs=SIZE)
    assert rim["D"] == pytest.approx(8.0 - 0.004, abs=1e-3)
    assert rim["DMAJ"] == pytest.approx(38.0, abs=1e-3)


def test_torus_from_exact_ball_centres(revolved_run: tuple[object, VirtualMachine]) -> None:
    _, vm = revolved_run
    spec = load_spec(REVOLVED_BLOCK)
    rim = next(f for f in spec.features if f.id == "RIM")
    plan = plan_revolved(rim, part_of(spec), spec.machine, spec.clearance_z)  # type: ignore[arg-type]
    centres = [t.centre for t in vm.touches if t.face_id == RIM.face]
    sections = [plan.section_of_touch[k] for k in sorted(plan.normals)]
    res = evaluate_revolved("RIM", nominal_of(plan), centres, sections, ball_radius=3.0,
                            limits=rim.tolerance)  # type: ignore[arg-type]
    got = chars(res)
    assert got["D"] == pytest.approx(8.0 - 0.004, abs=1e-6)
    assert got["DMAJ"] == pytest.approx(38.0, abs=1e-6)
    assert got["POS"] == pytest.approx(2 * math.hypot(0.3, 0.2), abs=1e-6)


def test_dmis_cone_sphere_and_torus_with_forms_on_the_virtual_cmm(tmp_path: Path) -> None:
    output, vm = run(REVOLVED_BLOCK, (CONE, DOME, RIM), "dmis", tmp_path)
    out = parse_dmis_output(output, strict=True)
    rim = out.feature("RIM")
    # the CMM fits the exact ball centres; only the output's 5 decimals round
    assert (rim.type, rim.material) == ("TORUS", "OUTER")
    assert np.allclose(rim.position, np.array([25.0, 25.0, 26.0]) + OFFSET, atol=SIZE)
    assert np.allclose(rim.direction, [0.0, 0.0, 1.0], atol=SIZE)
    assert rim.diameter == pytest.approx(38.0, abs=SIZE)
    assert rim.minor_diameter == pytest.approx(8.0 + 2 * RIM.offset, abs=SIZE)
    dome = out.feature("DOME")
    theta, h, delta = planted(vm, DOME, (75.0, 75.0, 30.0))
    polar = np.arccos(np.clip(h / 15.0, -1.0, 1.0))
    u = [np.sin(polar) * np.cos(theta), np.sin(polar) * np.sin(theta), np.cos(polar)]
    coef, _ = lsq([np.ones_like(h), *u], delta)
    assert dome.diameter == pytest.approx(30.0 + 2 * coef[0], abs=SIZE)
    want = np.array([75.0, 75.0, 30.0]) + OFFSET + coef[1:]
    assert np.allclose(dome.position, want, atol=SIZE)
    cone = out.feature("CONE")
    # the apex (the CMM reports it): 0.003 mm more radius moves it 0.003 / tan α up
    assert np.allclose(cone.position, [25.3, 74.8, 90.0 + 0.003 / 0.2], atol=1e-3)


def test_too_few_sections_or_touches_are_notes(tmp_path: Path) -> None:
    """A log without the last ring of the torus and the dome's lower ring: each is left
    out with a note saying what was missing; the cone (all its touches) is evaluated."""
    output, _ = run(REVOLVED_BLOCK, (), "fanuc", tmp_path)
    drop = {("RIM", k) for k in range(17, 25)} | {("DOME", k) for k in range(9, 17)}
    kept = [line for line in output.splitlines(keepends=True)
            if not (line.startswith("PT ") and (line.split()[1], int(line.split()[2])) in drop)]
    log = tmp_path / "cut.log"
    log.write_text("".join(kept))
    ing = ingest(log, load_spec(REVOLVED_BLOCK))
    assert [r.feature for r in ing.revolved] == ["CONE"]
    assert "feature DOME: not evaluated, 8 touches in 1 sections (at least 5 needed, in 2 " \
        "sections)" in ing.notes
    assert "feature RIM: not evaluated, 16 touches in 2 sections (at least 8 needed, in 3 " \
        "sections)" in ing.notes
    assert "feature RIM: no touch for points 17-24" in ing.notes
