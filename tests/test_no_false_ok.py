"""No false OK (issue 15, item 2): a run cut short, a no-contact touch and a toleranced
feature without touches are NOT EVALUATED in every output (terminal table,
results.json, results.csv, the HTML report, QIF) and end with exit code 11
(``INCOMPLETE``), never with a green OK and 0; a spec of lines and planes alone is
ingested and its faces evaluated, against the truth planted on the virtual machine.

Every case goes through ``probegen.cli.app.main`` like a user; the logs are the sample
sphere test's log (samples/sphere25/sphere_test.log, P_FTU 0.0016) edited in the test,
and one made by the virtual machine for the lines-and-planes spec.
"""

from __future__ import annotations

import csv
import io
import json
import math
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import REPO, SHARED
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen import cad
from probegen.cli.app import ExitCode, main
from probegen.errors import ProbegenError
from probegen.evaluate.characteristics import run_status

LOG = REPO / "samples/sphere25/sphere_test.log"
GREEN = 'class="badge ok"'
"""The report's green badge (run, feature or characteristic)."""
TOLERANCE = "tolerance = { form = 0.01, size = 0.01 }\n"
"""Limits the sample's sphere test meets (P_FTU 0.0016, P_STU -0.0008)."""


def sphere_spec(tmp: Path, extra: str = "", tolerance: str = TOLERANCE) -> Path:
    """The sample sphere test's spec with absolute paths, ``tolerance`` and ``extra``
    TOML appended."""
    text = (REPO / "samples/sphere25/sphere_test.toml").read_text()
    text = text.replace('"../machines', f'"{REPO}/samples/machines').replace(
        '"sphere25.step"', f'"{REPO}/samples/sphere25/sphere25.step"')
    path = tmp / "spec.toml"
    path.write_text(text + tolerance + extra)
    return path


def edited_log(tmp: Path, drop: tuple[str, ...] = (),
               after: dict[str, str] | None = None) -> Path:
    """The sample log without the lines starting with ``drop``, with a line inserted
    after each line starting with a key of ``after``."""
    out = []
    for line in LOG.read_text().splitlines():
        if line.startswith(drop):
            continue
        out.append(line)
        out += [new for old, new in (after or {}).items() if line.startswith(old)]
    path = tmp / "run.log"
    path.write_text("\n".join(out) + "\n")
    return path


@dataclass(frozen=True)
class Run:
    """What ``probegen ingest`` and ``probegen report`` gave."""

    code: int
    table: str
    doc: dict[str, Any]
    rows: list[dict[str, str]]
    html: str

    def feature(self, fid: str) -> dict[str, Any]:
        return next(f for f in self.doc["features"] if f["id"] == fid)

    def csv_status(self, fid: str, name: str) -> str:
        return next(r["status"] for r in self.rows
                    if r["feature"] == fid and r["characteristic"] == name)


def run(log: Path, spec: Path, tmp: Path,
        capsys: pytest.CaptureFixture[str]) -> Run:
    """Ingest and report; a spec with features the sample program lacks is read with
    ``--ignore-identity`` (the log is the one-sphere program's)."""
    out = tmp / "out"
    extra = ["--ignore-identity"] if "SPH2" in spec.read_text() else []
    code = main(["ingest", str(log), "--spec", str(spec), "-o", str(out), *extra])
    table = capsys.readouterr().out
    assert main(["report", str(out / "results.json"), "-o", str(tmp / "r.html")]) == 0
    doc = json.loads((out / "results.json").read_text())
    rows = list(csv.DictReader(io.StringIO((out / "results.csv").read_text())))
    return Run(code, table, doc, rows, (tmp / "r.html").read_text())


def test_complete_log_is_ok_and_green(tmp_path: Path,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    """The control: the untouched sample log with met limits is OK, 0 and green, so
    the checks below can fail."""
    r = run(LOG, sphere_spec(tmp_path), tmp_path, capsys)
    assert r.code == ExitCode.OK
    assert (r.doc["status"], r.doc["complete"]) == ("OK", True)
    assert r.feature("SPH1")["status"] == "OK"
    assert r.csv_status("SPH1", "P_FTU") == "OK" and r.csv_status("SPH1", "X") == "-"
    assert '<span class="badge ok" id="run-status">OK</span>' in r.html
    assert "status: OK\n" in r.table


def test_truncated_log_is_not_evaluated(tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    # the run stops after touch 19 of 25: no PGEND
    cut = tuple(f"PT SPH1 {k} " for k in range(20, 26)) + ("PGEND", "%")
    r = run(edited_log(tmp_path, drop=cut), sphere_spec(tmp_path), tmp_path, capsys)
    assert r.code == ExitCode.INCOMPLETE == 11
    assert (r.doc["status"], r.doc["complete"]) == ("NOT EVALUATED", False)
    f = r.feature("SPH1")
    assert (f["status"], f["ok"], f["reason"]) == ("NOT EVALUATED", None,
                                                    "no touch for points 20-25")
    chars = {c["name"]: c for c in f["characteristics"]}
    # the 19-point fit is shown for information, its verdicts are not
    assert chars["P_FTU"]["status"] == "NOT EVALUATED" and chars["P_FTU"]["ok"] is None
    assert chars["P_FTU"]["measured"] is not None and chars["X"]["status"] == "-"
    assert r.csv_status("SPH1", "D") == r.csv_status("SPH1", "P_STU") == "NOT EVALUATED"
    assert "SPH1: NOT EVALUATED: no touch for points 20-25" in r.table
    assert "status: NOT EVALUATED (the run did not finish)" in r.table
    assert "OK" not in [line.split()[-1] for line in r.table.splitlines() if line]
    assert GREEN not in r.html
    assert '<span class="badge ne" id="run-status">NOT EVALUATED</span>' in r.html


def test_no_contact_touch_is_not_evaluated(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    # touch 7 reported no contact after its logged position; the run went on to PGEND
    log = edited_log(tmp_path, after={"PT SPH1 7 ": "ERR NOTOUCH SPH1 7"})
    r = run(log, sphere_spec(tmp_path), tmp_path, capsys)
    assert r.code == ExitCode.INCOMPLETE
    assert (r.doc["status"], r.doc["complete"]) == ("NOT EVALUATED", True)
    f = r.feature("SPH1")
    assert f["status"] == "NOT EVALUATED"
    assert f["reason"].startswith("no contact at point 7 (ERR NOTOUCH, line ")
    assert r.csv_status("SPH1", "P_FTU") == "NOT EVALUATED"
    assert "SPH1: NOT EVALUATED: no contact at point 7" in r.table
    assert GREEN not in r.html


def test_run_stopped_at_its_first_touch(tmp_path: Path,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    """The machine alarmed on no contact at the first touch: NOT EVALUATED, 11."""
    log = tmp_path / "stopped.log"
    log.write_text("%\nPGSTART O1001 V1\nERR NOTOUCH SPH1 1\n")
    r = run(log, sphere_spec(tmp_path), tmp_path, capsys)
    assert r.code == ExitCode.INCOMPLETE
    assert (r.doc["status"], r.feature("SPH1")["status"]) == ("NOT EVALUATED",) * 2
    assert r.csv_status("SPH1", "P_FTU") == "NOT EVALUATED"
    assert GREEN not in r.html


def test_a_no_contact_touch_measured_again_counts(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """A program stopped by ERR NOTOUCH and resumed (a new PGSTART, docs/results.md "Log
    identity") that touched the point again: OK."""
    lines = LOG.read_text().splitlines()
    start = next(line for line in lines if line.startswith("PGSTART "))
    log = edited_log(tmp_path, after={"PT SPH1 6 ": f"ERR NOTOUCH SPH1 7\n{start}"})
    assert run(log, sphere_spec(tmp_path), tmp_path, capsys).code == ExitCode.OK


SECOND = ('\n[[feature]]\nid = "SPH2"\nkind = "sphere_test"\nat = [0.0, 0.0, 12.5]\n'
          'diameter = 25.0\nlayout = "octahedral"\n')


def test_toleranced_feature_without_touches_is_not_evaluated(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = sphere_spec(tmp_path, SECOND + "tolerance = { position = 0.05, form = 0.01 }\n")
    r = run(LOG, spec, tmp_path, capsys)
    assert r.code == ExitCode.INCOMPLETE
    assert r.doc["status"] == "NOT EVALUATED" and r.doc["complete"] is True
    assert r.feature("SPH1")["status"] == "OK"
    f = r.feature("SPH2")
    assert (f["status"], f["n"], f["reason"]) == ("NOT EVALUATED", 0,
                                                   "no touch for points 1-25")
    assert [(c["name"], c["upper"], c["measured"], c["status"])
            for c in f["characteristics"]] == [("POS", 0.05, None, "NOT EVALUATED"),
                                               ("P_FTU", 0.01, None, "NOT EVALUATED")]
    assert r.csv_status("SPH2", "POS") == "NOT EVALUATED"
    pos = next(line for line in r.table.splitlines() if line.startswith("SPH2 "))
    assert pos.split() == ["SPH2", "POS", "-", "-", "-", "<=", "0.0500", "NOT", "EVALUATED",
                           "-", "-"]
    html_sph2 = r.html.split('id="chars-SPH2"')[1].split("</table>")[0]
    assert '<span class="badge ne">NOT EVALUATED</span>' in html_sph2
    assert GREEN not in r.html.split('id="chars-SPH1"')[0]  # the run's badge is not green


def test_out_of_tolerance_wins_over_not_evaluated(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """Both at once: exit 8 and NOT OK (a definite finding, documented in cli_exit),
    the unmeasured feature still NOT EVALUATED."""
    spec = sphere_spec(tmp_path, SECOND + TOLERANCE, tolerance="tolerance = { form = 0.001 }\n")
    r = run(LOG, spec, tmp_path, capsys)
    assert r.code == ExitCode.NOT_OK
    assert r.doc["status"] == "NOT OK"
    assert (r.feature("SPH1")["status"], r.feature("SPH2")["status"]) == ("NOT OK",
                                                                           "NOT EVALUATED")
    assert GREEN not in r.html


@pytest.fixture(scope="module")
def toleranced_spec(tmp_path_factory: pytest.TempPathFactory) -> Any:
    from probegen.spec.model import load_spec

    return load_spec(sphere_spec(tmp_path_factory.mktemp("spec")))


@settings(max_examples=examples(40))
@given(dropped=st.sets(st.integers(1, 25)), blind=st.sets(st.integers(1, 25)),
       finished=st.booleans())
def test_only_a_whole_run_is_ok(toleranced_spec: Any, dropped: set[int], blind: set[int],
                                finished: bool) -> None:
    """Any mix of dropped touches, no-contact touches and a missing end: OK exactly when
    nothing is missing, else NOT EVALUATED (the sample meets its limits), or an error
    when no touch is left; never a traceback."""
    from probegen.evaluate.ingest import ingest
    from probegen.evaluate.outputs import to_csv, to_json

    out = []
    for line in LOG.read_text().splitlines():
        k = int(line.split()[2]) if line.startswith("PT SPH1 ") else 0
        if (k in dropped) or (line.startswith("PGEND") and not finished):
            continue
        out.append(line)
        if k in blind:
            out.append(f"ERR NOTOUCH SPH1 {k}")
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "run.log"
        log.write_text("\n".join(out) + "\n")
        try:
            ing = ingest(log, toleranced_spec)
        except ProbegenError as exc:
            assert len(dropped) == 25 and "found none usable" in str(exc)
            return
    whole = not dropped and not blind and finished
    assert ing.status == ("OK" if whole else "NOT EVALUATED")
    assert (json.loads(to_json(ing))["status"] == ing.status)
    assert ("NOT EVALUATED" in to_csv(ing)) == bool(dropped or blind)


def test_run_status_rule() -> None:
    assert run_status([True, None], not_evaluated=False, complete=True) == "OK"
    assert run_status([None], not_evaluated=False, complete=True) == "-"
    assert run_status([True], not_evaluated=False, complete=False) == "NOT EVALUATED"
    assert run_status([True], not_evaluated=True, complete=True) == "NOT EVALUATED"
    assert run_status([False, True], not_evaluated=True, complete=False) == "NOT OK"


def test_qif_marks_a_partial_sphere_not_analyzed(tmp_path: Path) -> None:
    cut = tuple(f"PT SPH1 {k} " for k in range(20, 26)) + ("PGEND",)
    spec = sphere_spec(tmp_path, tolerance="tolerance = { form = 0.01, position = 4.0 }\n")
    target = tmp_path / "r.qif"
    assert main(["qif", str(edited_log(tmp_path, drop=cut)), "--spec", str(spec),
                 "-o", str(target), "--validate", "--schema",
                 str(SHARED / "ref/qif/schema")]) == ExitCode.OK
    text = target.read_text()
    assert text.count("<CharacteristicStatusEnum>NOT_ANALYZED</CharacteristicStatusEnum>") == 2
    assert "<InspectionStatusEnum>NOT_MEASURED</InspectionStatusEnum>" in text
    assert "PASS" not in text
    full = tmp_path / "full.qif"
    assert main(["qif", str(LOG), "--spec", str(spec), "-o", str(full)]) == ExitCode.OK
    assert "<InspectionStatusEnum>PASS</InspectionStatusEnum>" in full.read_text()


# ------------------------------------------------------------------ lines and planes

FACES = """
[part]
model = "{repo}/samples/bore_block/bore_block.step"
units = "mm"

[machine]
profile = "{repo}/samples/machines/vmc-fanuc.toml"
clearance_z = 100.0

[program]
number = 1004
name = "FACES"

[[feature]]
id = "EDGE"
kind = "line"
at = [50.0, 0.0, 25.0]                  # the front face, y = 0, outward normal -Y
contacts = [[10.0, 0.0, 25.0], [50.0, 0.0, 25.0], [90.0, 0.0, 25.0]]
retract = 4.0
tolerance = {{ position = [-1.0, 1.0], angle = 1.0 }}

[[feature]]
id = "TOP"
kind = "plane"
at = [80.0, 80.0, 50.0]                 # the top face, z = 50
contacts = [[80.0, 20.0, 50.0], [80.0, 80.0, 50.0], [20.0, 80.0, 50.0], [30.0, 30.0, 50.0]]
retract = 4.0
tolerance = {{ position = [{low}, 0.5] }}
"""
SHIFT = np.array([1.234, -0.8, 0.3])
ANGLE = math.radians(0.5)


@pytest.fixture(scope="module")
def faces_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The lines-and-planes program run on the virtual machine: the part shifted by
    SHIFT and turned ANGLE about Z through its origin."""
    from probegen.dialects import get_dialect
    from probegen.machine.probe_model import ProbeModel
    from probegen.planning import plan_program
    from probegen.sim.contact import PlacedPart
    from probegen.sim.vm import VirtualMachine, run_text
    from probegen.spec.model import load_spec

    tmp = tmp_path_factory.mktemp("faces")
    spec = tmp / "faces.toml"
    spec.write_text(FACES.format(repo=REPO, low=-0.5))
    text = get_dialect("fanuc").generate(plan_program(load_spec(spec),
                                                      runtime_variables=True).program)
    c, s = math.cos(ANGLE), math.sin(ANGLE)
    part = PlacedPart.from_model(cad.load_step(REPO / "samples/bore_block/bore_block.step"),
                                 rotation=np.array([[c, -s, 0.0], [s, c, 0.0], [0, 0, 1.0]]),
                                 translation=SHIFT)
    res = run_text(text, VirtualMachine(part, ProbeModel(3.0)), kind="macrob")
    assert res.alarm is None and "PGEND" in res.output
    log = tmp / "faces.log"
    log.write_text(res.output)
    return log


def faces_spec(tmp: Path, low: float = -0.5) -> Path:
    path = tmp / "faces.toml"
    path.write_text(FACES.format(repo=REPO, low=low))
    return path


def test_lines_and_planes_alone_are_ingested(faces_log: Path, tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    r = run(faces_log, faces_spec(tmp_path), tmp_path, capsys)
    assert r.code == ExitCode.OK and r.doc["status"] == "OK"
    edge, top = r.feature("EDGE"), r.feature("TOP")
    assert (edge["kind"], edge["status"], top["kind"], top["status"]) == (
        "line", "OK", "plane", "OK")
    e = {c["name"]: c for c in edge["characteristics"]}
    t = {c["name"]: c for c in top["characteristics"]}
    # the planted truth: the top 0.3 mm high; the front face (outward -Y) moved out by
    # 0.8 and turned 0.5 deg about the part origin, so at the contacts' mean x (50) it
    # stands 0.8 - (50 - 1.234)·tan(0.5°) out; the ball's cosine error is 1.1e-4 mm
    assert t["DIST"]["measured"] == pytest.approx(SHIFT[2], abs=1e-4)
    assert e["DIST"]["measured"] == pytest.approx(
        -SHIFT[1] - (50.0 - SHIFT[0]) * math.tan(ANGLE), abs=2e-4)
    assert e["ANGLE"]["deviation"] == pytest.approx(0.5, abs=1e-4)
    assert e["FORM"]["measured"] < 1e-4 and t["FORM"]["measured"] < 1e-4
    assert (t["DIST"]["lower"], t["DIST"]["upper"], e["ANGLE"]["upper"]) == (-0.5, 0.5, 1.0)
    assert r.csv_status("TOP", "DIST") == "OK" and r.csv_status("EDGE", "FORM") == "-"
    assert "TOP      DIST" in r.table and '<table class="chars" id="chars-EDGE">' in r.html
    assert "(line, plane): distance of each contact point" in r.html
    assert "from the least-squares sphere" not in r.html
    assert '<span class="badge ok" id="run-status">OK</span>' in r.html


def test_plane_out_of_tolerance(faces_log: Path, tmp_path: Path,
                                capsys: pytest.CaptureFixture[str]) -> None:
    r = run(faces_log, faces_spec(tmp_path, low=0.35), tmp_path, capsys)  # 0.3 < 0.35
    assert r.code == ExitCode.NOT_OK
    assert r.feature("TOP")["status"] == "NOT OK" and r.csv_status("TOP", "DIST") == "NOT OK"


def test_a_face_cut_short_is_not_evaluated(faces_log: Path, tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    kept = [line for line in faces_log.read_text().splitlines()
            if not line.startswith(("PT TOP 4", "PGEND"))]
    log = tmp_path / "cut.log"
    log.write_text("\n".join(kept) + "\n")
    r = run(log, faces_spec(tmp_path), tmp_path, capsys)
    assert r.code == ExitCode.INCOMPLETE
    assert r.feature("EDGE")["status"] == "OK"
    top = r.feature("TOP")
    assert (top["status"], top["reason"]) == ("NOT EVALUATED", "no touch for point 4")
    assert [(c["name"], c["status"]) for c in top["characteristics"]] == [
        ("DIST", "NOT EVALUATED")]
    assert GREEN not in r.html.split('id="chars-TOP"')[1].split("</table>")[0]


# ------------------------------------------------------------------------ post-ingest

def test_post_ingest_of_a_run_cut_short(tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    from probegen.dmis.reader import parse_dmis
    from probegen.machine.profile import load_profile
    from probegen.post.featuremap import dumps, feature_map
    from probegen.post.frontend import post_dmis

    program = SHARED / "ref/nist-ippdme/IPlusSimplePart/DMIS/simple_in.dms"
    text = program.read_text()
    profile = load_profile(REPO / "samples/post/vmc-fanuc-d4.toml")
    fmap = tmp_path / "simple.features.json"
    fmap.write_text(dumps(feature_map(post_dmis(parse_dmis(text), profile), text,
                                      "simple_in.dms", "fanuc")))
    touches = ("PGSTART O1001 V1\nPT ACIRCLE 1 X73.0000 Y50.0000 Z40.0000\n"
               "PT ACIRCLE 2 X27.0000 Y50.0000 Z40.0000\n"
               "PT ACIRCLE 3 X50.0000 Y73.0000 Z40.0000\n")
    fourth = "PT ACIRCLE 4 X50.0000 Y27.0000 Z40.0000\n"
    cases = [(touches + fourth + "PGEND O1001\n", ExitCode.OK, "status: -"),
             (touches + fourth, ExitCode.INCOMPLETE, "status: NOT EVALUATED (the run did "),
             (touches + fourth + "ERR NOTOUCH ACIRCLE 4\nPGEND O1001\n",
              ExitCode.INCOMPLETE, "status: NOT EVALUATED"),
             (touches, ExitCode.INCOMPLETE, "NOT EVALUATED, the log has no PGEND"),
             (touches + "ERR NOTOUCH ACIRCLE 4\n", ExitCode.INCOMPLETE,
              "NOT EVALUATED, no contact (ERR NOTOUCH, line 5)")]
    for log_text, code, said in cases:
        log = tmp_path / "run.log"
        log.write_text(log_text)
        assert main(["post-ingest", str(log), "--features", str(fmap),
                     "-o", str(tmp_path / "out.dmo")]) == code, log_text
        shown = capsys.readouterr()
        assert said in shown.out + shown.err, log_text
