"""``results.json`` → one self-contained HTML page.

Everything is inline: the CSS, the viewer script, the SVG plots, the 3-D scenes as
JSON.  The page loads nothing (no URL appears in it), so it can be mailed, archived
and opened on a machine without network.  The same results give the same bytes:
numbers have fixed decimals and nothing depends on the clock unless a ``generated``
text is passed in.

Templates: ``templates/report/`` (``report.html.j2`` with the includes ``guard.js.j2``,
``style.css.j2``, ``viewer.js.j2``), found through ``probegen.resources``.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from probegen.errors import ProbegenError
from probegen.evaluate.characteristics import NOT_EVALUATED, NOT_OK, OK, UNTOLERANCED
from probegen.files import write_file
from probegen.report import sections
from probegen.report.model import Characteristic, Results, read_results, run_fields
from probegen.report.numbers import fixed, signed
from probegen.report.trend import trend_section
from probegen.resources import template_text
from probegen.spc.series import Series

if TYPE_CHECKING:
    import jinja2

DECIMALS = 4
"""Decimals of lengths in the tables, mm (as ``probegen ingest`` prints them)."""


def render_report(results: Mapping[str, Any], *, title: str | None = None,
                  generated: str | None = None, source: str = "results.json",
                  history: Sequence[Series] = ()) -> str:
    """The HTML report of ``results`` (a parsed ``results.json``).

    Args:
        results: the JSON document ``probegen ingest`` writes.
        title: page title; default: the part number, name and serial when the results
            name a part number (``Inspection report 4711-020-A Bearing block, serial
            S0042``), else ``probegen report: <log file>``.
        generated: a text for the footer (e.g. a timestamp); none by default, so the
            page is byte-for-byte repeatable.
        source: name of the results for error messages.
        history: the characteristics' history (from the results store); when given, a
            History section with the SPC table and a trend chart per series
            (:func:`probegen.report.trend.trend_section`).

    Returns:
        The page, ``\\n`` line endings.

    Raises:
        ProbegenError: a key of ``results`` is malformed (message names its key path).
    """
    res = read_results(results, source)
    page = _env().get_template("report.html.j2").render(
        title=title or _default_title(res), results=res, status=overall_status(res),
        run=run_fields(res.run), views=sections.views(res),
        form={f.id: sections.form_plots(f) for f in res.features},
        calibration=sections.calibration(res), decisions=sections.decisions(res),
        generated=generated, history=trend_section(history) if history else "")
    return page.replace("\r\n", "\n")


def write_report(results_json_path: str | Path, out_path: str | Path, *,
                 title: str | None = None, history: Sequence[Series] = ()) -> Path:
    """Read ``results.json``, write the report page (with the ``history`` section when
    given, see :func:`render_report`), return its path.

    Raises:
        ProbegenError: the file cannot be read or is not a results document.
    """
    src, out = Path(results_json_path), Path(out_path)
    try:
        doc = json.loads(src.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ProbegenError(f"{src}: expected the results.json that probegen ingest wrote, "
                            "found no such file") from None
    except OSError as exc:
        raise ProbegenError(f"{src}: cannot read the results: {exc.strerror}") from exc
    except json.JSONDecodeError as exc:
        raise ProbegenError(f"{src}:{exc.lineno}:{exc.colno}: expected results JSON, "
                            f"found invalid JSON ({exc.msg})") from exc
    if isinstance(doc, dict) and "features" not in doc:
        raise ProbegenError(f"{src}: expected the results.json that probegen ingest wrote (with "
                            f"its 'features' list), found JSON without 'features'")
    page = render_report(doc, title=title, source=str(src), history=history)
    return write_file(out, page, "the HTML report")


def overall_status(res: Results) -> str:
    """The run's status (``results.json`` ``status``): ``OK`` only when every
    toleranced characteristic of the spec was evaluated and conforms, else ``NOT OK``,
    ``NOT EVALUATED``, or ``not toleranced``."""
    return "not toleranced" if res.status == UNTOLERANCED else res.status


def _default_title(res: Results) -> str:
    run = res.run
    if run is not None and run.part_number:
        name = f" {run.part_name}" if run.part_name else ""
        serial = f", serial {run.serial}" if run.serial else ""
        return f"Inspection report {run.part_number}{name}{serial}"
    return f"probegen report: {res.source}" if res.source else "probegen report"


@functools.cache
def _env() -> jinja2.Environment:
    """The page's Jinja environment: autoescaped, strict about undefined names."""
    import jinja2

    env = jinja2.Environment(
        loader=jinja2.FunctionLoader(lambda name: template_text("report", name)),
        undefined=jinja2.StrictUndefined, autoescape=True, keep_trailing_newline=True,
        trim_blocks=True, lstrip_blocks=True)
    env.filters.update(mm=mm, dev=deviation, tol=tolerance, status=status, expanded=expanded,
                       status_class=status_class, agreement=agreement,
                       trusted=_markup)
    return env


def _markup(text: str) -> Any:
    """Trusted text made here (SVG, JSON) inserted as is."""
    import markupsafe

    return markupsafe.Markup(text)


def mm(value: float | None) -> str:
    """A length in the table, mm (``–`` when not evaluated)."""
    return "\u2013" if value is None else fixed(value, DECIMALS)


def expanded(value: float | None) -> str:
    """An expanded uncertainty in the table, mm, or ``–`` when the results have none."""
    return "\u2013" if value is None else mm(value)


def deviation(value: float | None) -> str:
    """A deviation in the table, signed, mm (``–`` when not evaluated)."""
    return "\u2013" if value is None else signed(value, DECIMALS)


def tolerance(c: Characteristic) -> str:
    """The tolerance zone of a characteristic: ``−a / +b``, ``≤ b``, ``≥ a`` or ``–``."""
    if c.lower is None and c.upper is None:
        return "\u2013"
    if c.lower is None:
        return f"\u2264 {deviation(c.upper or 0.0)}"
    if c.upper is None:
        return f"\u2265 {deviation(c.lower)}"
    return f"{deviation(c.lower)} / {deviation(c.upper)}"


def status(value: str) -> str:
    """A status as the page prints it (``–`` for not toleranced)."""
    return "\u2013" if value == UNTOLERANCED else value


def agreement(agrees: bool | None) -> str:
    """``agree``, ``DISAGREE`` or ``–`` (a value missing on one side)."""
    return "\u2013" if agrees is None else ("agree" if agrees else "DISAGREE")


def status_class(value: str | bool | None) -> str:
    """CSS class colouring a status or an agreement: green ``ok`` only for ``OK`` (or
    agreeing), amber ``ne`` for ``NOT EVALUATED``."""
    if isinstance(value, bool) or value is None:
        return "none" if value is None else ("ok" if value else "nok")
    return {OK: "ok", NOT_OK: "nok", NOT_EVALUATED: "ne"}.get(value, "none")
