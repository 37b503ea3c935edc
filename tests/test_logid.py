"""The log belongs to its program: identity on PGSTART, the run used, unknown and duplicate
point ids, corrupt and implausible values (issue 15, item 3; docs/results.md "Log identity")."""

from __future__ import annotations

import dataclasses
import functools
import json
import re
from pathlib import Path

import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate

from probegen.cli.app import ExitCode, main
from probegen.dialects import get_dialect
from probegen.errors import ProbegenError
from probegen.evaluate.ingest import ingest
from probegen.ir.identity import PlannedTouch
from probegen.planning import plan_program
from probegen.planning.identity import planned_touches
from probegen.results import parse_dprnt
from probegen.results.logcheck import PLAUSIBLE_MARGIN, check_log
from probegen.spec.model import Spec, load_spec

SPEC = REPO / "samples/sphere25/sphere_test.toml"
LOG_TEXT = (REPO / "samples/sphere25/sphere_test.log").read_text()
IDENTITY = re.search(r"PGSTART O1001 V1 (H[0-9A-F]{8})\n", LOG_TEXT)
assert IDENTITY is not None
ID = IDENTITY.group(1)
BODY = LOG_TEXT.split(f"PGSTART O1001 V1 {ID}\n")[1].split("PGEND O1001\n")[0]


@functools.cache
def _spec() -> Spec:
    return load_spec(SPEC)


@functools.cache
def _planned() -> tuple[str, tuple[PlannedTouch, ...]]:
    planned = plan_program(_spec(), runtime_variables=True, check_collisions=False)
    return planned.program.setup.identity, planned_touches(planned.program,
                                                           planned.sphere_tests)


def _run(body: str = BODY, *, end: bool = True, identity: str = ID, number: int = 1001) -> str:
    head = f"PGSTART O{number:04d} V1 {identity}\n" if identity else f"PGSTART O{number} V1\n"
    return head + body + (f"PGEND O{number:04d}\n" if end else "")


def _ingest(tmp_path: Path, text: str, **kw: object) -> object:
    log = tmp_path / "run.log"
    log.write_text(text)
    return ingest(log, _spec(), **kw)  # type: ignore[arg-type]


# --- the identity the programs print ---------------------------------------------------


def test_every_dprnt_dialect_prints_the_plan_identity() -> None:
    identity, _ = _planned()
    assert re.fullmatch(r"H[0-9A-F]{8}", identity) and identity == ID
    program = plan_program(_spec(), runtime_variables=True).program
    lines = {name: next(ln for ln in get_dialect(name).generate(program).splitlines()
                        if "PGSTART" in ln) for name in ("fanuc", "haas", "linuxcnc")}
    assert lines == {"fanuc": f"DPRNT[PGSTART*O1001*V1*{ID}]",
                     "haas": f"DPRNT[PGSTART*O1001*V1*{ID}]",
                     "linuxcnc": f"(LOG,PGSTART O1001 V1 {ID})"}
    assert "PGSTART" not in get_dialect("dmis").generate(
        plan_program(_spec(), runtime_variables=False).program)


def test_identity_follows_the_program_not_offline_tolerances(tmp_path: Path) -> None:
    text = SPEC.read_text().replace('"../machines', f'"{REPO}/samples/machines').replace(
        '"sphere25.step"', f'"{REPO}/samples/sphere25/sphere25.step"')

    def identity(spec_text: str) -> str:
        path = tmp_path / "s.toml"
        path.write_text(spec_text)
        return plan_program(load_spec(path), runtime_variables=True,
                            check_collisions=False).program.setup.identity

    assert identity(text) == ID  # moved files and comments do not count
    assert identity(text + "tolerance = { form = 0.001 }\n") == ID  # evaluated offline
    assert identity(text.replace("number = 1001", "number = 1002")) != ID
    changed = re.sub(r"diameter = 25\.0\b", "diameter = 25.5", text)
    assert changed != text and identity(changed) != ID


# --- identity checks ----------------------------------------------------------------------


def test_another_program_number_is_refused_naming_both(tmp_path: Path) -> None:
    with pytest.raises(ProbegenError, match=rf"run.log:1: expected the program of the spec, "
                                            rf"O1001 {ID}, found O1002 {ID}"):
        _ingest(tmp_path, _run(number=1002))


def test_another_identity_is_refused_and_can_be_overridden(tmp_path: Path) -> None:
    other = "H0000BEEF"
    with pytest.raises(ProbegenError, match=f"O1001 {ID}, found O1001 {other}"):
        _ingest(tmp_path, _run(identity=other))
    result = _ingest(tmp_path, _run(identity=other), ignore_identity=True)
    assert any(n.startswith("WARNING: identity not checked") and other in n
               for n in result.notes)  # type: ignore[attr-defined]
    out = tmp_path / "out"
    code = main(["ingest", str(tmp_path / "run.log"), "--spec", str(SPEC), "-o", str(out),
                 "--ignore-identity", "--write-calibration", str(tmp_path / "cal.toml")])
    assert code != ExitCode.OK and not (tmp_path / "cal.toml").exists()
    notes = json.loads((out / "results.json").read_text())["notes"]
    assert any(n.startswith("WARNING: identity not checked") for n in notes)


def test_a_log_without_identity_is_read_with_a_note(tmp_path: Path) -> None:
    result = _ingest(tmp_path, _run(identity=""))
    assert result.notes[-1].startswith("log carries no program identity")  # type: ignore[attr-defined]
    assert len(result.results[0].points) == 25  # type: ignore[attr-defined]


# --- several runs in one file -------------------------------------------------------------


def _shifted(body: str, dx: float) -> str:
    """The body with every PT X moved by ``dx`` (another measurement of the same part)."""
    def move(m: re.Match[str]) -> str:
        return f"{m.group(1)}X{float(m.group(2)) + dx:.4f}"
    return re.sub(r"^(PT .*?)X(-?[0-9.]+)", move, body, flags=re.M)


def test_the_last_complete_run_is_used_and_run_n_chooses(tmp_path: Path) -> None:
    text = _run(_shifted(BODY, 0.01)) + _run()
    last = _ingest(tmp_path, text)
    first = _ingest(tmp_path, text, run=1)
    x_last = last.results[0].fit.centre[0]  # type: ignore[attr-defined]
    x_first = first.results[0].fit.centre[0]  # type: ignore[attr-defined]
    assert x_first - x_last == pytest.approx(0.01, abs=2e-4)
    assert last.notes[0].startswith("the log holds 2 runs (PGSTART at lines 1, 35); using "  # type: ignore[attr-defined]
                                    "run 2 (line 35 to PGEND at line 68), the last complete")
    with pytest.raises(ProbegenError, match="--run 3: expected a run from 1 to 2"):
        _ingest(tmp_path, text, run=3)


def test_a_cut_short_run_after_a_complete_one_is_named(tmp_path: Path) -> None:
    half = "".join(BODY.splitlines(keepends=True)[:12])
    result = _ingest(tmp_path, _run() + _run(_shifted(half, 0.5), end=False))
    assert result.log.complete and len(result.results[0].points) == 25  # type: ignore[attr-defined]
    assert any(n.startswith("run 2 after it (from line 35, no PGEND) was cut short")
               for n in result.notes)  # type: ignore[attr-defined]


def test_a_resumed_run_repeats_points_and_counts_once(tmp_path: Path) -> None:
    lines = BODY.splitlines(keepends=True)
    cut = _run("".join(lines[:20]), end=False)
    resumed = _run("".join(lines[15:]))  # re-prints 5 points after a new PGSTART
    result = _ingest(tmp_path, cut + resumed)
    assert len(result.results[0].points) == 25  # type: ignore[attr-defined]
    assert any(n.startswith("run 2 resumes run 1") for n in result.notes)  # type: ignore[attr-defined]


# --- point ids --------------------------------------------------------------------------------


@pytest.mark.parametrize(("record", "message"), [
    ("PT SPH9 1 X0 Y0 Z0", r"run.log:34: PT SPH9 1: expected a PT point of a feature of the "
                           r"plan \(SPH1\), found feature SPH9"),
    ("PT SPH1 26 X0 Y0 Z0", r"run.log:34: PT SPH1 26: expected a PT index the plan has for "
                            r"SPH1 \(1-25\), found 26"),
    ("LOC SPH1 9 X0 Y0 Z0", r"run.log:34: LOC SPH1 9: expected a LOC index the plan has"),
])
def test_unknown_point_ids_are_refused(tmp_path: Path, record: str, message: str) -> None:
    with pytest.raises(ProbegenError, match=message):
        _ingest(tmp_path, _run(BODY + record + "\n"))


def test_a_point_twice_in_one_run_is_refused(tmp_path: Path) -> None:
    first = next(ln for ln in BODY.splitlines() if ln.startswith("PT SPH1 3 "))
    line = 1 + BODY.splitlines().index(first) + 1
    with pytest.raises(ProbegenError, match=rf"run.log:34: PT SPH1 3: printed twice in one "
                                            rf"run \(first at line {line}\)"):
        _ingest(tmp_path, _run(BODY + first + "\n"))


# --- corrupt and implausible values -----------------------------------------------------------


def _corrupt(point: int, repl: str) -> tuple[str, int]:
    lines = BODY.splitlines(keepends=True)
    k = next(i for i, ln in enumerate(lines) if ln.startswith(f"PT SPH1 {point} "))
    lines[k] = re.sub(r"X(-?)", repl, lines[k], count=1)
    return _run("".join(lines)), k + 2


def test_a_corrupt_value_is_named_and_the_other_lines_kept(tmp_path: Path) -> None:
    text, line = _corrupt(7, r"X\g<1>1.2.")
    result = _ingest(tmp_path, text)
    (diag,) = result.log.diagnostics  # type: ignore[attr-defined]
    assert (diag.source, diag.line, diag.column) == (str(tmp_path / "run.log"), line, 16)
    assert "feature SPH1: no touch for points 7" in result.notes  # type: ignore[attr-defined]
    assert "SPH1" in result.incomplete
    (partial,) = (n.partial for n in result.not_evaluated)  # type: ignore[attr-defined]
    assert len(partial.points) == 24  # NOT EVALUATED, the partial fit for information


def test_a_value_that_cannot_be_the_touch_writes_no_calibration(tmp_path: Path) -> None:
    """Issue 15: one corrupt coordinate gave an effective radius of 50 m."""
    text, line = _corrupt(7, r"X\g<1>5000")
    log = tmp_path / "run.log"
    log.write_text(text)
    result = ingest(log, _spec())
    (diag,) = result.log.diagnostics
    assert (diag.line, diag.column) == (line, 11) and "cannot be that touch" in diag.message
    assert str(diag).endswith("    PT SPH1 7 X-50008.1488 Y-10.1488 Z9.2984\n              ^")
    assert not result.results  # NOT EVALUATED: a touch was refused
    (partial,) = (n.partial for n in result.not_evaluated)
    assert partial.effective_radius == pytest.approx(3.0, abs=0.01)
    cal = tmp_path / "cal.toml"
    code = main(["ingest", str(log), "--spec", str(SPEC), "-o", str(tmp_path / "out"),
                 "--write-calibration", str(cal)])
    assert code != ExitCode.OK and not cal.exists()


def test_a_touch_on_its_search_line_is_plausible() -> None:
    _, touches = _planned()
    t = touches[-1]
    mid = tuple((a + b) / 2.0 for a, b in zip(t.start, t.end, strict=True))
    assert t.distance(mid) == pytest.approx(0.0, abs=1e-12)  # type: ignore[arg-type]
    off = (mid[0], mid[1], mid[2] + PLAUSIBLE_MARGIN + t.uncertainty + 1.0)
    assert t.distance(off) > PLAUSIBLE_MARGIN + t.uncertainty


# --- properties: appended runs, unknown ids, corrupted values ---------------------------------

ALPHABET = "PGSTARTENDLOCXYZH0123456789.-+ %\nABCDEF"
RECORDS = BODY.splitlines()


@st.composite
def appended_runs(draw: st.DrawFn) -> str:
    """One to four runs of the sample, each cut or complete, some with ids renumbered."""
    out = []
    for _ in range(draw(st.integers(1, 4))):
        body = draw(st.lists(st.sampled_from(RECORDS), max_size=8))
        if draw(st.booleans()):  # renumber: unknown and duplicate ids
            shift = draw(st.integers(0, 30))
            body = [re.sub(r" (\d+) X", lambda m, k=shift: f" {int(m.group(1)) + k} X", ln,
                           count=1)
                    for ln in body]
        out.append(_run("".join(ln + "\n" for ln in body), end=draw(st.booleans()),
                        identity=draw(st.sampled_from([ID, "", "H0000BEEF"]))))
    return "".join(out)


def _check_or_refuse(text: str, run: int | None = None) -> None:
    identity, touches = _planned()
    log = parse_dprnt(text, source="p.log")
    try:
        checked = check_log(log, program=1001, identity=identity, touches=touches, run=run)
    except ProbegenError as exc:
        assert str(exc).startswith(("p.log", "--run"))
        return
    keys = {(t.kind, t.feature, t.index) for t in touches}
    assert all((t.kind, t.feature, t.index) in keys for t in checked.log.touches)
    per_run = [(t.run, t.kind, t.feature, t.index) for t in checked.log.touches]
    assert len(per_run) == len(set(per_run))
    assert {t.run for t in checked.log.touches} <= {r.number for r in checked.log.runs}


PROPERTY = settings(max_examples=examples(60), suppress_health_check=[HealthCheck.too_slow])


@PROPERTY
@given(appended_runs(), st.one_of(st.none(), st.integers(0, 5)))
def test_appended_runs_give_a_result_or_a_probegen_error(text: str, run: int | None) -> None:
    _check_or_refuse(text, run)


@st.composite
def mutated_run(draw: st.DrawFn) -> str:
    return mutate(draw, _run() + _run(end=False), ALPHABET, most=12)


@PROPERTY
@given(mutated_run())
def test_mutated_logs_give_a_result_or_a_probegen_error(text: str) -> None:
    _check_or_refuse(text)


@settings(max_examples=examples(8), suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(1, 25), st.sampled_from(["X", "Y", "Z"]), st.floats(-1e6, 1e6))
def test_ingest_of_a_changed_coordinate_never_crashes(tmp_path_factory: pytest.TempPathFactory,
                                                      point: int, axis: str,
                                                      value: float) -> None:
    lines = BODY.splitlines(keepends=True)
    k = next(i for i, ln in enumerate(lines) if ln.startswith(f"PT SPH1 {point} "))
    lines[k] = re.sub(rf"{axis}-?[0-9.]+", f"{axis}{value:.4f}", lines[k])
    log = tmp_path_factory.mktemp("m") / "m.log"
    log.write_text(_run("".join(lines)))
    try:
        result = ingest(log, _spec())
    except ProbegenError:
        return
    r = result.results[0] if result.results else result.not_evaluated[0].partial
    assert r is not None and r.effective_radius == pytest.approx(3.0, abs=0.5)  # never 50 m
    assert dataclasses.is_dataclass(result)


def test_a_log_without_pgstart_is_noted() -> None:
    identity, touches = _planned()
    log = parse_dprnt(BODY + "PGEND O1001\n", source="late.log")
    checked = check_log(log, program=1001, identity=identity, touches=touches)
    assert checked.notes[-1].startswith("log carries no program identity (no PGSTART line")
    assert log.diagnostics[0].message.startswith("expected the PGSTART header")
    assert len(checked.log.touches) == len(log.touches)
