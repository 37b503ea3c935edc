"""The trend chart of a characteristic's history and the report's History section."""

from __future__ import annotations

import json
import math
import re
import xml.etree.ElementTree as ET

import numpy as np
from conftest import REPO
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from spc_series import make_series

from probegen.report import render_report
from probegen.report.trend import trend_section, trend_svg
from probegen.spc import Series, control_chart

RESULTS = REPO / "tests" / "golden" / "ingest" / "results.json"


def _noise(count: int, seed: int) -> list[float]:
    return list(0.001 * np.random.default_rng(seed).standard_normal(count))


def _parse(svg: str) -> ET.Element:
    root = ET.fromstring(svg)
    assert root.tag == "svg"
    return root


def _points(root: ET.Element) -> list[ET.Element]:
    return [c for c in root.iter("circle") if "point" in c.get("class", "").split()]


def test_the_chart_is_xml_and_marks_a_planted_out_of_control_point() -> None:
    values: list[float | None] = list(_noise(25, 1))
    values[11] = 0.0085
    series = make_series(values, lower=-0.01, upper=0.01)
    root = _parse(trend_svg(series))
    points = _points(root)
    assert len(points) == 25
    ooc = [p for p in points if "ooc" in p.get("class", "").split()]
    assert [p.get("data-run") for p in ooc] == ["r12"]
    tip = ooc[0].find("title")
    assert tip is not None and "serial S12" in (tip.text or "") and "beyond" in (tip.text or "")
    labels = {t.text for t in root.iter("text")}
    assert {"LSL", "USL", "CL", "LCL", "UCL"} <= labels
    # the marked point is drawn above the UCL line
    chart = control_chart(series)
    assert chart is not None
    assert float(ooc[0].get("cy", "nan")) < _line_y(root, chart.ucl)



def _line_y(root: ET.Element, value: float) -> float:
    """The pixel y of the limit line nearest to data ``value`` (from the y tick labels)."""
    ticks = [(float(t.text or ""), float(t.get("y", "nan")) - 4.0) for t in root.iter("text")
             if t.get("text-anchor") == "end"]
    (v0, y0), (v1, y1) = ticks[0], ticks[-1]
    at = y0 + (value - v0) * (y1 - y0) / (v1 - v0)
    limits = [float(e.get("y1", "nan")) for e in root.iter("line") if e.get("class") == "limit"]
    return min(limits, key=lambda y: abs(y - at))


def test_a_planted_drift_shows_on_the_chart() -> None:
    # 30 runs: 15 stationary, then a drift of 0.4 σ per run.
    values: list[float | None] = [*_noise(15, 2), *(0.0004 * k for k in range(1, 16))]
    root = _parse(trend_svg(make_series(values)))
    marked = [p.get("data-run") for p in _points(root) if "trend" in p.get("class", "").split()]
    assert marked and all(int(str(run)[1:]) >= 15 for run in marked)
    # the early values lie below the centre line the drift pulled up: a run, not a trend
    runs = [p.get("data-run") for p in _points(root) if "run" in p.get("class", "").split()]
    assert runs
    stationary = _parse(trend_svg(make_series(_noise(30, 7))))
    assert not [p for p in _points(stationary) if p.get("class") != "point"]


def test_subgroup_means_are_plotted_over_single_values() -> None:
    values: list[float | None] = list(_noise(20, 4))
    root = _parse(trend_svg(make_series(values, subgroups=[str(k // 4) for k in range(20)])))
    assert len(_points(root)) == 5
    assert len([c for c in root.iter("circle") if c.get("class") == "single"]) == 20


def test_not_evaluated_runs_are_marked_and_nothing_to_draw_says_so() -> None:
    root = _parse(trend_svg(make_series([0.001, None, 0.002, -0.001])))
    gaps = [p for p in root.iter("path") if p.get("class") == "not-evaluated"]
    assert len(gaps) == 1 and "r02" in (gaps[0].findtext("title") or "")
    empty = trend_svg(make_series([None, None]))
    assert empty.startswith('<p class="empty">') and "no evaluated value" in empty
    one = _parse(trend_svg(make_series([0.001], lower=None, upper=None)))
    assert len(_points(one)) == 1


def test_the_chart_is_repeatable() -> None:
    series = make_series(_noise(30, 5))
    assert trend_svg(series) == trend_svg(series)


def test_history_section_in_the_report() -> None:
    doc = json.loads(RESULTS.read_text(encoding="utf-8"))
    plain = render_report(doc)
    assert render_report(doc, history=()) == plain
    assert 'id="history"' not in plain
    history = [make_series(_noise(30, 3)), make_series([0.001] * 12, feature="F<1>")]
    page = render_report(doc, history=history)
    assert '<a href="#history">History</a>' in page
    section = page.split('<section id="history">')[1].split("</section>")[0]
    assert section.count("<svg") == 2 and "F&lt;1&gt;" in section and "F<1>" not in section
    assert "constant values" in section
    rows = re.findall(r'<tr><td>P-100</td><td>([^<]*)</td><th scope="row">D</th>', section)
    assert rows == ["BORE", "F&lt;1&gt;"]
    # the rest of the page is the page without history, but for the nav link
    assert page.replace(trend_section(history) + "\n", "", 1).replace(
        ' <a href="#history">History</a>', "", 1) == plain


FINITE = st.floats(allow_nan=False, allow_infinity=False)
MEASURED = st.one_of(st.none(), FINITE, st.floats(-1.0, 1.0), st.just(0.0))


@settings(max_examples=examples(150))
@given(values=st.lists(MEASURED, max_size=30), lower=st.one_of(st.none(), FINITE),
       upper=st.one_of(st.none(), FINITE), nominal=FINITE,
       size=st.integers(1, 5))
def test_any_series_gives_a_chart_or_a_reason(values: list[float | None], lower: float | None,
                                              upper: float | None, nominal: float,
                                              size: int) -> None:
    series: Series = make_series(values, lower=lower, upper=upper, nominal=nominal,
                                 subgroups=[str(k // size) for k in range(len(values))])
    svg = trend_svg(series)
    if svg.startswith("<p"):
        assert "no trend chart" in svg
        return
    root = _parse(svg)
    for c in root.iter("circle"):
        assert math.isfinite(float(c.get("cx", "nan"))) and math.isfinite(float(c.get("cy", "nan")))
    assert trend_section([series]).startswith('<section id="history">')
