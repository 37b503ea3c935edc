"""The HTML report: content, self-containment, determinism, and a real browser run.

The browser test loads the page in headless Chromium and fails on any console output,
uncaught exception or error marker (the page's guard script turns errors into a
``data-report-error`` element), requires the ``data-report-ready`` marker the viewer
sets at its end, and checks that the screenshot shows the drawn 3-D views.  Without
Chromium it skips, unless ``CI`` is set: then it fails.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import zlib
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from mutations import mutate

from probegen.errors import ProbegenError
from probegen.report import palette, render_report, write_report
from probegen.report.model import read_results, sphere_test_radii
from probegen.report.numbers import compact, fixed, signed
from probegen.report.svg import nice_ticks

SAMPLE = REPO / "samples" / "sphere25"


@pytest.fixture(scope="module")
def ingested() -> Any:
    from probegen.evaluate.ingest import ingest
    from probegen.spec.model import load_spec

    spec = load_spec(SAMPLE / "sphere_test.toml")
    return ingest(SAMPLE / "sphere_test.log", spec, with_path=True)


@pytest.fixture(scope="module")
def results(ingested: Any) -> dict[str, Any]:
    from probegen.evaluate.outputs import to_json

    doc: dict[str, Any] = json.loads(to_json(ingested))
    return doc


@pytest.fixture(scope="module")
def page(results: dict[str, Any]) -> str:
    return render_report(results)


def scene(html: str, element_id: str) -> dict[str, Any]:
    match = re.search(rf'<script type="application/json" id="{element_id}">(.*?)</script>',
                      html, re.S)
    assert match, f"no scene {element_id} in the page"
    data: dict[str, Any] = json.loads(match.group(1))
    return data


# -- content ----------------------------------------------------------------------------

def test_summary_table_holds_the_values(page: str) -> None:
    rows = re.findall(r"<tr class=\"(\w+)\"><th scope=\"row\">(\w+)(?: <small>[^<]*</small>)?"
                      r"</th>((?:<td[^>]*>[^<]*</td>)+)", page)
    cells = {name: re.findall(r">([^<]*)</td>", tds) for _, name, tds in rows}
    assert list(cells) == ["X", "Y", "Z", "POS", "D", "P_FTU", "P_STU", "R_EFF"]
    assert cells["D"][:3] == ["24.9992", "25.0000", "-0.0008"]
    assert cells["X"][:3] == ["0.8000", "0.0000", "+0.8000"]
    assert cells["R_EFF"][:3] == ["2.9996", "3.0000", "-0.0004"]
    assert all(cls == "none" for cls, _, _ in rows)
    # the form value names its method (ISO 10360-5's P_FTU is least squares)
    assert '<th scope="row">P_FTU <small>least squares</small></th>' in page


def test_tolerances_colour_the_status(results: dict[str, Any]) -> None:
    doc = json.loads(json.dumps(results))
    chars = doc["features"][0]["characteristics"]
    chars[5].update(upper=0.001, ok=False, status="NOT OK")        # P_FTU 0.0016 > 0.001
    chars[4].update(lower=-0.002, upper=0.002, ok=True, status="OK")
    doc["features"][0].update(ok=False, status="NOT OK")
    doc["status"] = "NOT OK"
    html = render_report(doc)
    assert re.search(r'<tr class="nok"><th scope="row">P_FTU <small>least squares</small></th>'
                     r'.*?NOT OK</td>', html)
    assert re.search(r'<tr class="ok"><th scope="row">D</th>.*?-0.0020 / \+0.0020.*?OK</td>',
                     html)
    assert '<span class="badge nok">NOT OK</span>' in html


def test_summary_shows_U_and_the_iso_14253_decision(results: dict[str, Any],
                                                    ingested: Any) -> None:
    d = next(c for c in ingested.results[0].characteristics if c.name == "D")
    doc = json.loads(json.dumps(results))
    chars = doc["features"][0]["characteristics"]
    chars[4].update(lower=-0.0008 - 0.5 * d.U, upper=0.01, ok=True, status="OK",
                    decision="undecided")
    html = render_report(doc)
    row = re.search(r'<th scope="row">D</th>(.*?)</tr>', html)
    assert row is not None
    cells = re.findall(r">([^<]*)</td>", row[1])
    assert cells[-2:] == [f"{d.U:.4f}", "undecided"] and cells[-3] == "OK"
    assert "decision rule simple (simple acceptance" in html
    assert "the machine contribution was not stated" in html
    old = json.loads(json.dumps(results))
    for c in old["features"][0]["characteristics"]:
        del c["U"], c["u"], c["decision"]
    del old["uncertainty"]
    row = re.search(r'<th scope="row">D</th>(.*?)</tr>', render_report(old))
    assert row is not None and re.findall(r">([^<]*)</td>", row[1])[-2:] == ["\u2013"] * 2


def test_notes_and_diagnostics_are_shown(results: dict[str, Any]) -> None:
    doc = dict(results, notes=["feature SPH1: no touch for points 7"],
               diagnostics=["run.log:12:4: expected a number, found 'X'\n    PT X\n    ^"])
    html = render_report(doc)
    assert "<li>feature SPH1: no touch for points 7</li>" in html
    assert "run.log:12:4: expected a number, found &#39;X&#39;" in html


def test_page_is_self_contained(page: str) -> None:
    lowered = page.lower()
    for needle in ("http://", "https://", "//cdn", "<link", " src=", "@import", "url(",
                   "@font-face"):
        assert needle not in lowered, needle


def test_error_balls_follow_method_m1(page: str, results: dict[str, Any]) -> None:
    data = scene(page, "scene-balls-0")
    feature = results["features"][0]
    eps = np.array(feature["residuals"])
    balls = np.array(data["balls"])
    assert balls.shape == (25, 5)
    big_r = 12.5
    rho = np.abs(eps) * big_r * math.sin(math.pi / 12) / np.abs(eps).max()
    assert np.allclose(balls[:, 3], rho, atol=1e-4)
    assert np.array_equal(balls[:, 4], np.where(eps > 0, 1, -1))
    assert np.allclose(balls[:, :3], big_r * np.array(feature["directions"]), atol=1e-4)


def test_path_view_holds_every_segment_and_point(page: str, results: dict[str, Any]) -> None:
    data = scene(page, "scene-path")
    styles = [s["name"] for s in data["styles"]]
    used = {styles[s[6]] for s in data["segments"]}
    assert {"rapid", "protected", "touch", "reference"} <= used
    path = [s for s in data["segments"] if styles[s[6]] != "reference"]
    assert len(path) == len(results["path"])
    assert len(data["points"]) == 25


def test_form_plots(page: str) -> None:
    form = page[page.index('<section id="form">'):page.index('<section id="calibration">')]
    assert form.count("<svg") == 2
    assert form.count("<rect x=") >= 25 + 1      # 25 bars (and the frame)
    assert form.count("<circle") == 25


def test_calibration_from_the_sphere_test(page: str, ingested: Any) -> None:
    radii = sphere_test_radii(read_results(json.loads(_results_text(ingested))).features[0])
    assert radii is not None
    assert np.allclose(radii.radii, ingested.results[0].radii, atol=2e-7)
    cal = page[page.index('<section id="calibration">'):]
    assert "sphere test SPH1" in cal
    assert "No rotary-axis (method M4) or geometric-error (method M5)" in cal


def test_calibration_absent_says_so(results: dict[str, Any]) -> None:
    doc = json.loads(json.dumps(results))
    del doc["features"][0]["residuals"]
    cal = render_report(doc).split('<section id="calibration">')[1]
    assert "No probe calibration (effective radius per direction)" in cal
    assert "<svg" not in cal


def test_calibration_functions_render_line_plots(results: dict[str, Any]) -> None:
    positions = [0.0, 45.0, 90.0, 135.0, 180.0]
    doc = dict(results, calibration={
        "probe": {"ball_radius": 3.0, "effective_radius": 2.999, "source": "probe.toml",
                  "directions": [[0, 0, 1], [1, 0, 0], [0, 1, 0]],
                  "radii": [2.9990, 2.9985, 3.0004]},
        "functions": [
            {"name": "EXB", "positions": positions, "values": [0, 1.5, 2.0, 1.0, -0.5],
             "unit": "\u00b5m"},
            {"name": "EZX", "positions": [0.0, 500.0], "values": [0.0, 0.004]},
        ]})
    cal = render_report(doc).split('<section id="calibration">')[1]
    assert "probe calibration from probe.toml" in cal
    assert "sphere test SPH1" not in cal            # an explicit calibration wins
    assert "method M4" not in cal
    polylines = re.findall(r'<polyline points="([^"]*)"', cal)
    assert [len(p.split()) for p in polylines] == [5, 2]
    ys = [float(xy.split(",")[1]) for xy in polylines[0].split()]
    assert ys[2] == min(ys) and ys[4] == max(ys)    # highest value drawn highest
    assert ">EXB</text>" in cal and "value (\u00b5m)" in cal


def test_render_is_deterministic(results: dict[str, Any], tmp_path: Path) -> None:
    src = tmp_path / "results.json"
    src.write_text(json.dumps(results), encoding="utf-8")
    a = write_report(src, tmp_path / "a.html").read_bytes()
    b = write_report(src, tmp_path / "b.html").read_bytes()
    assert a == b
    assert a.decode("utf-8") == render_report(results, source=str(src))
    assert b"\r" not in a


def test_title_and_generated_text_are_injected(results: dict[str, Any]) -> None:
    html = render_report(results, title="Probe check <M1>", generated="2024-05-01 10:00")
    assert "<title>Probe check &lt;M1&gt;</title>" in html
    assert "2024-05-01 10:00" in html
    assert "<footer>Made by probegen.</footer>" in render_report(results)


RUN = {"part_number": "4711-020-A", "part_name": "Sphere artefact", "serial": "S0042",
       "operator": "A. Smith", "machine": "Generic VMC", "program": "O1001 H2DAFDB55",
       "time": "2026-11-26T13:48:53+01:00", "batch": None, "calibration": None}


def test_header_names_the_part_serial_operator_machine_program_and_date(
        results: dict[str, Any]) -> None:
    by_log = f"<title>probegen report: {results['source']}</title>"
    assert by_log in render_report(results)  # no run block: the log names the page
    html = render_report({**results, "run": RUN})
    assert "<title>Inspection report 4711-020-A Sphere artefact, serial S0042</title>" in html
    header = html[html.index('<dl class="run"'):html.index("</dl>")]
    fields = re.findall(r"<dt>(.*?)</dt><dd>(.*?)</dd>", header)
    assert fields == [("date", "2026-11-26T13:48:53+01:00"), ("part number", "4711-020-A"),
                      ("part", "Sphere artefact"), ("serial", "S0042"),
                      ("operator", "A. Smith"), ("machine", "Generic VMC"),
                      ("program", "O1001 H2DAFDB55")]
    without_number = render_report({**results, "run": {**RUN, "part_number": None}})
    assert by_log in without_number
    with pytest.raises(ProbegenError, match=re.escape("run.serial: expected a string, found 7")):
        render_report({**results, "run": {**RUN, "serial": 7}})


def test_user_text_is_escaped(results: dict[str, Any]) -> None:
    doc = json.loads(json.dumps(results))
    doc["features"][0]["id"] = "</script><b>&"
    html = render_report(doc)
    assert "<b>&" not in html and "&lt;/script&gt;&lt;b&gt;&amp;" in html
    data = scene(html, "scene-balls-0")
    assert data["title"].startswith("Error balls of </script><b>&")


# -- in-process decisions (docs/actions.md) ---------------------------------------------

@pytest.fixture(scope="module")
def decided(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, Any]]:
    """results.json of the bore_block setup program run on the virtual machine: the bore
    0.03 mm oversize (tool 12 wear +0.015) and 0.08 mm oversize (alarm 3010)."""
    from conftest import sample_script
    from test_actions_closed_loop import SPEC, run

    from probegen.cad import load_step
    from probegen.dialects import get_dialect
    from probegen.evaluate.ingest import ingest
    from probegen.evaluate.outputs import to_json
    from probegen.planning import plan_program
    from probegen.spec.model import load_spec

    spec = load_spec(REPO / SPEC)
    text = get_dialect("fanuc").generate(plan_program(spec, runtime_variables=True).program)
    out = {}
    for bore in (50.03, 50.08):
        tmp = tmp_path_factory.mktemp("decided")
        sample_script("bore_block").main(tmp / "part.step", bore_diameter=bore,
                                         boss_diameter=20.0)
        (tmp / "run.log").write_text(run(text, load_step(tmp / "part.step")).output)
        out[f"{bore:.2f}"] = json.loads(to_json(ingest(tmp / "run.log", spec)))
    return out


def _row(html: str, feature: str, key: str) -> list[str]:
    table = html.split(f'id="decisions-{feature}"')[1].split("</table>")[0]
    row = re.search(rf'<tr class="(\w+)"><th scope="row">{key} <small>.*?</tr>', table)
    assert row is not None, (feature, key)
    return [row.group(1), *re.findall(r"<td[^>]*>(.*?)</td>", row.group(0))]


def test_decisions_show_offline_and_machine_values(decided: dict[str, Any]) -> None:
    doc = decided["50.03"]
    html = render_report(doc)
    assert '<a href="#decisions">' in html and '<section id="decisions">' in html
    # the tool 12 radius wear the program wrote for the bore 0.03 oversize (RES BORE T12 C.0150)
    cls, offline, machine, diff, limit, agreement = _row(html, "BORE", "C")
    assert (cls, machine, agreement) == ("ok", "+0.0150", "agree")
    assert abs(float(offline) - 0.015) <= 2e-4 and limit == "\u2264 0.0002"
    assert abs(float(diff)) <= 2e-4
    assert _row(html, "EDGE", "A")[2].startswith("+0.50")     # the part turned 0.5 degrees
    assert _row(html, "BOSS", "NG")[1:3] == ["no", "no"]
    tables = re.findall(r'id="decisions-(\w+)"', html)
    assert tables == list(dict.fromkeys(d["feature"] for d in doc["decisions"]))
    assert html.count("<tr class=") - render_report(
        {k: v for k, v in doc.items() if k != "decisions"}).count("<tr class=") == len(
        doc["decisions"])
    assert render_report(doc) == html                          # byte-repeatable


def test_decisions_show_a_disagreement_and_an_alarm(decided: dict[str, Any]) -> None:
    doc = json.loads(json.dumps(decided["50.03"]))
    bore_x = next(d for d in doc["decisions"] if d["feature"] == "BORE" and d["key"] == "X")
    bore_x.update(machine=bore_x["machine"] + 0.001, agrees=False)
    html = render_report(doc)
    assert _row(html, "BORE", "X")[0] == "nok" and _row(html, "BORE", "X")[-1] == "DISAGREE"
    assert '<span class="badge nok">DISAGREE</span>' in html.split('id="decisions-BORE"')[1]
    stopped = render_report(decided["50.08"])
    alarm = re.findall(r'<p class="alarm">(.*?)</p>', stopped)
    assert len(alarm) == 1 and alarm[0].startswith("the program stopped: ERR OUTTOL BORE 1")
    assert _row(stopped, "BORE", "C")[2] == "\u2013"         # not printed: stopped before


DECISIONS_JSON = json.dumps({"features": [], "notes": ["the program stopped: ERR OUTTOL B 1"],
                             "decisions": [{"feature": "B", "key": "C", "offline": 0.015,
                                            "machine": 0.015, "agrees": True, "limit": 2e-4}]})


@st.composite
def mutated_decisions(draw: st.DrawFn) -> str:
    return mutate(draw, DECISIONS_JSON, '0123456789.-,:"[]{}ntrufals')


@settings(max_examples=examples(150))
@given(mutated_decisions())
def test_mutated_decisions_give_a_page_or_a_probegen_error(text: str) -> None:
    try:
        doc = json.loads(text)
    except ValueError:
        return
    try:
        assert render_report(doc).startswith("<!DOCTYPE html>")
    except ProbegenError:
        pass


def test_results_without_decisions_have_no_section(page: str) -> None:
    assert "decisions" not in page and "Decisions" not in page


# -- bad input --------------------------------------------------------------------------

@pytest.mark.parametrize(("edit", "message"), [
    (lambda d: d.pop("features"), "results.json: features: expected a list, found nothing"),
    (lambda d: d["features"][0]["residuals"].__setitem__(3, "x"),
     "features[0].residuals[3]: expected a number, found 'x'"),
    (lambda d: d["features"][0]["residuals"].pop(),
     "features[0].residuals: expected 25 entries (one per point), found 24"),
    (lambda d: d["path"][2].__setitem__("end", [1, 2]),
     "path[2].end: expected 3 numbers, found [1, 2]"),
    (lambda d: d.__setitem__("calibration", {"functions": [{"name": "f", "positions": [1, 2],
                                                            "values": [1]}]}),
     "calibration.functions[0].values: expected as many values as positions (2)"),
    (lambda d: d.__setitem__("decisions", [{"feature": "B", "key": "X", "offline": "1"}]),
     "decisions[0].offline: expected a number, found '1'"),
])
def test_bad_results_name_the_key(results: dict[str, Any], edit: Any, message: str) -> None:
    doc = json.loads(json.dumps(results))
    edit(doc)
    with pytest.raises(ProbegenError, match=re.escape(message)):
        render_report(doc)


def test_write_report_rejects_bad_json(tmp_path: Path) -> None:
    src = tmp_path / "results.json"
    src.write_text('{"features": [\n  1,,\n]}', encoding="utf-8")
    with pytest.raises(ProbegenError, match=r"results.json:2:5: expected results JSON"):
        write_report(src, tmp_path / "r.html")
    with pytest.raises(ProbegenError, match="missing.json: expected the results.json that "
                                            "probegen ingest wrote, found no such file"):
        write_report(tmp_path / "missing.json", tmp_path / "r.html")


# -- helpers ----------------------------------------------------------------------------

def test_numbers_are_fixed_and_never_negative_zero() -> None:
    assert fixed(-0.00001, 4) == "0.0000"
    assert fixed(1e-12, 2) == "0.00" and fixed(-1.5, 1) == "-1.5"
    assert signed(0.25, 3) == "+0.250" and signed(-0.00001, 3) == "0.000"
    assert compact(2.50, 4) == "2.5" and compact(-0.00001, 4) == "0"
    assert nice_ticks(-0.79, 0.81) == ([-1.0, -0.5, 0.0, 0.5, 1.0], 1)
    assert nice_ticks(0.0, 0.003) == ([0.0, 0.001, 0.002, 0.003], 3)


def test_importing_the_report_does_not_load_jinja() -> None:
    code = "import sys, probegen.report; print('jinja2' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=REPO)
    assert out.stdout.strip() == "False"


def _results_text(ingested: Any) -> str:
    from probegen.evaluate.outputs import to_json

    return to_json(ingested)


# -- the browser --------------------------------------------------------------------------

CHROMIUM_FLAGS = ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic",
                  "--no-first-run", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--hide-scrollbars",
                  "--host-resolver-rules=MAP * ~NOTFOUND", "--window-size=1200,1600")


def chromium() -> str:
    """Path of the Chromium binary; skip (fail under CI) when there is none."""
    for name in (os.environ.get("PROBEGEN_CHROMIUM", ""), "chromium", "chromium-browser",
                 "google-chrome"):
        found = shutil.which(name) if name else None
        if found:
            return found
    reason = "headless Chromium not found (apt-get install chromium, or PROBEGEN_CHROMIUM)"
    if os.environ.get("CI", "").lower() not in ("", "0", "false", "no"):
        pytest.fail(reason + "; CI must run the browser test", pytrace=False)
    pytest.skip(reason)


def run_chromium(page: Path, tmp_path: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    profile = tmp_path / f"profile-{len(list(tmp_path.glob('profile-*')))}"
    cmd = [chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *extra,
           page.resolve().as_uri()]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=30, check=False)


def console_lines(stderr: str) -> list[str]:
    """Console messages and uncaught exceptions Chromium logged (the report logs none)."""
    return [line for line in stderr.splitlines() if ":CONSOLE" in line or "Uncaught" in line]


def decode_png(data: bytes) -> np.ndarray:
    """An 8-bit RGB(A) non-interlaced PNG as an (h, w, channels) uint8 array."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, header = 8, b"", None
    while pos < len(data):
        size, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + size]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + size
    assert header is not None
    width, height, depth, colour, _, _, interlace = header
    assert depth == 8 and colour in (2, 6) and interlace == 0, header
    bpp = 3 if colour == 2 else 4
    raw = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(height, -1)
    out = np.zeros((height, width * bpp), dtype=np.uint8)
    prev = np.zeros(width * bpp, dtype=np.uint8)
    for y in range(height):
        out[y] = prev = _unfilter(int(raw[y, 0]), raw[y, 1:], prev, bpp)
    return out.reshape(height, width, bpp)


def _unfilter(kind: int, row: np.ndarray, prev: np.ndarray, bpp: int) -> np.ndarray:
    if kind == 0:
        return row.copy()
    if kind == 1:
        return (np.cumsum(row.reshape(-1, bpp).astype(np.int64), axis=0) % 256
                ).astype(np.uint8).ravel()
    if kind == 2:
        return ((row.astype(np.int64) + prev) % 256).astype(np.uint8)
    cur, up = bytearray(row.tobytes()), prev.tobytes()
    for i in range(len(cur)):
        left = cur[i - bpp] if i >= bpp else 0
        if kind == 3:
            cur[i] = (cur[i] + (left + up[i]) // 2) & 0xFF
            continue
        upleft = up[i - bpp] if i >= bpp else 0
        p = left + up[i] - upleft
        pa, pb, pc = abs(p - left), abs(p - up[i]), abs(p - upleft)
        pred = left if pa <= pb and pa <= pc else (up[i] if pb <= pc else upleft)
        cur[i] = (cur[i] + pred) & 0xFF
    return np.frombuffer(bytes(cur), dtype=np.uint8)


def near(image: np.ndarray, colour: str, tol: int = 24) -> int:
    """How many pixels are within ``tol`` of ``#rrggbb`` in every channel."""
    rgb = np.array([int(colour[k:k + 2], 16) for k in (1, 3, 5)])
    return int((np.abs(image[..., :3].astype(int) - rgb) <= tol).all(axis=-1).sum())


@pytest.fixture
def page_file(page: str, tmp_path: Path) -> Path:
    path = tmp_path / "report.html"
    path.write_text(page, encoding="utf-8", newline="\n")
    return path


def test_browser_runs_the_page_cleanly(page_file: Path, tmp_path: Path) -> None:
    dom = run_chromium(page_file, tmp_path, "--enable-logging=stderr", "--v=0", "--dump-dom")
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert console_lines(dom.stderr) == []
    assert not re.search(r'<p class="report-error"', dom.stdout)
    assert 'data-report-ready="2"' in dom.stdout


def test_browser_screenshot_shows_the_views(page_file: Path, tmp_path: Path) -> None:
    shot = tmp_path / "shot.png"
    run = run_chromium(page_file, tmp_path, "--enable-logging=stderr", "--v=0",
                       f"--screenshot={shot}")
    assert run.returncode == 0 and shot.exists(), run.stderr[-2000:]
    assert console_lines(run.stderr) == []
    image = decode_png(shot.read_bytes())
    assert image.shape[:2] == (1600, 1200)
    rgb = image[..., :3].reshape(-1, 3)
    assert (rgb < 245).any(axis=1).mean() > 0.05            # not a blank page
    assert len(np.unique(rgb @ np.array([65536, 256, 1]))) > 200
    assert near(image, palette.PATH["protected"]) > 200    # the path view is drawn
    assert near(image, palette.PATH["touch"]) > 50
    assert near(image, palette.DARK) > 500                 # dark error balls
    assert near(image, palette.LIGHT) > 500                # light ones


INTERACT = """<script>
(function () {
  var changed = 0;
  document.querySelectorAll('canvas[data-scene]').forEach(function (c) {
    var before = c.toDataURL(), view = c.reportView;
    c.dispatchEvent(new PointerEvent('pointerdown', {clientX: 100, clientY: 100, pointerId: 7}));
    c.dispatchEvent(new PointerEvent('pointermove', {clientX: 160, clientY: 130, pointerId: 7}));
    c.dispatchEvent(new PointerEvent('pointerup', {pointerId: 7}));
    c.dispatchEvent(new WheelEvent('wheel', {deltaY: -300, cancelable: true}));
    c.dispatchEvent(new KeyboardEvent('keydown', {key: 'ArrowUp', cancelable: true}));
    var scheduled = view.pending;
    view.draw();  /* what the scheduled animation frame does */
    if (scheduled && view.zoom > 1 && c.toDataURL() !== before) { changed += 1; }
  });
  document.documentElement.setAttribute('data-redrawn', String(changed));
}());
</script>
</body>"""


def test_browser_redraws_on_drag_wheel_and_keys(page: str, tmp_path: Path) -> None:
    moved = tmp_path / "moved.html"
    moved.write_text(page.replace("</body>", INTERACT), encoding="utf-8")
    dom = run_chromium(moved, tmp_path, "--enable-logging=stderr", "--v=0", "--dump-dom")
    assert console_lines(dom.stderr) == []
    assert not re.search(r'<p class="report-error"', dom.stdout)
    assert 'data-redrawn="2"' in dom.stdout


def test_browser_harness_sees_script_errors(page: str, tmp_path: Path) -> None:
    broken = tmp_path / "broken.html"
    broken.write_text(page.replace("</body>", "<script>noSuchFunction();</script>\n</body>"),
                      encoding="utf-8")
    dom = run_chromium(broken, tmp_path, "--enable-logging=stderr", "--v=0", "--dump-dom")
    assert '<p class="report-error" data-report-error="">' in dom.stdout
    assert any("noSuchFunction" in line for line in console_lines(dom.stderr))
