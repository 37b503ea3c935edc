"""QIF export of every evaluated kind (``probegen qif LOG --spec``): circle, cylinder, cone,
sphere, torus and free-form results next to a sphere test, schema-valid, with each
value's standard uncertainty and the statuses of the decision rule.

The results are built from synthetic ball centres on each kind's offset surface (a
2 µm Gaussian noise, fixed seed), so every kind is present without a virtual machine
run.
"""

from __future__ import annotations

import dataclasses
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, SHARED
from test_no_false_ok import faces_log  # noqa: F401  (the module-scoped fixture)
from test_planar_form import bumped, faces_spec
from test_uncertainty import BORE, bore_centres

from probegen.evaluate.freeform import NominalPoint, evaluate_freeform
from probegen.evaluate.ingest import Ingested, ingest
from probegen.evaluate.revolved import Nominal, RevolvedResult, evaluate_revolved
from probegen.geometry.uncertainty import Budget
from probegen.qif.export import ingested_to_qif, load_schema, validate_qif
from probegen.results.dprnt_records import DprntLog
from probegen.spec.model import FREEFORM_STRIDE, load_spec

SCHEMA = SHARED / "ref/qif/schema"
NS = {"q": "http://qifstandards.org/xsd/qif3"}
R = 3.0
NOISE = 0.002


@dataclasses.dataclass(frozen=True)
class Limits:
    diameter: tuple[float, float] | None = (-0.02, 0.02)
    position: float | None = 0.1
    form: float | None = 0.02
    roundness: float | None = 0.02
    taper: float | None = 0.01
    angle: tuple[float, float] | None = (-0.1, 0.1)


@pytest.fixture(scope="module")
def schema() -> Path:
    load_schema(SCHEMA)
    return SCHEMA


def _ring(n: int) -> np.ndarray:
    return 0.3 + 2.0 * math.pi * np.arange(n) / n


def _circle(rng: np.random.Generator) -> RevolvedResult:
    t = _ring(8)
    c = np.column_stack([(10.0 - R) * np.cos(t), (10.0 - R) * np.sin(t), np.full(8, -4.0)])
    nominal = Nominal("circle", (0.0, 0.0, -4.0), (0.0, 0.0, 1.0), 20.0, True,
                      (((0.0, 0.0, -4.0), 20.0),))
    return evaluate_revolved("HOLE", nominal, c + rng.normal(0, NOISE, c.shape), np.zeros(8),
                             ball_radius=R, limits=Limits(), budget=Budget(machine=0.001))


def _cylinder(rng: np.random.Generator) -> RevolvedResult:
    c, k = bore_centres(rng, R)
    return evaluate_revolved("BORE", BORE, c, k, ball_radius=R, limits=Limits())


def _cone(rng: np.random.Generator) -> RevolvedResult:
    # a conical hole, apex at z = -40 on the Z axis, half angle 20 deg, ball inside
    alpha, pts, secs = math.radians(20.0), [], []
    heights = (-5.0, -15.0)
    for j, z in enumerate(heights):
        rad = (z + 40.0) * math.tan(alpha)
        for t in _ring(8):
            e = np.array([math.cos(t), math.sin(t), 0.0])
            surface = rad * e + [0.0, 0.0, z]
            pts.append(surface + R * (-math.cos(alpha) * e + [0.0, 0.0, math.sin(alpha)]))
            secs.append(j)
    sections = tuple(((0.0, 0.0, z), 2.0 * (z + 40.0) * math.tan(alpha)) for z in heights)
    nominal = Nominal("cone", (0.0, 0.0, -40.0), (0.0, 0.0, 1.0), 0.0, True, sections,
                      half_angle=alpha)
    c = np.array(pts)
    return evaluate_revolved("CONE", nominal, c + rng.normal(0, NOISE, c.shape), secs,
                             ball_radius=R, limits=Limits())


def _sphere(rng: np.random.Generator) -> RevolvedResult:
    pts, secs = [], []
    for j, polar in enumerate((0.6, 1.2)):
        for t in _ring(6):
            pts.append((15.0 - R) * np.array([math.cos(t) * math.sin(polar),
                                              math.sin(t) * math.sin(polar), math.cos(polar)]))
            secs.append(j)
    c = np.array(pts)
    nominal = Nominal("sphere", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 30.0, True,
                      (((0.0, 0.0, 8.0), 20.0), ((0.0, 0.0, 4.0), 28.0)))
    return evaluate_revolved("CAV", nominal, c + rng.normal(0, NOISE, c.shape), secs,
                             ball_radius=R, limits=Limits())


def _torus(rng: np.random.Generator) -> RevolvedResult:
    big, tube, pts, secs = 30.0, 5.0, [], []
    for j, phi in enumerate((-0.7, 0.0, 0.7)):
        for t in _ring(8):
            e = np.array([math.cos(t), math.sin(t), 0.0])
            pts.append(big * e + (tube + R) * (math.cos(phi) * e + [0, 0, math.sin(phi)]))
            secs.append(j)
    c = np.array(pts)
    nominal = Nominal("torus", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 10.0, False,
                      tuple(((0.0, 0.0, 0.0), 60.0) for _ in range(3)), major_diameter=60.0)
    return evaluate_revolved("RIM", nominal, c + rng.normal(0, NOISE, c.shape), secs,
                             ball_radius=R, limits=Limits())


def _freeform() -> object:
    nominal = [NominalPoint(g, (10.0 * g, 0.0, 0.0), (0.0, 0.0, 1.0)) for g in (1, 2, 3)]
    dev = {1: 0.001, 2: -0.004, 3: 0.03}
    touches = {("SURF", FREEFORM_STRIDE * g): (10.0 * g, 0.0, R + dev[g]) for g in dev}
    return evaluate_freeform("SURF", "vector", nominal, touches, direction=(0.0, 0.0, 1.0),
                             radius=R, deviation=(-0.02, 0.02),
                             budget=Budget(machine=0.001, probe=0.001))


@pytest.fixture(scope="module")
def every_kind() -> Ingested:
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(REPO)
        sphere = ingest("samples/sphere25/sphere_test.log",
                        load_spec("samples/sphere25/sphere_test.toml"))
    rng = np.random.default_rng(15)
    revolved = (_circle(rng), _cylinder(rng), _cone(rng), _sphere(rng), _torus(rng))
    log = DprntLog("synthetic.log", 1001, (), (), (), True, 0, ())
    return dataclasses.replace(sphere, source="synthetic.log", log=log, revolved=revolved,
                               freeform=(_freeform(),))


def _doc(text: str) -> ET.Element:
    return ET.fromstring(text)


def test_every_kind_is_exported_and_schema_valid(schema: Path, every_kind: Ingested) -> None:
    text = ingested_to_qif(every_kind, version="0.0.0")
    validate_qif(text, schema=schema)
    root = _doc(text)
    names = {e.tag.split("}")[1]: 0 for e in root.iterfind(".//q:MeasuredFeatures/*", NS)}
    for e in root.iterfind(".//q:MeasuredFeatures/*", NS):
        names[e.tag.split("}")[1]] += 1
    assert names == {"SphereFeatureMeasurement": 2, "CircleFeatureMeasurement": 1,
                     "CylinderFeatureMeasurement": 1, "ConeFeatureMeasurement": 1,
                     "TorusFeatureMeasurement": 1, "PointFeatureMeasurement": 3}
    items = {e.findtext("q:Name", namespaces=NS) for e in
             root.iterfind(".//q:CharacteristicItems/*", NS)}
    assert {"HOLE D", "HOLE POS", "HOLE FORM", "BORE D_S2", "BORE RON_S1", "CONE ANGLE",
            "CONE D_S1", "CAV D", "RIM FORM", "SURF E3", "SPH1 D"} <= items
    notes = [a.get("value") for a in root.iterfind(".//q:MeasurementResults/q:Attributes/*",
                                                   NS)]
    assert any(n and n.startswith("BORE TAPER: no QIF characteristic") for n in notes)


def _measurement(root: ET.Element, name: str) -> ET.Element:
    items = {e.findtext("q:Name", namespaces=NS): e.get("id") for e in
             root.iterfind(".//q:CharacteristicItems/*", NS)}
    for m in root.iterfind(".//q:CharacteristicMeasurements/*", NS):
        if m.findtext("q:CharacteristicItemId", namespaces=NS) == items[name]:
            return m
    raise AssertionError(name)


def test_values_carry_their_standard_uncertainty(every_kind: Ingested) -> None:
    root = _doc(ingested_to_qif(every_kind, version="0.0.0"))
    bore = {c.name: c for c in every_kind.revolved[1].characteristics}
    value = _measurement(root, "BORE D").find("q:Value", NS)
    assert value is not None and value.get("meanError") == "0.0000000"
    assert float(value.get("combinedUncertainty", "nan")) == pytest.approx(bore["D"].u,
                                                                           abs=1e-7)
    cyl = root.find(".//q:CylinderFeatureMeasurement/q:Axis/q:AxisPoint", NS)
    assert cyl is not None
    assert float(cyl.get("xCombinedUncertainty", "nan")) == pytest.approx(bore["X"].u,
                                                                          abs=1e-7)
    cone = root.find(".//q:ConeFeatureMeasurement/q:HalfAngle", NS)
    assert cone is not None and float(cone.text or "nan") == pytest.approx(20.0, abs=0.05)
    assert float(cone.get("combinedUncertainty", "nan")) > 0.0


def test_statuses_follow_the_decision_rule(every_kind: Ingested) -> None:
    # E3 deviates 0.030 against ±0.02: FAIL; E2 (-0.004) passes under both rules.  A
    # circle diameter placed within U of its limit passes under simple acceptance and
    # fails under guard banding.
    hole = every_kind.revolved[0]
    d = {c.name: c for c in hole.characteristics}["D"]
    assert d.U is not None
    lower = d.deviation - 0.5 * d.U
    chars = tuple(dataclasses.replace(c, lower=lower, upper=lower + 0.05) if c.name == "D"
                  else c for c in hole.characteristics)
    near = dataclasses.replace(hole, characteristics=chars)
    revolved = (near, *every_kind.revolved[1:])
    for rule, expected in (("simple", "PASS"), ("guard_band", "FAIL")):
        ing = dataclasses.replace(every_kind, revolved=revolved, rule=rule)
        root = _doc(ingested_to_qif(ing, version="0.0.0"))
        status = _measurement(root, "HOLE D").findtext(".//q:CharacteristicStatusEnum",
                                                       namespaces=NS)
        assert status == expected
        assert _measurement(root, "SURF E3").findtext(
            ".//q:CharacteristicStatusEnum", namespaces=NS) == "FAIL"
        assert _measurement(root, "SURF E2").findtext(
            ".//q:CharacteristicStatusEnum", namespaces=NS) == "PASS"


def test_cli_exports_a_revolved_log(in_repo: Path, tmp_path: Path,
                                    capsys: pytest.CaptureFixture[str]) -> None:
    """``probegen qif LOG --spec``: the bore block's bore (cylinder) and boss (circle) from
    a virtual machine run, validated against the schema by the command itself."""
    from probegen import cad
    from probegen.cli.app import main
    from probegen.dialects import get_dialect
    from probegen.machine.probe_model import ProbeModel
    from probegen.planning import plan_program
    from probegen.sim.contact import PlacedPart
    from probegen.sim.vm import VirtualMachine, run_text

    spec = "samples/bore_block/bore_block.toml"
    d = get_dialect("fanuc")
    text = d.generate(plan_program(load_spec(spec), runtime_variables=True).program)
    model = cad.load_step(REPO / "samples/bore_block/bore_block.step")
    vm = VirtualMachine(PlacedPart.from_model(model, translation=np.array([0.3, -0.2, 0.0])),
                        ProbeModel(3.0, noise_sigma=0.001, seed=4))
    log = tmp_path / "run.log"
    log.write_text(run_text(text, vm, kind="macrob").output)
    out = tmp_path / "r.qif"
    assert main(["qif", str(log), "--spec", spec, "-o", str(out), "--validate", "--schema",
                 str(SCHEMA / "QIFDocument.xsd"), "--decision-rule", "guard_band"]) == 0
    assert "valid against the QIF 3 schema" in capsys.readouterr().out
    root = _doc(out.read_text())
    assert root.find(".//q:CylinderFeatureMeasurement/q:Diameter", NS) is not None
    circle = root.find(".//q:CircleFeatureMeasurement/q:Diameter", NS)
    assert circle is not None and float(circle.get("combinedUncertainty", "0")) > 0.0
    notes = [a.get("value") or "" for a in
             root.iterfind(".//q:MeasurementResults/q:Attributes/*", NS)]
    assert any("decision rule guard_band" in n for n in notes)


def test_cli_exports_lines_and_planes(faces_log: Path, tmp_path: Path,  # noqa: F811
                                      capsys: pytest.CaptureFixture[str]) -> None:
    """The lines-and-planes spec on the virtual machine with planted form errors
    (``test_planar_form``): a LineFeatureMeasurement and a PlaneFeatureMeasurement,
    their position as a line and surface profile about the nominal face (TOP's zone
    ``[-0.2, 0.5]`` offset by 0.15), the angle, straightness and flatness with their
    method; schema-valid."""
    from probegen.cli.app import main

    out = tmp_path / "faces.qif"
    spec = faces_spec(tmp_path, "form = 0.02", low=-0.2)
    assert main(["qif", str(bumped(faces_log, tmp_path)), "--spec", str(spec), "-o", str(out),
                 "--validate", "--schema", str(SCHEMA / "QIFDocument.xsd")]) == 0
    assert "valid against the QIF 3 schema" in capsys.readouterr().out
    root = _doc(out.read_text())
    line = root.find(".//q:LineFeatureMeasurement", NS)
    plane = root.find(".//q:PlaneFeatureMeasurement", NS)
    assert line is not None and plane is not None
    assert line.findtext("q:FeatureName", namespaces=NS) == "EDGE"
    assert [float(v) for v in (line.findtext("q:Normal", namespaces=NS) or "").split()] == [
        0.0, -1.0, 0.0]
    assert float(line.findtext("q:Form", namespaces=NS) or "nan") == pytest.approx(0.015,
                                                                                  abs=1e-4)
    assert float(plane.findtext("q:Form", namespaces=NS) or "nan") == pytest.approx(0.03,
                                                                                   abs=1e-4)
    normal = [float(v) for v in (plane.findtext("q:Normal", namespaces=NS) or "").split()]
    assert normal[2] > 0.999

    def value(name: str) -> tuple[float, str]:
        m = _measurement(root, name)
        return (float(m.findtext("q:Value", namespaces=NS) or "nan"),
                m.findtext(".//q:CharacteristicStatusEnum", namespaces=NS) or "")

    # DIST 0.3 + 0.05/4 (one touch of four 50 µm high) in [-0.2, 0.5]: 2·|0.3125 − 0.15|
    top, top_status = value("TOP DIST")
    assert top == pytest.approx(0.325, abs=2e-4) and top_status == "PASS"
    assert value("TOP FORM")[1] == "FAIL" and value("EDGE FORM")[1] == "PASS"
    assert value("EDGE ANGLE")[1] == "PASS"
    kinds = {e.findtext("q:Name", namespaces=NS): e.tag.split("}")[1]
             for e in root.iterfind(".//q:CharacteristicItems/*", NS)}
    assert kinds == {"EDGE DIST": "LineProfileCharacteristicItem",
                     "EDGE ANGLE": "AngleCharacteristicItem",
                     "EDGE FORM": "StraightnessCharacteristicItem",
                     "TOP DIST": "SurfaceProfileCharacteristicItem",
                     "TOP FORM": "FlatnessCharacteristicItem"}
    offsets = [float(e.text or "nan") for e in root.iterfind(".//q:UnequallyDisposedZone", NS)]
    assert offsets == [pytest.approx(0.15)]  # EDGE's [-1, 1] is centred
    methods = [e.text for e in root.iterfind(".//q:SubstituteFeatureAlgorithmEnum", NS)]
    assert methods == ["MINMAX", "MINMAX"]
    status = root.findtext(".//q:InspectionStatus/q:InspectionStatusEnum", namespaces=NS)
    assert status == "FAIL"
