"""The QIF 3 document builder shared by the exporters (see ``docs/qif.md``).

:class:`QifBuilder` hands out the numeric QIF ids (``id="1"``, ``<Id>1</Id>``), collects
the elements of each list (feature definitions, nominals, items; characteristic
definitions, nominals, items; measured features, point sets, characteristic
measurements) and assembles them in the order ``QIFDocumentType`` prescribes, with every
list's ``n`` attribute and the document's ``idMax``.

The text is byte-for-byte repeatable: elements and attributes in a fixed order, numbers
with :data:`DECIMALS` fixed decimals (never ``-0.0000000``, never an exponent), two-space
indentation, ``\\n`` line ends, no time stamp unless one is passed.  The required
``QPId`` (a UUID) is derived from the rest of the document (a name-based UUID of its
SHA-256), so the same results give the same file and different results a different id.
"""

from __future__ import annotations

import hashlib
import math
import re
import uuid
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from urllib.parse import quote

from probegen.errors import ProbegenError
from probegen.evaluate.run_identity import RunIdentity

NAMESPACE = "http://qifstandards.org/xsd/qif3"
"""The QIF 3 target namespace (the default namespace of every document written)."""

QIF_VERSION = "3.0.0"
"""The ``versionQIF`` written: the schema set in ``../shared/ref/qif/schema``."""

DECIMALS = 7
"""Decimals of every number written (0.1 nm in mm; the ingest JSON rounds the same way)."""

INDENT = "  "
"""One level of indentation."""

_PLACEHOLDER = "00000000-0000-0000-0000-000000000000"
_UUID_NAMESPACE = uuid.UUID("5f0b3c9e-6a41-4f57-9a53-6b2b2f0f1a51")
_QPID = re.compile(r"^[0-9A-Fa-f]{8}-[0-9A-Fa-f]{4}-[0-9A-Fa-f]{4}-[0-9A-Fa-f]{4}-[0-9A-Fa-f]{12}$")

Vec3 = tuple[float, float, float]


def num(value: float) -> str:
    """Format a number with :data:`DECIMALS` fixed decimals, never ``-0.0000000``.

    Raises:
        ProbegenError: the value is not finite (QIF decimals have no NaN or infinity).
    """
    if not math.isfinite(value):
        raise ProbegenError(f"QIF export: expected a finite number, found {value}")
    text = f"{value:.{DECIMALS}f}"
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text


def vec(values: Iterable[float]) -> str:
    """Format a point or vector as ``"x y z"``."""
    return " ".join(num(v) for v in values)


def sub(parent: ET.Element, tag: str, text: str | None = None, **attrs: str) -> ET.Element:
    """Append a child element (attributes in the order given) and return it."""
    child = ET.SubElement(parent, tag, attrs)
    if text is not None:
        child.text = text
    return child


def ref_list(parent: ET.Element, tag: str, ids: Sequence[int]) -> ET.Element:
    """Append an id array ``<tag n="k"><Id>..</Id>...</tag>``."""
    array = sub(parent, tag, n=str(len(ids)))
    for ident in ids:
        sub(array, "Id", str(ident))
    return array


def point_lines(points: Sequence[Sequence[float]], depth: int) -> str:
    """The text of a ``Points``/``Normals`` list: one triple per line at ``depth``."""
    pad = "\n" + INDENT * (depth + 1)
    return pad + pad.join(vec(p) for p in points) + "\n" + INDENT * depth


def attributes(parent: ET.Element, values: Sequence[tuple[str, float]]) -> None:
    """Append ``<Attributes>`` with one ``AttributeD1`` (name, number) per value."""
    if values:
        group = sub(parent, "Attributes", n=str(len(values)))
        for name, value in values:
            sub(group, "AttributeD1", name=name, value=num(value))


def check_qpid(qpid: str) -> str:
    """Return ``qpid`` if it is a UUID as QIF writes them.

    Raises:
        ProbegenError: it is not ``8-4-4-4-12`` hexadecimal digits.
    """
    if not _QPID.match(qpid):
        raise ProbegenError(f"QIF export: expected a QPId as a UUID "
                            f"(8-4-4-4-12 hex digits), found {qpid!r}")
    return qpid.lower()


@dataclass(slots=True)
class QifBuilder:
    """One QIF document under construction.

    Attributes:
        application: ``Header/Application/Name``.
        version: the software version written in ``SoftwareDefinitions``.
        created: ``Version/TimeCreated``, or None for none (repeatable output).
        qpid: the document's QPId, or None to derive it from the content.
        software_id: id of the ``Software`` entry (set by :func:`begin_document`).
        standard_id: id of the formal ``Standard`` of the characteristics.
        results_id: id of the ``MeasurementResults``.
        lists: the members of each id-bearing list, by list name.
        singles: the sections built whole by a converter (``Product`` ...).
        statuses: every verdict (PASS/FAIL/UNDEFINED/NOT_ANALYZED) behind
            ``InspectionStatus``.
        notes: written as ``MeasurementResults/Attributes`` (``AttributeStr`` "note k").
        run: the run's identity (:meth:`identify`), or None.
        component_id: id of the ``ActualComponent`` (the part measured), 0 without ``run``.
    """

    application: str
    version: str
    created: datetime | None = None
    qpid: str | None = None
    software_id: int = 0
    standard_id: int = 0
    results_id: int = 0
    _next: int = 1
    lists: dict[str, list[ET.Element]] = field(default_factory=dict)
    singles: dict[str, ET.Element] = field(default_factory=dict)
    statuses: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    run: RunIdentity | None = None
    component_id: int = 0

    def identify(self, run: RunIdentity | None) -> None:
        """Write the run's identity (:func:`_traceability`); nothing when None."""
        if run is not None:
            self.run, self.component_id = run, self.new_id()

    def new_id(self) -> int:
        """Return the next free QIF id."""
        ident, self._next = self._next, self._next + 1
        return ident

    def add(self, group: str, tag: str) -> tuple[ET.Element, int]:
        """Create a list member ``<tag id="k">`` of ``group``; return it and its id."""
        ident = self.new_id()
        element = ET.Element(tag, {"id": str(ident)})
        self.lists.setdefault(group, []).append(element)
        return element, ident

    def has(self, group: str) -> bool:
        """True when ``group`` has members."""
        return bool(self.lists.get(group))

    def single(self, name: str, element: ET.Element) -> ET.Element:
        """Keep a top-level section (``Product``, ``MeasurementResources`` ...)."""
        self.singles[name] = element
        return element

    def to_text(self) -> str:
        """Assemble and serialise the document (see the module docstring)."""
        root = ET.Element("QIFDocument", {"xmlns": NAMESPACE, "versionQIF": QIF_VERSION,
                                          "idMax": str(self._next - 1)})
        sub(root, "QPId", _PLACEHOLDER)
        for part in _sections(self):
            root.append(part)
        ET.indent(root, space=INDENT)
        text = ('<?xml version="1.0" encoding="UTF-8"?>\n'
                + ET.tostring(root, encoding="unicode") + "\n")
        digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
        qpid = self.qpid or str(uuid.uuid5(_UUID_NAMESPACE, digest))
        return text.replace(_PLACEHOLDER, check_qpid(qpid), 1)


def _sections(b: QifBuilder) -> list[ET.Element]:
    """The top-level sections in ``QIFDocumentType`` order."""
    out: list[ET.Element] = []
    if b.created is not None:
        version = ET.Element("Version")
        sub(version, "TimeCreated", b.created.isoformat(timespec="seconds"))
        out.append(version)
    out += [_header(b), *_wrapped(b, "StandardsDefinitions", "standards"),
            _software(b), _file_units()]
    out += [b.singles[k] for k in ("MeasurementResources", "Product") if k in b.singles]
    out += _group(b, "Features", ("FeatureDefinitions", "FeatureNominals", "FeatureItems"))
    if b.has("CharacteristicDefinitions"):
        out.append(_characteristics(b))
    out.append(_results(b))
    return out


def _wrapped(b: QifBuilder, tag: str, group: str) -> list[ET.Element]:
    """``<tag n="k">`` around the members of ``group`` (nothing when empty)."""
    members = b.lists.get(group, [])
    if not members:
        return []
    wrapper = ET.Element(tag, {"n": str(len(members))})
    wrapper.extend(members)
    return [wrapper]


def _group(b: QifBuilder, tag: str, groups: tuple[str, ...]) -> list[ET.Element]:
    """A section holding the non-empty lists ``groups`` (nothing when all are empty)."""
    parts = [w for g in groups for w in _wrapped(b, g, g)]
    if not parts:
        return []
    section = ET.Element(tag)
    section.extend(parts)
    return [section]


def _header(b: QifBuilder) -> ET.Element:
    header = ET.Element("Header")
    application = sub(header, "Application")
    sub(application, "Name", b.application)
    sub(application, "Organization", "the probegen project")
    return header


def _software(b: QifBuilder) -> ET.Element:
    software = ET.Element("SoftwareDefinitions", n="1")
    entry = sub(software, "Software", id=str(b.software_id))
    sub(entry, "VendorName", "the probegen project")
    sub(entry, "ApplicationName", b.application)
    sub(entry, "Version", b.version)
    return software


def _file_units() -> ET.Element:
    units = ET.Element("FileUnits")
    primary = sub(units, "PrimaryUnits")
    for tag, si, name, factor in (("AngularUnit", "radian", "degree", "0.017453292519943295"),
                                  ("LinearUnit", "meter", "mm", "0.001")):
        unit = sub(primary, tag)
        sub(unit, "SIUnitName", si)
        sub(unit, "UnitName", name)
        sub(sub(unit, "UnitConversion"), "Factor", factor)
    return units


def _characteristics(b: QifBuilder) -> ET.Element:
    section = ET.Element("Characteristics")
    sub(section, "FormalStandardId", str(b.standard_id))
    for group in ("CharacteristicDefinitions", "CharacteristicNominals", "CharacteristicItems"):
        section.extend(_wrapped(b, group, group))
    return section


def _results(b: QifBuilder) -> ET.Element:
    results = ET.Element("Results")
    results_set = sub(results, "MeasurementResultsSet", n="1")
    measured = sub(results_set, "MeasurementResults", id=str(b.results_id))
    labels = _run_labels(b.run) + [(f"note {k}", note)
                                   for k, note in enumerate(b.notes, start=1)]
    if labels:
        group = sub(measured, "Attributes", n=str(len(labels)))
        for name, value in labels:
            sub(group, "AttributeStr", name=name, value=value)
    if b.run is not None:
        measured.append(_traceability(b.run))
    if "ExternalFileReferences" in b.singles:
        measured.append(b.singles["ExternalFileReferences"])
    measured.extend(_wrapped(b, "MeasuredFeatures", "MeasuredFeatures"))
    measured.extend(_wrapped(b, "MeasuredPointSets", "MeasuredPointSets"))
    if b.has("CharacteristicMeasurements"):
        chars = sub(measured, "MeasuredCharacteristics")
        chars.extend(_wrapped(b, "CharacteristicMeasurements", "CharacteristicMeasurements"))
    status = sub(measured, "InspectionStatus")
    sub(status, "InspectionStatusEnum", inspection_status(b.statuses))
    if b.run is not None:
        ref_list(measured, "ActualComponentIds", [b.component_id])
        results.append(_component(b, b.run))
    return results


def _run_labels(run: RunIdentity | None) -> list[tuple[str, str]]:
    """``MeasurementResults/Attributes`` of the run: the program (number and identity
    token as the log printed them) and the machine, which QIF has no element for."""
    if run is None:
        return []
    return [(name, value) for name, value in (("program", run.program),
                                              ("machine", run.machine)) if value]


def _utc(time: str) -> str:
    """An ISO 8601 time as QIF's ``xs:dateTime`` in UTC (QIF asks for GMT, not local)."""
    return datetime.fromisoformat(time).astimezone(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def _traceability(run: RunIdentity) -> ET.Element:
    """``MeasurementResults/InspectionTraceability``: when, and who measured."""
    trace = ET.Element("InspectionTraceability")
    sub(trace, "InspectionStart", _utc(run.time))
    if run.operator:
        sub(sub(trace, "InspectionOperator"), "Name", run.operator)
    return trace


def _component(b: QifBuilder, run: RunIdentity) -> ET.Element:
    """``Results/ActualComponentSets``: the part measured, its serial number and batch
    (``LotNumber``) and the inspection's status."""
    sets = ET.Element("ActualComponentSets", n="1")
    component = sub(sub(sets, "ActualComponentSet", n="1"), "ActualComponent",
                    id=str(b.component_id))
    if run.serial:
        sub(component, "SerialNumber", run.serial)
    sub(sub(component, "Status"), "InspectionStatusEnum", inspection_status(b.statuses))
    trace = sub(component, "Traceability")
    if run.batch:
        sub(trace, "LotNumber", run.batch)
    sub(trace, "InspectionStart", _utc(run.time))
    return sets


def inspection_status(statuses: Sequence[str]) -> str:
    """The document's verdict: FAIL if any FAIL; NOT_MEASURED if any NOT_ANALYZED (a
    characteristic, a feature or the run not evaluated completely: never PASS); PASS if
    any PASS; else UNDEFINED."""
    if "FAIL" in statuses:
        return "FAIL"
    if "NOT_ANALYZED" in statuses:
        return "NOT_MEASURED"
    return "PASS" if "PASS" in statuses else "UNDEFINED"


def begin_document(b: QifBuilder, *, standard: tuple[str, str, str], source: str,
                   source_kind: str) -> None:
    """Allocate the document-level ids and write the standard and source reference.

    Args:
        b: the builder.
        standard: (organisation enum, designator, title) of the formal standard the
            characteristics follow.
        source: the file the results were read from.
        source_kind: what that file is (``DPRNT log``, ``DMIS output``).
    """
    b.software_id = b.new_id()
    element, b.standard_id = b.add("standards", "Standard")
    sub(sub(element, "Organization"), "StandardsOrganizationEnum", standard[0])
    sub(element, "Designator", standard[1])
    sub(element, "Title", standard[2])
    b.results_id = b.new_id()
    refs = ET.Element("ExternalFileReferences", n="1")
    ref = sub(refs, "ExternalFileReference")
    sub(ref, "URI", _uri(source))
    sub(sub(ref, "FileSpec"), "OtherFileSpec", source_kind)
    sub(ref, "Description", f"the {source_kind} these results were read from")
    b.single("ExternalFileReferences", refs)


def _uri(path: str) -> str:
    """A relative URI reference for a file name (backslashes to slashes, blanks escaped)."""
    return quote(path.replace("\\", "/"), safe="/:._-~")
