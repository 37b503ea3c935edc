"""QIF 3 results export: ``probegen qif`` (see ``docs/qif.md``).

* :func:`ingested_to_qif`: the results of ``probegen ingest`` (sphere tests, circles,
  cylinders, cones, spheres, tori, free-form points, lines, planes) as a QIF document: features,
  measured points, characteristics, their statuses and standard uncertainties.
* :func:`dmis_output_to_qif`: a DMIS output file's feature and tolerance actuals as a QIF
  document, with a list of what could not be converted.
* :func:`validate_qif`: check a document against the QIF 3 XSD set, keys and keyrefs
  included (the schema's path is an argument: it is not shipped with probegen).
* :func:`write_qif`: write a document (optionally validated first).

Output is byte-for-byte repeatable (no time stamp unless ``created`` is given; the
document's QPId is derived from its content unless ``qpid`` is given).

Example:
    >>> from probegen.results import parse_dmis_output
    >>> out = parse_dmis_output("FA(C1)=FEAT/CIRCLE,INNER,CART,1,2,3,0,0,1,10\\n")
    >>> export = dmis_output_to_qif(out)
    >>> "<CircleFeatureMeasurement" in export.text, export.notes
    (True, ())
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING

from probegen.errors import ProbegenError
from probegen.files import write_file
from probegen.qif.dmis_output import DmisTolerance, QifExport, dmis_output_qif, read_dmis_tolerances
from probegen.qif.validate import SCHEMA_ENV, QifValidationError, load_schema, validate_qif

if TYPE_CHECKING:
    from probegen.evaluate.ingest import Ingested
    from probegen.results.dmis_output import DmisOutput
    from probegen.spec.model import Spec

__all__ = [
    "SCHEMA_ENV",
    "DmisTolerance",
    "QifExport",
    "QifValidationError",
    "dmis_output_to_qif",
    "ingested_to_qif",
    "load_schema",
    "read_dmis_tolerances",
    "validate_qif",
    "write_qif",
]

APPLICATION = "probegen"
"""``Header/Application/Name`` and ``Software/ApplicationName`` of every document."""


def _version(version: str | None) -> str:
    if version is not None:
        return version
    from probegen import __version__

    return __version__


def ingested_to_qif(ing: Ingested, *, spec: Spec | None = None,
                    created: datetime | None = None, qpid: str | None = None,
                    version: str | None = None) -> str:
    """The results of ``probegen ingest`` as a QIF 3 document.

    Args:
        ing: the ingest (every evaluated feature; its decision rule sets the statuses).
        spec: the spec it was ingested with: names the machine and the part model and
            describes the probe (ball and shank diameter, length); without it the probe
            is described by the ball radius the points were compensated with.
        created: written as ``Version/TimeCreated`` (none by default: repeatable).
        qpid: the document's QPId (a UUID); default: derived from the content.
        version: the software version written; default probegen's.

    Returns:
        The document text (UTF-8 declaration, ``\\n`` line ends).

    Raises:
        ProbegenError: ``ing`` has no results, or ``qpid`` is not a UUID.
    """
    from probegen.qif.sphere_test import sphere_results_qif

    if not (ing.results or ing.revolved or ing.freeform or ing.planar) and not any(
            n.kind == "sphere_test" and n.partial is not None for n in ing.not_evaluated):
        raise ProbegenError(f"{ing.source}: expected evaluated features to export, found none")
    return sphere_results_qif(ing, spec=spec, application=APPLICATION,
                              version=_version(version), created=created, qpid=qpid)


def dmis_output_to_qif(out: DmisOutput, *,
                       tolerances: Mapping[str, DmisTolerance] | None = None,
                       created: datetime | None = None, qpid: str | None = None,
                       version: str | None = None) -> QifExport:
    """A DMIS output's feature and tolerance actuals as a QIF 3 document.

    Every ``FA`` becomes a feature measurement; every ``TA`` of a supported kind with
    known limits becomes a characteristic (INTOL: PASS, OUTOL: FAIL).  Items that cannot
    be converted are left out and named in the returned notes, never dropped silently;
    a caller that wants none left out raises on ``export.notes`` (the CLI prints them).

    Args:
        out: the parsed output (:func:`probegen.results.read_dmis_output`).
        tolerances: the ``T(name)`` definitions by name
            (:func:`read_dmis_tolerances` of the program): QIF needs every
            characteristic's limits, which an output file does not repeat.
        created: ``Version/TimeCreated``; none by default.
        qpid: the document's QPId; default: derived from the content.
        version: the software version written; default probegen's.

    Returns:
        The document and the notes.
    """
    return dmis_output_qif(out, tolerances=tolerances, application=APPLICATION,
                           version=_version(version), created=created, qpid=qpid)


def write_qif(path: str | os.PathLike[str], text: str, *,
              schema: str | os.PathLike[str] | None = None, validate: bool = False) -> Path:
    """Write a QIF document (UTF-8, ``\\n`` line ends), validating it first if asked.

    Args:
        path: the file to write (its folder is created).
        text: the document.
        schema: the QIF schema for validation (default ``$PROBEGEN_QIF_SCHEMA``).
        validate: check the text with :func:`validate_qif` before writing; an invalid
            document is never written.

    Returns:
        The path written.

    Raises:
        ProbegenError: the file cannot be written, or validation fails
            (:class:`QifValidationError`).
    """
    target = Path(path)
    if validate:
        validate_qif(text, schema=schema, source=str(target))
    return write_file(target, text, "the QIF document")
