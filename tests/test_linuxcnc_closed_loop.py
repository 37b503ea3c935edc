"""Closed loop in the LinuxCNC dialect: every sample spec's LinuxCNC program runs on the
virtual machine's LinuxCNC control (``sim/ngc``) and measures as the Fanuc program does.

Planted truth as in test_haas_closed_loop.py: the part 0.03, -0.02, 0.01 mm off the G54
origin (G54 at 300, 200, -100 mm), turned 0.05 degrees about Z, a probe with lobing, the
bore_block specs on a block whose bore is 0.03 mm oversize.

Tolerance: the touches (ball centre where it first meets the part) within 1e-6 mm; the
logs' records and ``results.json`` exactly.  The two programs command the same points:
the LinuxCNC program writes the constants the Fanuc program writes (4 decimals) and
does the same run-time arithmetic, only in named parameters; rs274ngc's ``%.4f`` and
DPRNT's ``[44]`` round the same doubles the same way.  The differences between the
logs are in form only (DPRNT's ``%`` lines and its suppressed leading zeros), so the
records parse to the same numbers.  That the Fanuc results are right against the
planted truth is checked again here for the sphere test (test_closed_loop.py's
expected fit from the planted centre and the probe's pre-travel).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, assert_golden
from test_closed_loop import LOBING as SPHERE_LOBING
from test_closed_loop import OFFSET, expected_fit, program_text
from test_haas_closed_loop import LOBING, WORK, oversize_bore_block, placed_part  # noqa: F401
from test_linuxcnc import SPECS

from probegen import cad
from probegen.dialects import get_dialect
from probegen.evaluate.ingest import ingest
from probegen.evaluate.outputs import to_json
from probegen.machine.probe_model import ProbeModel
from probegen.planning import plan_program
from probegen.results import parse_dprnt
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import SimResult, VirtualMachine, run_text
from probegen.spec.model import Spec, load_spec

TOUCH_TOL = 1e-6


def test_the_linuxcnc_samples_are_all_here() -> None:
    """Every sample spec without in-process decisions (LinuxCNC refuses those)."""
    names = {p.stem for p in SPECS}
    assert {"sphere_test", "sphere_test_iso", "sphere_test_cap", "bore_block",
            "revolved_block", "freeform"} <= names
    assert len(SPECS) == 7


def run(text: str, part: PlacedPart, ball: float, kind: str) -> tuple[SimResult, np.ndarray]:
    """A run and the ball centres of its touches (machine coordinates)."""
    vm = VirtualMachine(part, ProbeModel(ball, LOBING))
    res = run_text(text, vm, kind=kind, work_offset=WORK)
    return res, np.array([hit.point for hit in vm.touches])


def results(output: str, spec: Spec, folder: Path) -> dict[str, object]:
    """``results.json`` of a log, without its path and the file's time."""
    folder.mkdir()
    log = folder / "run.log"
    log.write_text(output, encoding="ascii")
    doc = json.loads(to_json(ingest(log, spec)))
    doc.pop("source")
    doc.get("run", {}).pop("time", None)
    return dict(doc)


def records(output: str) -> list[tuple[object, ...]]:
    """A log's touches and centres as (kind, feature, index, xyz), numbers as parsed."""
    log = parse_dprnt(output, strict=True)
    assert log.complete and not log.errors
    return ([(t.kind, t.feature, t.index, t.xyz) for t in log.touches]
            + [("CTR", c.feature, 0, c.xyz) for c in log.centres])


@pytest.mark.parametrize("spec_path", SPECS, ids=lambda p: p.stem)
def test_linuxcnc_program_measures_as_the_fanuc_program(
        spec_path: Path, oversize_bore_block: cad.Model, tmp_path: Path) -> None:  # noqa: F811
    spec = load_spec(spec_path)
    program = plan_program(spec, runtime_variables=True).program
    fanuc_text, ngc_text = (get_dialect(d).generate(program) for d in ("fanuc", "linuxcnc"))
    part = placed_part(spec, oversize_bore_block)
    ball = spec.machine.probe.ball_radius
    fanuc, fanuc_touches = run(fanuc_text, part, ball, "macrob")
    ngc, ngc_touches = run(ngc_text, part, ball, "ngc")
    assert fanuc.alarm is None and ngc.alarm is None, (fanuc.alarm, ngc.alarm)
    assert ngc.touches == fanuc.touches > 0
    assert np.abs(ngc_touches - fanuc_touches).max() < TOUCH_TOL
    assert "PGEND" in ngc.output and not ngc.output.startswith("%")
    assert records(ngc.output) == records(fanuc.output)
    ngc_doc = results(ngc.output, spec, tmp_path / "linuxcnc")
    assert ngc_doc == results(fanuc.output, spec, tmp_path / "fanuc")
    assert ngc_doc["complete"] and ngc_doc["features"]


def test_linuxcnc_sphere_test_recovers_the_planted_sphere(in_repo: Path, tmp_path: Path) -> None:
    """The sphere test on the model, shifted and turned, with lobing: the fitted sphere is
    the one the planted centre and the probe's pre-travel give (test_closed_loop.py)."""
    text, planned = program_text("sphere_test.toml", "linuxcnc")
    probe = ProbeModel(3.0, SPHERE_LOBING)
    c, s = np.cos(np.radians(0.5)), np.sin(np.radians(0.5))
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    model = cad.load_step(REPO / "samples/sphere25/sphere25.step")
    vm = VirtualMachine(PlacedPart.from_model(model, rotation=rot, translation=OFFSET), probe)
    res = run_text(text, vm, kind="ngc")
    assert res.alarm is None and res.touches == 31
    log = tmp_path / "probegen-1001.log"
    log.write_text(res.output)
    (r,) = ingest(log, load_spec(Path("samples/sphere25/sphere_test.toml"))).results
    dirs = np.array(planned.sphere_tests[0].directions)  # type: ignore[attr-defined]
    centre, diameter, form = expected_fit(OFFSET, 12.5, dirs, probe)
    assert np.allclose(r.fit.centre, centre, atol=1e-4)
    assert 2 * r.fit.radius == pytest.approx(diameter, abs=1e-4)
    assert r.p_ftu == pytest.approx(form, abs=1e-4)


def test_missed_touch_stops_the_linuxcnc_program(in_repo: Path) -> None:
    """G38.2 without contact is LinuxCNC's own error: no ERR line, no PGEND."""
    text, _ = program_text("sphere_test_iso.toml", "linuxcnc")
    part = PlacedPart.from_spheres([[0.0, 0.0, 0.0]], [12.5 - 3.0])  # far smaller: no touch
    res = run_text(text, VirtualMachine(part, ProbeModel(3.0)), kind="ngc")
    assert res.alarm is not None
    assert res.alarm.startswith("9302 G38.2 probe move finished without contact (line ")
    assert "PGSTART" in res.output and "PGEND" not in res.output and "ERR" not in res.output
    assert not parse_dprnt(res.output).complete


def test_unexpected_contact_aborts_the_linuxcnc_program(in_repo: Path) -> None:
    text, _ = program_text("sphere_test_iso.toml", "linuxcnc")
    part = PlacedPart.from_spheres([[0.0, 0.0, 0.0], [0.0, 0.0, 40.0]], [12.5, 5.0])
    res = run_text(text, VirtualMachine(part, ProbeModel(3.0)), kind="ngc")
    assert res.alarm is not None
    assert res.alarm.startswith("9301 UNEXPECTED PROBE TRIGGER SPH1 1 (line ")
    assert res.output.splitlines()[-1] == "ERR COLLISION SPH1 1"


def test_a_g92_offset_stops_the_program_before_it_moves(in_repo: Path) -> None:
    """The program's #5210 check: with a G92 offset applied it aborts, touching nothing."""
    text, _ = program_text("sphere_test_iso.toml", "linuxcnc")
    part = PlacedPart.from_spheres([[0.0, 0.0, 0.0]], [12.5])
    shifted = text.replace("G54\n", "G54\nG92 X1\n", 1)
    res = run_text(shifted, VirtualMachine(part, ProbeModel(3.0)), kind="ngc")
    assert res.alarm is not None and res.alarm.startswith("9301 G92/G52 OFFSET IS APPLIED")
    assert res.touches == 0 and res.output == ""


# -- the compact form: o<pg_move>/o<pg_touch> calls to the macro library -----------------
GOLDEN = REPO / "tests/golden/linuxcnc_library"


def compact_forms(spec_path: Path) -> tuple[str, str]:
    """The inline and the compact LinuxCNC program of a spec."""
    program = plan_program(load_spec(spec_path), runtime_variables=True).program
    d = get_dialect("linuxcnc")
    inline = d.generate(program)
    d.compact = True
    return inline, d.generate(program)


def test_compact_program_and_library_match_golden(in_repo: Path) -> None:
    _, compact = compact_forms(Path("samples/sphere25/sphere_test.toml"))
    assert_golden(GOLDEN / "sphere_test.compact.ngc", compact)
    for name, text in get_dialect("linuxcnc").library_files(8000, 100, "mm").items():
        assert_golden(GOLDEN / name, text)
    assert "G38." not in compact and compact.count("o<pg_touch> call") == 31


@pytest.mark.parametrize("spec_path", SPECS, ids=lambda p: p.stem)
def test_compact_measures_as_inline(spec_path: Path, oversize_bore_block: cad.Model,  # noqa: F811
                                    tmp_path: Path) -> None:
    inline_text, compact_text = compact_forms(spec_path)
    assert len(compact_text) < len(inline_text)
    for name, text in get_dialect("linuxcnc").library_files(8000, 100, "mm").items():
        (tmp_path / name).write_text(text, encoding="ascii")
    spec = load_spec(spec_path)
    part = placed_part(spec, oversize_bore_block)
    ball = spec.machine.probe.ball_radius
    inline, inline_touches = run(inline_text, part, ball, "ngc")
    vm = VirtualMachine(part, ProbeModel(ball, LOBING))
    compact = run_text(compact_text, vm, kind="ngc", work_offset=WORK, program_dir=tmp_path)
    assert inline.alarm is None and compact.alarm is None, (inline.alarm, compact.alarm)
    assert compact.touches == inline.touches > 0
    assert np.array_equal(np.array([h.point for h in vm.touches]), inline_touches)
    assert compact.output == inline.output and "PGEND" in compact.output


def test_compact_unexpected_trigger_logs_and_aborts_as_inline(in_repo: Path,
                                                             tmp_path: Path) -> None:
    inline_text, compact_text = compact_forms(Path("samples/sphere25/sphere_test_iso.toml"))
    for name, text in get_dialect("linuxcnc").library_files(8000, 100, "mm").items():
        (tmp_path / name).write_text(text, encoding="ascii")
    part = PlacedPart.from_spheres([[0.0, 0.0, 0.0], [0.0, 0.0, 40.0]], [12.5, 5.0])
    inline = run_text(inline_text, VirtualMachine(part, ProbeModel(3.0)), kind="ngc")
    compact = run_text(compact_text, VirtualMachine(part, ProbeModel(3.0)), kind="ngc",
                       program_dir=tmp_path)
    assert compact.output == inline.output and compact.output.endswith("ERR COLLISION SPH1 1\n")
    assert inline.alarm is not None and compact.alarm is not None
    assert compact.alarm.split(" (line")[0] == inline.alarm.split(" (line")[0]


def test_cli_compile_compact_sim_and_macros(in_repo: Path, tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    """compile --compact -d linuxcnc writes pg_move.ngc and pg_touch.ngc beside the
    program; sim (by the .ngc name, or --control linuxcnc) finds them there or through
    --library, and logs what the inline program logs; macros writes the same files."""
    from probegen.cli.app import main
    from probegen.errors import ExitCode

    spec = "samples/sphere25/sphere_test.toml"
    out, inline = tmp_path / "c", tmp_path / "i"
    assert main(["compile", spec, "--compact", "-d", "linuxcnc", "-o", str(out)]) == 0
    assert main(["compile", spec, "-d", "linuxcnc", "-o", str(inline)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["pg_move.ngc", "pg_touch.ngc",
                                                        "sphere_test.ngc"]
    assert sorted(p.name for p in inline.iterdir()) == ["sphere_test.ngc"]
    logs = []
    for folder in (out, inline):
        logs.append(tmp_path / f"{folder.name}.log")
        assert main(["sim", str(folder / "sphere_test.ngc"), "--spec", spec,
                     "-o", str(logs[-1])]) == ExitCode.OK
    assert logs[0].read_text() == logs[1].read_text() and "PGEND" in logs[0].read_text()
    alone = tmp_path / "alone"
    alone.mkdir()
    (alone / "p.txt").write_text((out / "sphere_test.ngc").read_text())
    capsys.readouterr()
    assert main(["sim", str(alone / "p.txt"), "--control", "linuxcnc", "--spec", spec,
                 "-o", str(tmp_path / "x.log")]) == ExitCode.SIM_ALARM
    assert "Unable to open file for subroutine o<pg_move>" in capsys.readouterr().err
    assert main(["sim", str(alone / "p.txt"), "--control", "linuxcnc", "--library", str(out),
                 "--spec", spec, "-o", str(tmp_path / "y.log")]) == ExitCode.OK
    assert (tmp_path / "y.log").read_text() == logs[1].read_text()
    assert main(["macros", "-d", "linuxcnc", "-o", str(tmp_path / "m")]) == 0
    for name in ("pg_move.ngc", "pg_touch.ngc"):
        assert (tmp_path / "m" / name).read_text() == (out / name).read_text()


@pytest.mark.parametrize("name", ["m4", "pivot"])
def test_rotary_programs_measure_as_the_fanuc_ones(name: str) -> None:
    """The M4 rotary-axis programs (``G53 G0 B.. C..``, samples/rotary) on the five-axis
    B/C machine with planted location errors and lobing: the Fanuc program's touches."""
    from test_rotary_closed_loop import ERRORS, plan

    from probegen.machine.kinematics import Machine, Topology
    from probegen.machine.probe_model import Lobing

    p = plan(name)
    spec = p.spec
    found = []
    for dialect, kind in (("fanuc", "macrob"), ("linuxcnc", "ngc")):
        vm = VirtualMachine(
            PlacedPart.from_spheres([spec.sphere_centre], [spec.sphere_radius]),
            ProbeModel(spec.machine.probe.ball_radius, Lobing(0.004, 0.0015)),
            Machine(Topology.FIVE_AXIS_BC, ERRORS, spec.pivot_length))
        res = run_text(get_dialect(dialect).generate(p.program), vm, kind=kind)
        assert res.alarm is None, res.alarm
        found.append((records(res.output), np.array([h.point for h in vm.touches])))
    (fanuc, fanuc_touches), (ngc, ngc_touches) = found
    assert ngc == fanuc and len(ngc) == len(ngc_touches) > 10
    assert np.abs(ngc_touches - fanuc_touches).max() < TOUCH_TOL
