"""QIF 3 export: the sphere test's results and DMIS outputs, validated against the full
QIF 3 schema (keys and keyrefs included), their values, golden files, and rejection of
invalid documents.  The schema (``../shared/ref/qif/schema``) is loaded once."""

from __future__ import annotations

import dataclasses
import doctest
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from datetime import datetime
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, SHARED, assert_golden

import probegen.qif.export
from probegen.errors import ProbegenError
from probegen.evaluate.ingest import Ingested, identified, ingest
from probegen.evaluate.run_identity import IdentityOptions
from probegen.qif.export import (
    SCHEMA_ENV,
    QifValidationError,
    dmis_output_to_qif,
    ingested_to_qif,
    load_schema,
    read_dmis_tolerances,
    validate_qif,
    write_qif,
)
from probegen.results import parse_dmis_output, read_dmis_output
from probegen.spec.model import Spec, SphereTolerance, load_spec

SCHEMA = SHARED / "ref/qif/schema"
GOLDEN = REPO / "tests/golden/qif"
NIST = SHARED / "ref/nist-ippdme"
IMTS_OUTPUT = REPO / "tests/data/dmisvm/imts_output.dmo"
IMTS_PROGRAM = NIST / "DCXpart/DMIS/IMTS_M_clean.dmi"
NS = {"q": "http://qifstandards.org/xsd/qif3"}
GOLDEN_VERSION = "0.0.0"  # goldens name a fixed version: a release does not change them
Ingest = tuple[Ingested, Spec]


@pytest.fixture(scope="module")
def schema() -> Path:
    """The QIF schema folder, loaded (about 5 s) once for the whole module."""
    load_schema(SCHEMA)
    return SCHEMA


def _ingest(tolerance: SphereTolerance | None = None) -> Ingest:
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(REPO)
        spec = load_spec("samples/sphere25/sphere_test.toml")
        if tolerance is not None:
            features = tuple(dataclasses.replace(f, tolerance=tolerance) for f in spec.features)
            spec = dataclasses.replace(spec, features=features)
        return ingest("samples/sphere25/sphere_test.log", spec), spec


@pytest.fixture(scope="module")
def sphere() -> Iterator[Ingest]:
    """The sample log ingested with its spec (no tolerances), from the repository root."""
    yield _ingest()


@pytest.fixture(scope="module")
def toleranced() -> Iterator[Ingest]:
    """The sample ingested with limits: form 0.001 (fails: P_FTU is 0.0016), size 0.004
    (passes) and position 1.0 (fails: the centre is 1.48 mm off nominal)."""
    yield _ingest(SphereTolerance(form=0.001, size=0.004, position=1.0))


def _root(text: str) -> ET.Element:
    return ET.fromstring(text.encode("utf-8"))


def _floats(element: ET.Element | None) -> list[float]:
    assert element is not None and element.text is not None
    return [float(v) for v in element.text.split()]


def _statuses(root: ET.Element) -> dict[str, str]:
    """Characteristic item name -> measured status."""
    names = {i.get("id"): i.findtext("q:Name", namespaces=NS)
             for i in root.findall(".//q:CharacteristicItems/*", NS)}
    return {str(names[m.findtext("q:CharacteristicItemId", namespaces=NS)]):
            str(m.findtext("q:Status/q:CharacteristicStatusEnum", namespaces=NS))
            for m in root.findall(".//q:CharacteristicMeasurements/*", NS)}


# ----------------------------------------------------------------------- the sphere test


def test_sphere_results_validate_against_the_schema(schema: Path, sphere: Ingest) -> None:
    ing, spec = sphere
    validate_qif(ingested_to_qif(ing, spec=spec), schema=schema)
    validate_qif(ingested_to_qif(ing), schema=schema)  # without the spec: probe from the radius


def test_the_run_identity_is_in_the_qif_places(schema: Path, sphere: Ingest) -> None:
    ing, spec = sphere
    spec = dataclasses.replace(spec, part_number="4711-020-A", part_name="Sphere artefact")
    who = IdentityOptions(serial="S0042", operator="A. Smith", batch="LOT 7",
                          time="2026-11-26T13:48:53+01:00")
    text = ingested_to_qif(identified(ing, spec, who), spec=spec)
    validate_qif(text, schema=schema)
    root = _root(text)
    part = root.find(".//q:Product/q:PartSet/q:Part", NS)
    assert part is not None
    assert part.findtext("q:Header/q:Name", namespaces=NS) == "Sphere artefact"
    assert part.findtext("q:ModelNumber", namespaces=NS) == "4711-020-A"
    results = root.find(".//q:MeasurementResults", NS)
    assert results is not None
    trace = results.find("q:InspectionTraceability", NS)
    assert trace is not None
    assert trace.findtext("q:InspectionStart", namespaces=NS) == "2026-11-26T12:48:53Z"
    assert trace.findtext("q:InspectionOperator/q:Name", namespaces=NS) == "A. Smith"
    labels = {a.get("name"): a.get("value") for a in results.findall("q:Attributes/*", NS)}
    assert labels["program"] == "O1001 H2DAFDB55"
    assert labels["machine"] == spec.machine.name
    component = root.find(".//q:ActualComponentSets/q:ActualComponentSet/q:ActualComponent",
                          NS)
    assert component is not None
    assert component.findtext("q:SerialNumber", namespaces=NS) == "S0042"
    assert component.findtext("q:Traceability/q:LotNumber", namespaces=NS) == "LOT 7"
    assert results.findtext("q:ActualComponentIds/q:Id", namespaces=NS) == component.get("id")


def test_sphere_values_equal_the_ingest_results(sphere: Ingest) -> None:
    ing, spec = sphere
    (r,) = ing.results
    root = _root(ingested_to_qif(ing, spec=spec))
    measured = root.find(".//q:MeasuredFeatures/q:SphereFeatureMeasurement", NS)
    assert measured is not None
    assert measured.findtext("q:FeatureName", namespaces=NS) == "SPH1"
    assert np.allclose(_floats(measured.find("q:Location", NS)), r.fit.centre, atol=1e-7)
    assert _floats(measured.find("q:Diameter", NS))[0] == pytest.approx(2 * r.fit.radius, abs=1e-7)
    assert _floats(measured.find("q:Form", NS))[0] == pytest.approx(r.p_ftu, abs=1e-7)
    points = root.find(".//q:MeasuredPointSet", NS)
    assert points is not None and points.get("count") == "25"
    assert np.allclose(np.reshape(_floats(points.find("q:Points", NS)), (-1, 3)), r.points,
                       atol=1e-7)
    assert np.allclose(np.reshape(_floats(points.find("q:Normals", NS)), (-1, 3)),
                       r.directions, atol=1e-7)
    assert points.findtext("q:Compensated", namespaces=NS) == "true"
    assert _floats(points.find("q:ProbeRadius", NS)) == [r.ball_radius]
    tip = root.find(".//q:SimpleTactileProbeSensor/q:TipEndDiameter", NS)
    assert _floats(tip) == [spec.machine.probe.ball_diameter]
    assert _statuses(root) == {"SPH1 D": "UNDEFINED"}  # the sample spec has no limits
    assert root.findtext(".//q:InspectionStatusEnum", namespaces=NS) == "UNDEFINED"


def test_sphere_results_are_golden_and_repeatable(sphere: Ingest) -> None:
    ing, spec = sphere
    text = ingested_to_qif(ing, spec=spec, version=GOLDEN_VERSION)
    assert text == ingested_to_qif(ing, spec=spec, version=GOLDEN_VERSION)
    assert_golden(GOLDEN / "sphere_test.qif", text)
    assert "TimeCreated" not in text and "-0.0000000" not in text
    assert not re.search(r"\d[eE][-+]?\d", text)  # no exponents
    assert f"<Version>{probegen.__version__}</Version>" in ingested_to_qif(ing, spec=spec)


def test_created_and_qpid_are_injected(sphere: Ingest) -> None:
    ing, spec = sphere
    qpid = "0f8fad5b-d9cb-469f-a165-70867728950e"
    text = ingested_to_qif(ing, spec=spec, created=datetime(2024, 5, 1, 8, 30), qpid=qpid)
    assert "<TimeCreated>2024-05-01T08:30:00</TimeCreated>" in text
    assert f"<QPId>{qpid}</QPId>" in text
    with pytest.raises(ProbegenError, match="expected a QPId as a UUID"):
        ingested_to_qif(ing, qpid="not-a-uuid")


def test_toleranced_sphere_has_statuses(schema: Path, toleranced: Ingest) -> None:
    ing, spec = toleranced
    (r,) = ing.results
    text = ingested_to_qif(ing, spec=spec, version=GOLDEN_VERSION)
    validate_qif(text, schema=schema)
    assert_golden(GOLDEN / "sphere_test_toleranced.qif", text)
    root = _root(text)
    expected = {c.name: c.ok for c in r.characteristics}
    assert _statuses(root) == {
        "SPH1 D": "PASS" if expected["D"] else "FAIL",
        "SPH1 P_FTU": "FAIL",  # 0.0016 against 0.001
        "SPH1 POS": "PASS" if expected["POS"] else "FAIL",
    }
    assert root.findtext(".//q:InspectionStatusEnum", namespaces=NS) == "FAIL"
    position = root.find(".//q:PositionCharacteristicMeasurement/q:Value", NS)
    distance = float(np.linalg.norm(np.subtract(r.fit.centre, r.nominal_centre)))
    assert _floats(position)[0] == pytest.approx(2 * distance, abs=1e-7)  # a zone diameter
    zone = root.find(".//q:PositionCharacteristicDefinition/q:ToleranceValue", NS)
    assert _floats(zone) == [1.0]  # the spec's position is the zone diameter
    size = root.find(".//q:SphericalDiameterCharacteristicDefinition/q:Tolerance", NS)
    assert size is not None and _floats(size.find("q:MaxValue", NS)) == [0.004]


# -------------------------------------------------------------------------- DMIS outputs


def test_nist_simple_output_holds_the_circle(schema: Path) -> None:
    export = dmis_output_to_qif(read_dmis_output(NIST / "IPlusSimplePart/DMIS/output.dms"))
    validate_qif(export.text, schema=schema)
    assert export.notes == ()
    circle = _root(export.text).find(".//q:CircleFeatureMeasurement", NS)
    assert circle is not None
    assert circle.findtext("q:FeatureName", namespaces=NS) == "A_CIRCLE"
    assert _floats(circle.find("q:Location", NS)) == [50.0, 50.0, 40.0]
    assert _floats(circle.find("q:Normal", NS)) == [0.0, 0.0, 1.0]
    assert _floats(circle.find("q:Diameter", NS)) == [50.0]


def test_imts_output_with_the_program_tolerances(schema: Path) -> None:
    tolerances = read_dmis_tolerances(IMTS_PROGRAM.read_text(), source=str(IMTS_PROGRAM))
    out = dataclasses.replace(read_dmis_output(IMTS_OUTPUT), source="imts_output.dmo")
    export = dmis_output_to_qif(out,
                                tolerances=tolerances, version=GOLDEN_VERSION)
    validate_qif(export.text, schema=schema)
    assert export.notes == ()
    assert_golden(GOLDEN / "imts_output.qif", export.text)
    root = _root(export.text)
    kinds = [m.tag.split("}")[1] for m in root.findall(".//q:MeasuredFeatures/*", NS)]
    assert kinds == ["PlaneFeatureMeasurement"] * 3 + [
        "LineFeatureMeasurement", "PointFeatureMeasurement"] + ["CylinderFeatureMeasurement"] * 2
    assert _statuses(root) == {f"TOL{k}": "PASS" for k in range(1, 8)}
    chars = [m.tag.split("}")[1].removesuffix("CharacteristicMeasurement")
             for m in root.findall(".//q:CharacteristicMeasurements/*", NS)]
    assert chars == ["Flatness", "Position", "Position", "Diameter", "Cylindricity",
                     "Position", "Diameter"]
    shapes = [z.tag.split("}")[1] for z in root.findall(".//q:ZoneShape/*", NS)]
    assert shapes == ["SphericalZone", "DiametricalZone", "DiametricalZone"]  # 3D, 2D, 2D
    target = root.find(".//q:DiameterCharacteristicNominal/q:TargetValue", NS)
    assert _floats(target) == [31.0]  # actual 31.0 minus the deviation 0.0


def test_imts_output_without_tolerances_names_what_is_left_out(schema: Path) -> None:
    export = dmis_output_to_qif(read_dmis_output(IMTS_OUTPUT))
    validate_qif(export.text, schema=schema)
    assert len(export.notes) == 7
    assert export.notes[0].startswith("TA(TOL1)=TOL/FLAT (line 8): the limits of T(TOL1) "
                                      "are unknown")
    root = _root(export.text)
    notes = root.findall(".//q:MeasurementResults/q:Attributes/q:AttributeStr", NS)
    assert [n.get("value") for n in notes] == list(export.notes)  # kept in the document
    assert root.find("q:Characteristics", NS) is None
    assert len(root.findall(".//q:MeasuredFeatures/*", NS)) == 7
    assert root.findtext(".//q:InspectionStatusEnum", namespaces=NS) == "PASS"


EVERY_TYPE = """\
UNITS/MM, ANGDEC
TA(EARLY) = TOL/DIAM, 0.01, INTOL
MEAS/CIRCLE, F(C1), 3
PTMEAS/CART, 5, 0, 0, 1, 0, 0
PTMEAS/CART, -2.5, 4.33013, 0, -0.5, 0.86603, 0
PTMEAS/CART, -2.5, -4.33013, 0, -0.5, -0.86603, 0
ENDMES
FA(C1) = FEAT/CIRCLE, OUTER, CART, 0, 0, 0, 0, 0, 1, 10.02
TA(D1) = TOL/DIAM, 0.02, OUTOL
TA(F1) = TOL/FLAT, 0.0, INTOL
FA(S1) = FEAT/SPHERE, OUTER, CART, 1, 2, 3, 25.001
TA(D2) = TOL/DIAM, 0.001, INTOL
TA(P1) = TOL/POS, 3D, 0.004, INTOL
FA(K1) = FEAT/CONE, INNER, CART, 0, 0, 10, 0, 0, -1, 60
FA(L1) = FEAT/LINE, BND, CART, 0, 0, 0, 10, 0, 0
FA(PT1) = FEAT/POINT, CART, 1, 1, 1
TA(PAR) = TOL/PARLEL, 0.01, INTOL
FA(CY1) = FEAT/CYLNDR, INNER, CART, 0, 0, 0, 0, 0, 1, 8
TA(CC1) = TOL/CYLCTY, 0.002, INTOL
FA(T1) = FEAT/TORUS, OUTER, CART, 0, 0, 1, 0, 0, 1, 1.5, 0.25
TA(D3) = TOL/DIAM, 0.001, INTOL
"""
EVERY_TOLERANCE = """\
UNITS/INCH
T(EARLY) = TOL/DIAM, -0.001, 0.001
T(D1) = TOL/DIAM, -0.0004, 0.0004
T(F1) = TOL/FLAT, 0.001
T(D2) = TOL/DIAM, -0.0001, 0.0001
T(P1) = TOL/POS, 3D, 0.0002, MMC
T(CC1) = TOL/CIRLTY, 0.001
T(D3) = TOL/DIAM, -0.002, 0.002
"""


def test_every_feature_type_and_the_notes(schema: Path) -> None:
    tolerances = read_dmis_tolerances(EVERY_TOLERANCE)
    assert tolerances["D1"].lower == pytest.approx(-0.01016)  # inch -> mm
    assert tolerances["P1"].material == "MMC" and tolerances["P1"].mode == "3D"
    out = parse_dmis_output(EVERY_TYPE, source="every.dmo")
    export = dmis_output_to_qif(out, tolerances=tolerances)
    validate_qif(export.text, schema=schema)
    assert [n.split(":")[0] for n in export.notes] == [
        "TA(EARLY)=TOL/DIAM (line 2)", "TA(F1)=TOL/FLAT (line 10)",
        "TA(PAR)=TOL/PARLEL (line 17)", "TA(CC1)=TOL/CYLCTY (line 19)",
        "TA(D3)=TOL/DIAM (line 21)"]
    assert "applies to a PLANE, the feature before it is the CIRCLE C1" in export.notes[1]
    assert "defines a CIRLTY tolerance, not CYLCTY" in export.notes[3]
    root = _root(export.text)
    kinds = [m.tag.split("}")[1] for m in root.findall(".//q:MeasuredFeatures/*", NS)]
    assert kinds == ["CircleFeatureMeasurement", "SphereFeatureMeasurement",
                     "ConeFeatureMeasurement", "LineFeatureMeasurement",
                     "PointFeatureMeasurement", "CylinderFeatureMeasurement",
                     "TorusFeatureMeasurement"]
    assert _statuses(root) == {"D1": "FAIL", "D2": "PASS", "P1": "PASS"}
    assert root.findtext(".//q:InspectionStatusEnum", namespaces=NS) == "FAIL"
    assert root.find(".//q:SphericalDiameterCharacteristicMeasurement", NS) is not None
    assert root.findtext(".//q:MaterialCondition", namespaces=NS) == "MAXIMUM"
    points = root.find(".//q:MeasuredPointSet", NS)
    assert points is not None and points.get("count") == "3"
    line = root.find(".//q:LineFeatureMeasurement", NS)
    assert line is not None and _floats(line.find("q:Length", NS)) == [10.0]
    cone = root.find(".//q:ConeFeatureMeasurement/q:FullAngle", NS)
    assert _floats(cone) == [60.0]
    torus = root.find(".//q:TorusFeatureMeasurement", NS)
    assert torus is not None
    assert [child.tag.split("}")[1] for child in torus][-4:] == [
        "Location", "AxisVector", "MinorDiameter", "MajorDiameter"]
    assert _floats(torus.find("q:MinorDiameter", NS)) == [0.25]
    assert _floats(torus.find("q:MajorDiameter", NS)) == [1.5]


# ----------------------------------------------------------------------------- validation


def _sphere_text(sphere: Ingest) -> str:
    ing, spec = sphere
    return ingested_to_qif(ing, spec=spec)


@pytest.mark.parametrize(("old", "new", "expected"), [
    ("<FeatureItemId>9</FeatureItemId>", "<FeatureItemId>99</FeatureItemId>",
     r"value 99 not found for key FeatureItemIdKey \(at /QIFDocument/Results/"
     r"MeasurementResultsSet/MeasurementResults/MeasuredFeatures/SphereFeatureMeasurement/"
     r"FeatureItemId\)"),
    ('<SphereFeatureItem id="9">', '<SphereFeatureItem id="8">',
     r"duplicated value 8 for QIFIdUnique \(at /QIFDocument/Features/FeatureItems/"
     r"SphereFeatureItem\)"),
    ("<CharacteristicNominalId>13</", "<CharacteristicNominalId>12</",
     r"value 12 not found for key .*CharacteristicNominal"),
    ("<WholePointSetId>10</", "<WholePointSetId>11</",
     r"WholePointSetId 11 names no MeasuredPointSet of these results"),
    (">24.9991907</Diameter>", ">big</Diameter>",
     r"invalid value 'big' for xs:decimal \(at .*SphereFeatureMeasurement/Diameter\)"),
    ('idMax="15"', 'idMax="14"', r"id 15 exceeds the document's idMax 14 \(at "
     r"/QIFDocument/Results/.*/SphericalDiameterCharacteristicMeasurement\)"),
])
def test_invalid_documents_are_rejected(schema: Path, sphere: Ingest, old: str, new: str,
                                        expected: str) -> None:
    text = _sphere_text(sphere)
    assert text.count(old) == 1
    bad = text.replace(old, new)
    with pytest.raises(QifValidationError, match=expected) as caught:
        validate_qif(bad, schema=schema, source="bad.qif")
    message = str(caught.value)
    at = 'id="15"' if new.startswith("idMax") else new  # where each problem is reported
    line = next(k for k, x in enumerate(bad.splitlines(), start=1) if at in x)
    assert re.search(rf"^bad\.qif:{line}:\d+: ", message, re.MULTILINE), message
    assert caught.value.diagnostics


def test_a_document_that_is_not_xml_is_rejected(schema: Path) -> None:
    with pytest.raises(QifValidationError, match=r"x\.qif:2:\d+: not well-formed XML"):
        validate_qif("<QIFDocument>\n<a></b>\n", schema=schema, source="x.qif")


def test_the_qif_samples_validate_once_substitution_groups_are_indexed(schema: Path) -> None:
    # Plain xmlschema reports every FeatureItemId of this sample as dangling.
    validate_qif((SHARED / "ref/qif/QIF_Results_Sample.QIF").read_text(), schema=schema)
    sample = SHARED / "ref/qif/QIF_PTS_SAMPLE.QIF"
    with pytest.raises(QifValidationError, match="WholePointSetId 828 names no MeasuredPointSet"):
        validate_qif(sample.read_text(), schema=schema, source=sample.name)


def test_the_schema_path_comes_from_the_argument_or_the_environment(
        schema: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(SCHEMA_ENV, raising=False)
    needed = f"pass the path of QIFDocument.xsd .* set {SCHEMA_ENV}"
    with pytest.raises(ProbegenError, match=needed):
        validate_qif("<x/>")
    with pytest.raises(ProbegenError, match="expected QIFDocument.xsd at .*nowhere"):
        validate_qif("<x/>", schema="nowhere")
    monkeypatch.setenv(SCHEMA_ENV, str(schema / "QIFDocument.xsd"))
    with pytest.raises(QifValidationError, match="problem"):
        validate_qif("<x/>")


def test_write_qif_validates_before_writing(schema: Path, sphere: Ingest, tmp_path: Path) -> None:
    text = _sphere_text(sphere)
    target = write_qif(tmp_path / "out" / "results.qif", text, schema=schema, validate=True)
    assert target.read_bytes() == text.encode("utf-8")
    bad = tmp_path / "bad.qif"
    with pytest.raises(QifValidationError):
        write_qif(bad, text.replace("<FeatureItemId>9<", "<FeatureItemId>99<"), schema=schema,
                  validate=True)
    assert not bad.exists()


def test_importing_the_exporter_is_light() -> None:
    code = ("import sys, probegen.qif.export; "
            "print(sorted(m for m in ('xmlschema', 'numpy', 'probegen.evaluate.ingest', 'lark') "
            "if m in sys.modules))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True, cwd=REPO)
    assert result.stdout.strip() == "[]"


def test_module_example() -> None:
    assert doctest.testmod(probegen.qif.export).failed == 0
