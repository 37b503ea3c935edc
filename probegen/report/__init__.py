"""The HTML report: ``probegen report results.json -o report.html``.

One self-contained page from the ``results.json`` that ``probegen ingest`` writes: a
table per feature, notes and diagnostics, the stylus path and the sphere test's error
balls in interactive 3-D views, form plots and a calibration section.  See
``docs/report.md``.

Importing this package is cheap: Jinja is loaded when a page is rendered.
"""

from __future__ import annotations

from probegen.report.html import render_report, write_report

__all__ = ["render_report", "write_report"]
