"""Validate QIF text against the QIF 3 XSD set, keys and keyrefs included.

The schema is not shipped with probegen: :func:`validate_qif` takes its path (the
``QIFDocument.xsd`` file or the folder holding it), else the environment variable
``PROBEGEN_QIF_SCHEMA``.  Loading the set takes about 5 s, so each loaded schema is kept
for the life of the process.  Loading never touches the network: the XML-signature
schema QIF imports from w3.org is taken from xmlschema's bundled copy.

xmlschema (4.3) misses the members of a substitution group when an identity
constraint's selector ends in a wildcard: ``t:Features/t:FeatureItems/t:*`` collects
no ``SphereFeatureItem`` (only the abstract head ``FeatureItem`` is indexed), so every
``FeatureItemId`` reference is reported as dangling (the "FeatureItemIdKey" errors of
the QIF sample files) while duplicate ids among such members go unnoticed.
:func:`load_schema` indexes every member under the constraints of its head, after which
the samples validate and a dangling or duplicate id is caught.

Two checks the XSD set does not make are added: every point-set reference in a measured
feature's ``PointList`` names a ``MeasuredPointSet`` of the same results, and no ``id``
exceeds the document's ``idMax``.
"""

from __future__ import annotations

import functools
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any
from xml.parsers import expat

from probegen.errors import Diagnostic, ProbegenError

if TYPE_CHECKING:
    import xmlschema

SCHEMA_ENV = "PROBEGEN_QIF_SCHEMA"
"""Environment variable naming the QIF schema (``QIFDocument.xsd`` or its folder)."""

SHOWN = 10
"""Problems spelled out in a validation error's message."""

_NS = "{http://qifstandards.org/xsd/qif3}"
_VALUE = re.compile(r"\(Decimal\('(\d+)'\),\)")
_KEY = re.compile(r"Xsd(Key|Unique|Keyref)\(name='t:(\w+)'\)")
_POINT_SET_REFS = ("WholePointSetId", "RangePointSetId", "SinglePointSetId")


class QifValidationError(ProbegenError):
    """QIF text that is not well-formed or not valid; one diagnostic per problem."""

    def __init__(self, message: str, diagnostics: tuple[Diagnostic, ...] = ()) -> None:
        super().__init__(message)
        self.diagnostics = diagnostics


def schema_path(schema: str | os.PathLike[str] | None = None) -> Path:
    """Resolve the schema argument (else ``$PROBEGEN_QIF_SCHEMA``) to ``QIFDocument.xsd``.

    Raises:
        ProbegenError: neither is given, or the file does not exist.
    """
    given = schema if schema is not None else os.environ.get(SCHEMA_ENV) or None
    if given is None:
        raise ProbegenError(
            "QIF validation needs the QIF 3 schema: pass the path of QIFDocument.xsd (or its "
            f"folder), or set {SCHEMA_ENV}; the schema set is not shipped with probegen")
    path = Path(given)
    if path.is_dir():
        path = path / "QIFDocument.xsd"
    if not path.is_file():
        raise ProbegenError(f"QIF schema: expected QIFDocument.xsd at {path}, found no file")
    return path.resolve()


def load_schema(schema: str | os.PathLike[str] | None = None) -> xmlschema.XMLSchema:
    """Load (once per process) and return the QIF schema, substitution groups indexed.

    Raises:
        ProbegenError: no schema path, a missing file, or a schema that does not load.
    """
    return _load(str(schema_path(schema)))


@functools.lru_cache(maxsize=4)
def _load(path: str) -> xmlschema.XMLSchema:
    import xmlschema

    try:
        schema = xmlschema.XMLSchema(path, allow="local")
    except (xmlschema.XMLSchemaException, OSError) as exc:
        raise ProbegenError(f"QIF schema {path}: cannot be loaded: {exc}") from exc
    _index_substitutes(schema)
    return schema


def _index_substitutes(schema: xmlschema.XMLSchema) -> None:
    """Let every identity constraint that selects a substitution-group head also select
    the group's members (see the module docstring)."""
    try:
        from xmlschema.validators.identities import FieldValueSelector

        groups = schema.maps.substitution_groups
        for identity in list(schema.maps.identities.values()):
            for head in list(identity.elements):
                for member in _members(groups, head, set()):
                    if member not in identity.elements:
                        identity.elements[member] = [FieldValueSelector(f, member)
                                                     for f in identity.fields]
                        member.selected_by.add(identity)
    except (ImportError, AttributeError, TypeError) as exc:
        import xmlschema

        raise ProbegenError(
            f"QIF validation: xmlschema {xmlschema.__version__} is not supported "
            f"(cannot index substitution groups for keys: {exc}); use xmlschema 4.x") from exc


def _members(groups: Any, head: Any, seen: set[Any]) -> Iterator[Any]:
    """Every element that may stand for ``head``, directly or through another member."""
    for member in groups.get(head.name, ()):
        if member not in seen:
            seen.add(member)
            yield member
            yield from _members(groups, member, seen)


def validate_qif(text: str, *, schema: str | os.PathLike[str] | None = None,
                 source: str = "<qif>") -> None:
    """Check QIF text against the QIF 3 schema (structure, types, keys, keyrefs).

    Args:
        text: the document.
        schema: ``QIFDocument.xsd`` or its folder; default ``$PROBEGEN_QIF_SCHEMA``.
        source: the name used in messages.

    Raises:
        ProbegenError: no schema is given or it cannot be loaded.
        QifValidationError: the text is not well-formed or not valid; the message gives
            each problem's line, element path and the schema's reason.
    """
    xsd = load_schema(schema)
    root, lines = _parse(text, source)
    problems = [_diagnostic(source, text, root, lines, e) for e in xsd.iter_errors(root)]
    problems += [_at(source, text, root, lines, elem, message)
                 for elem, message in _extra_checks(root)]
    if problems:
        count = len(problems)
        head = f"{source}: {count} problem{'s' if count > 1 else ''} against the QIF 3 schema"
        shown = [str(d) for d in problems[:SHOWN]]
        more = [f"... and {count - SHOWN} more"] if count > SHOWN else []
        raise QifValidationError("\n".join([head, *shown, *more]), tuple(problems))


def _parse(text: str, source: str) -> tuple[ET.Element, dict[int, tuple[int, int]]]:
    """Parse with expat, recording each element's (line, column)."""
    builder = ET.TreeBuilder()
    lines: dict[int, tuple[int, int]] = {}
    parser = expat.ParserCreate(namespace_separator="}")

    def qname(name: str) -> str:
        return "{" + name if "}" in name else name

    def start(name: str, attrs: dict[str, str]) -> None:
        element = builder.start(qname(name), {qname(k): v for k, v in attrs.items()})
        lines[id(element)] = (parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda name: builder.end(qname(name))
    parser.CharacterDataHandler = builder.data
    try:
        parser.Parse(text.encode("utf-8"), True)
    except expat.ExpatError as exc:
        line = text.splitlines()[exc.lineno - 1] if exc.lineno <= len(text.splitlines()) else ""
        diagnostic = Diagnostic(source, exc.lineno, exc.offset + 1,
                                f"not well-formed XML: {expat.ErrorString(exc.code)}", line)
        raise QifValidationError(f"{source}: not a QIF document\n{diagnostic}",
                                 (diagnostic,)) from exc
    return builder.close(), lines


def _diagnostic(source: str, text: str, root: ET.Element, lines: dict[int, tuple[int, int]],
                error: Any) -> Diagnostic:
    """A schema error as a diagnostic at its element (for a key error: at the id)."""
    reason = str(error.reason or error.message)
    elem = getattr(error, "elem", None)
    value, key = _VALUE.search(reason), _KEY.search(reason)
    if elem is root and value and key:
        culprit = _culprit(root, value.group(1), key.group(2), duplicate="duplicated" in reason)
        elem = culprit if culprit is not None else elem
    return _at(source, text, root, lines, elem, _plain(reason))


def _culprit(root: ET.Element, value: str, key: str, *, duplicate: bool) -> ET.Element | None:
    """The element behind a key error on ``value``: the second ``id=value`` (duplicate),
    else the first reference to it whose name fits the key (``FeatureItemId`` or
    ``FeatureItemIds/Id`` for ``FeatureItemIdKey`` and ``SphereFeatureItemKey``)."""
    if duplicate:
        found = [e for e in root.iter() if e.get("id") == value]
        return found[1] if len(found) > 1 else None
    stem = key.removesuffix("Key").removesuffix("Id")
    parents = {id(c): p for p in root.iter() for c in p}
    refs = [e for e in root.iter()
            if e.tag.endswith("Id") and (e.text or "").strip() == value]
    for ref in refs:
        name = ref.tag.removeprefix(_NS)
        if name == "Id" and id(ref) in parents:
            name = parents[id(ref)].tag.removeprefix(_NS).removesuffix("s")
        if stem.endswith(name.removesuffix("Id")):
            return ref
    return refs[0] if refs else None


def _plain(reason: str) -> str:
    """The schema's reason without Python reprs: ``value 3 not found for key X``."""
    reason = _VALUE.sub(lambda m: m.group(1), reason)
    return _KEY.sub(lambda m: ("key " if m.group(1) == "Key" else "") + m.group(2), reason)


def _at(source: str, text: str, root: ET.Element, lines: dict[int, tuple[int, int]],
        elem: ET.Element | None, message: str) -> Diagnostic:
    """A diagnostic at ``elem``: its line, column and path."""
    if elem is None or id(elem) not in lines:
        return Diagnostic(source, 0, 0, message)
    line, column = lines[id(elem)]
    physical = text.splitlines()[line - 1] if line <= len(text.splitlines()) else ""
    return Diagnostic(source, line, column, f"{message} (at {_path(root, elem)})", physical)


def _path(root: ET.Element, target: ET.Element) -> str:
    """``/QIFDocument/Features/FeatureItems/SphereFeatureItem[2]``: indices where needed."""
    parents = {id(c): p for p in root.iter() for c in p}
    steps: list[str] = []
    node: ET.Element | None = target
    while node is not None:
        parent = parents.get(id(node))
        step = node.tag.removeprefix(_NS)
        if parent is not None:
            same = [c for c in parent if c.tag == node.tag]
            step += f"[{same.index(node) + 1}]" if len(same) > 1 else ""
        steps.append(step)
        node = parent
    return "/" + "/".join(reversed(steps))


def _extra_checks(root: ET.Element) -> Iterator[tuple[ET.Element, str]]:
    """The checks the XSD set does not make (see the module docstring)."""
    raw = root.get("idMax", "").strip()
    for element in root.iter() if raw.isdigit() else ():
        ident = element.get("id", "").strip()
        if ident.isdigit() and int(ident) > int(raw):
            yield element, f"id {ident} exceeds the document's idMax {raw}"
    for results in root.iter(_NS + "MeasurementResults"):
        sets = {e.get("id") for e in results.iter(_NS + "MeasuredPointSet")}
        for feature in results.iterfind(f"{_NS}MeasuredFeatures/*"):
            for tag in _POINT_SET_REFS:
                for ref in feature.iterfind(f"{_NS}PointList/{_NS}{tag}"):
                    if (ref.text or "").strip() not in sets:
                        yield ref, (f"{tag} {(ref.text or '').strip()} names no "
                                    f"MeasuredPointSet of these results")
