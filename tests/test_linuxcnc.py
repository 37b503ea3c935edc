"""The LinuxCNC dialect, checked by LinuxCNC's own standalone interpreter ``rs274``.

``rs274 -g`` reads a program and prints the canonical machining commands it would send
(``STRAIGHT_TRAVERSE``, ``STRAIGHT_FEED``, ``STRAIGHT_PROBE``, ``SET_FEED_RATE``,
``LOG``).  It has no probe: after ``G38.2``/``G38.3`` it sets ``#5061-#5063`` to the
programmed end point and ``#5070`` to 0, as LinuxCNC does after a probe move that never
tripped (observed with rs274 2.9.0~pre1).  So in standalone mode every protected move
passes its check, every touch "misses" without error (the error for a missed ``G38.2``
comes from the motion controller, which ``rs274`` does not have), and the run-time
locating arithmetic runs on end points.  ``standalone_path`` evaluates the IR with
that same rule and the tests compare it with what ``rs274`` printed.

Tolerance: 1e-4 mm per coordinate.  ``Standalone`` computes as the program text does:
the constants rounded to the 4 decimals the program prints, the arithmetic in doubles
(rs274ngc's own).  ``rs274`` prints 4 decimals, so an exact dialect differs by at most
0.5e-4 mm; a wrong sign, axis, offset or store is off by far more.

Without ``rs274`` these tests skip, unless the environment variable ``CI`` is set: then
they fail, so a CI image without LinuxCNC cannot pass silently.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import pytest
from conftest import REPO

from probegen import ir
from probegen.dialects import get_dialect
from probegen.errors import UnsupportedError
from probegen.planning import plan_program
from probegen.results import parse_dprnt
from probegen.spec.model import load_spec

TOL = 1e-4
SPECS = sorted(p for p in (REPO / "samples").glob("*/*.toml")
               if "[[feature]]" in p.read_text(encoding="utf-8")
               and "on_out_of_tolerance" not in p.read_text(encoding="utf-8")
               and "set_work_offset" not in p.read_text(encoding="utf-8"))
"""The samples LinuxCNC can run: in-process decisions are Fanuc/Haas only (their
UnsupportedError is golden-tested in test_golden.py)."""
MOTION = {ir.MoveMode.RAPID: "STRAIGHT_TRAVERSE", ir.MoveMode.RETRACT: "STRAIGHT_FEED",
          ir.MoveMode.PROTECTED: "STRAIGHT_PROBE"}
CANON = re.compile(r"\s*\d+ N\.{5} (\w+)\((.*)\)\s*$")

SETUP = ir.Setup(
    program_number=7, program_name="T", units="mm", work_offset="G54", clearance_z=50.0,
    ball_diameter=6.0, shank_diameter=4.0, tool_number=20, tool_change=False,
    position_feed=2000.0, probe_feed=300.0, probe_on=(), probe_off=(), variable_base=500,
    reset_codes=("G17", "G69", "G15", "G50.1"), probe_length=40.0,
)


# -- running rs274 ------------------------------------------------------------------
def _in_ci() -> bool:
    return os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no")


@pytest.fixture(scope="module")
def rs274() -> str:
    """The ``rs274`` executable; fail in CI, skip elsewhere when it is missing."""
    path = shutil.which("rs274")
    if path is None:
        message = "rs274 (Debian package linuxcnc-uspace) is not installed"
        if _in_ci():
            pytest.fail(f"{message}, and CI is set: the LinuxCNC check must run in CI")
        pytest.skip(message)
    return path


@dataclass(frozen=True)
class Run:
    """What ``rs274 -g`` printed: its exit code, canonical commands and messages."""

    returncode: int
    commands: list[tuple[str, str]]
    output: str


def run_rs274(exe: str, text: str, work: Path, *, var_file: str | None = None) -> Run:
    """Run ``rs274 -g`` on ``text`` in ``work`` with a tool table holding the probe T20."""
    (work / "program.ngc").write_text(text, encoding="ascii")
    (work / "tool.tbl").write_text("T20 P20 Z0 D6 ;probe\n", encoding="ascii")
    args = [exe, "-g", "-t", "tool.tbl"]
    if var_file is not None:
        (work / "params.var").write_text(var_file, encoding="ascii")
        args += ["-v", "params.var"]
    done = subprocess.run([*args, "program.ngc"], cwd=work, capture_output=True, text=True,
                          timeout=120, check=False)
    commands = [(m[1], m[2]) for m in map(CANON.match, done.stdout.splitlines()) if m]
    return Run(done.returncode, commands, done.stdout + done.stderr)


def motions(run: Run) -> list[tuple[str, tuple[float, float, float], float]]:
    """The motion commands, each with its XYZ and the feed rate in force."""
    out, feed = [], 0.0
    for name, args in run.commands:
        if name == "SET_FEED_RATE":
            feed = float(args)
        elif name in MOTION.values():
            x, y, z = (float(v) for v in args.split(",")[:3])
            out.append((name, (x, y, z), 0.0 if name == "STRAIGHT_TRAVERSE" else feed))
    return out


def log_text(run: Run) -> str:
    """The lines the program's ``(LOG,...)`` comments wrote."""
    return "".join(args[1:-1] + "\n" for name, args in run.commands if name == "LOG")


# -- the path the IR implies in standalone mode -------------------------------------------
class Standalone:
    """Evaluate an IR program as ``rs274`` runs it: every skip position is the end point."""

    def __init__(self, setup: ir.Setup, decimals: int = 4) -> None:
        self.setup = setup
        self.decimals = decimals
        self.values: dict[str, float] = {}
        self.path: list[tuple[str, tuple[float, float, float], float]] = [
            ("STRAIGHT_TRAVERSE", (0.0, 0.0, setup.clearance_z), 0.0)]  # G43 H.. Z..
        self.logged: list[tuple[str, str, int, tuple[float, float, float]]] = []
        self.last: ir.Point | None = None
        self.centres: list[tuple[str, tuple[float, float, float]]] = []

    def value(self, c: ir.Coord) -> float:
        """A coordinate's value now, its constant rounded as the program prints it."""
        if isinstance(c, ir.Var):
            return self.values[c.name] + round(c.offset, self.decimals)
        return round(c, self.decimals)

    def point(self, p: ir.Point) -> tuple[float, float, float]:
        """A point's value now."""
        x, y, z = (self.value(c) for c in p)
        return x, y, z

    def run(self, program: ir.Program) -> Standalone:
        """Walk the program; return self with ``path``, ``logged`` and ``centres``."""
        for node in ir.walk(program.body):
            if isinstance(node, ir.Move):
                self.move(node)
            elif isinstance(node, ir.Touch):
                self.touch(node)
            elif isinstance(node, ir.Assign):
                if self.last is not None and node.name in {
                        c.name for c in self.last if isinstance(c, ir.Var)}:
                    self.last = None  # the same words name another point now
                self.values[node.name] = (self.value(node.a + node.offset) if node.b is None
                                          else (self.value(node.a) + self.value(node.b)) / 2)
            elif isinstance(node, ir.ReportCentre):
                self.centres.append((node.feature, self.point(node.centre)))
        return self

    def move(self, node: ir.Move) -> None:
        """A move; the dialect drops one to the same target as the move just before
        (rs274ngc refuses a probe move shorter than 0.254 mm), LOG lines and settings of
        other parameters between them."""
        if node.target != self.last:
            feed = 0.0 if node.mode is ir.MoveMode.RAPID else self.setup.position_feed
            self.path.append((MOTION[node.mode], self.point(node.target), feed))
        self.last = node.target

    def touch(self, node: ir.Touch) -> None:
        self.last = None
        k = self.setup.ball_diameter / 2 - node.overtravel
        x, y, z = (self.value(c + k * n) for c, n in zip(node.contact, node.normal, strict=True))
        self.path.append(("STRAIGHT_PROBE", (x, y, z), self.setup.probe_feed))
        for axis, name in enumerate(node.store):
            if name is not None:
                self.values[name] = (x, y, z)[axis]
        self.logged.append((node.role.value, node.feature, node.index, (x, y, z)))


def planned(spec_path: Path) -> tuple[ir.Program, str]:
    spec = load_spec(spec_path.relative_to(REPO))
    program = plan_program(spec, runtime_variables=True).program
    return program, get_dialect("linuxcnc").generate(program)


def assert_close(actual: tuple[float, ...], expected: tuple[float, ...], what: str) -> None:
    worst = max(abs(a - e) for a, e in zip(actual, expected, strict=True))
    assert worst <= TOL, f"{what}: rs274 {actual}, planned {expected} (off by {worst:.2e})"


# -- rs274 against the plan ---------------------------------------------------------------
@pytest.mark.parametrize("spec_path", SPECS, ids=lambda p: p.stem)
def test_rs274_runs_the_planned_path(in_repo: Path, rs274: str, tmp_path: Path,
                                     spec_path: Path) -> None:
    program, text = planned(spec_path)
    run = run_rs274(rs274, text, tmp_path)
    assert run.returncode == 0, run.output[-2000:]
    expected = Standalone(program.setup).run(program).path
    actual = motions(run)
    assert [m[0] for m in actual] == [m[0] for m in expected]
    for number, (got, want) in enumerate(zip(actual, expected, strict=True), start=1):
        assert_close(got[1], want[1], f"motion {number} ({got[0]})")
        assert got[2] == pytest.approx(want[2]), f"motion {number}: feed"


@pytest.mark.parametrize("spec_path", SPECS, ids=lambda p: p.stem)
def test_rs274_runs_the_compact_program_as_the_inline_one(in_repo: Path, rs274: str,
                                                          tmp_path: Path,
                                                          spec_path: Path) -> None:
    """``compile --compact``: rs274 finds ``o<pg_move>``/``o<pg_touch>`` in the folder it
    runs in (as LinuxCNC does in ``[RS274NGC] SUBROUTINE_PATH``) and commands the inline
    program's motions, feeds and LOG lines."""
    program, inline_text = planned(spec_path)
    d = get_dialect("linuxcnc")
    d.compact = True
    compact_text = d.generate(program)
    for name, text in d.library_files(8000, 100, "mm").items():
        (tmp_path / name).write_text(text, encoding="ascii")
    (tmp_path / "inline").mkdir()
    inline, compact = (run_rs274(rs274, inline_text, tmp_path / "inline"),
                       run_rs274(rs274, compact_text, tmp_path))
    assert inline.returncode == 0 and compact.returncode == 0, compact.output[-2000:]
    assert motions(compact) == motions(inline) and len(motions(inline)) > 10
    assert log_text(compact) == log_text(inline)


@pytest.mark.parametrize("spec_path", SPECS, ids=lambda p: p.stem)
def test_rs274_log_is_read_by_the_dprnt_reader(in_repo: Path, rs274: str, tmp_path: Path,
                                               spec_path: Path) -> None:
    program, text = planned(spec_path)
    run = run_rs274(rs274, text, tmp_path)
    log = parse_dprnt(log_text(run), source="rs274 LOG", strict=True)
    standalone = Standalone(program.setup).run(program)
    assert log.complete and log.program == program.setup.program_number
    assert [(t.kind, t.feature, t.index) for t in log.touches] == [
        entry[:3] for entry in standalone.logged]
    for touch, entry in zip(log.touches, standalone.logged, strict=True):
        assert_close(touch.xyz, entry[3], f"{touch.kind} {touch.feature} {touch.index}")
    assert [c.feature for c in log.centres] == [c[0] for c in standalone.centres]
    for centre, (_, xyz) in zip(log.centres, standalone.centres, strict=True):
        assert_close(centre.xyz, xyz, f"CTR {centre.feature}")


def test_rs274_aborts_when_a_g92_offset_is_applied(in_repo: Path, rs274: str,
                                                   tmp_path: Path) -> None:
    _, text = planned(SPECS[0])
    run = run_rs274(rs274, text, tmp_path, var_file="5210 1\n5211 0.5\n")
    assert run.returncode != 0
    assert "G92/G52 OFFSET IS APPLIED" in run.output
    assert not [name for name, _ in run.commands if name == "STRAIGHT_PROBE"]


def test_rs274_accepts_the_inch_program(rs274: str, tmp_path: Path) -> None:
    setup = ir.Setup(**{**{f: getattr(SETUP, f) for f in SETUP.__slots__}, "units": "inch"})
    touch = ir.Touch("F", 1, ir.TouchRole.MEASURE, (0.0, 0.0, 25.4), (0.0, 0.0, 1.0), 2.0, 2.0)
    text = get_dialect("linuxcnc").generate(ir.Program(setup, (
        ir.Move((0.0, 0.0, 33.02), ir.MoveMode.PROTECTED), touch)))
    run = run_rs274(rs274, text, tmp_path)
    assert run.returncode == 0, run.output[-2000:]
    (_, protected, _), (_, touch_end, feed) = motions(run)[1:]
    assert protected == (0.0, 0.0, 1.3) and touch_end == (0.0, 0.0, 1.0394)  # 4 decimals
    assert feed == pytest.approx(11.8)
    assert "PT F 1 X0.00000 Y0.00000 Z1.03937" in log_text(run)


# -- the program text ---------------------------------------------------------------------
def program(*nodes: ir.Node) -> str:
    return get_dialect("linuxcnc").generate(ir.Program(SETUP, nodes))


@pytest.mark.parametrize(
    ("node", "outcome"),
    [(ir.Move((ir.Var("A"), 0.0, 0.0), ir.MoveMode.RAPID), "G0 X#<_pg_a> Y0.0000 Z0.0000\n"),
     (ir.Assign("B", ir.Var("A"), offset=-1.5), "#<_pg_b> = [#<_pg_a>-1.5000]\n"),
     (ir.Assign("C", ir.Var("A"), ir.Var("B")), "#<_pg_c> = [[#<_pg_a>+#<_pg_b>]/2]\n"),
     (ir.ReportCentre("F", (ir.Var("A"), ir.Var("B"), ir.Var("C"))),
      "(LOG,CTR F X%.4f#<_pg_a> Y%.4f#<_pg_b> Z%.4f#<_pg_c>)\n"),
     (ir.ReportCentre("F", (ir.Var("A", 1.0), ir.Var("B"), ir.Var("C"))), UnsupportedError),
     (ir.LocalFrame("C", "F"), UnsupportedError)],
    ids=["var-move", "assign", "mean", "centre", "centre-offset", "local-frame"])
def test_capabilities(node: ir.Node, outcome: str | type[Exception]) -> None:
    if isinstance(outcome, str):
        assert outcome in program(node)
    else:
        with pytest.raises(outcome, match="dialect 'linuxcnc' cannot express"):
            program(node)


def test_header_translates_fanuc_reset_codes_and_checks_offsets() -> None:
    text = program()
    assert "\nG21\nG90 G17 G61\n" in text  # G69 G15 G50.1 cancel nothing on LinuxCNC
    assert "if [#5210 NE 0]" in text and "(LOGAPPEND,probegen-7.log)" in text
    assert text.startswith("%\n(PROGRAM 7 T)\n") and text.endswith("M2\n%\n")


def test_unknown_reset_code_is_refused_not_emitted() -> None:
    setup = ir.Setup(**{**{f: getattr(SETUP, f) for f in SETUP.__slots__},
                        "reset_codes": ("G17", "G68")})
    with pytest.raises(UnsupportedError, match="not a LinuxCNC modal code"):
        get_dialect("linuxcnc").generate(ir.Program(setup, ()))


def test_every_protected_move_checks_the_probe_and_aborts() -> None:
    lines = program(ir.Move((1.0, 2.0, 3.0), ir.MoveMode.PROTECTED)).splitlines()
    start = lines.index("G38.3 X1.0000 Y2.0000 Z3.0000 F2000")
    assert lines[start + 1:start + 6] == [
        "o1002 if [#5070 EQ 1]", "(LOG,ERR COLLISION NONE 1)",
        "(ABORT,UNEXPECTED PROBE TRIGGER NONE 1)", "M2", "o1002 endif"]


def test_comments_are_never_active_or_nested() -> None:
    text = program(ir.Comment("msg, hello (world)"), ir.Comment("debug"))
    assert "(NOTE MSG, HELLO [WORLD])\n(NOTE DEBUG)\n" in text


def test_parameter_names_that_collide_are_refused() -> None:
    with pytest.raises(UnsupportedError, match="two run-time values named _pg_a_b"):
        program(ir.Assign("A_B", 1.0), ir.Assign("A-B", 2.0))


def test_reader_accepts_linuxcnc_default_six_decimals() -> None:
    """``(LOG,X#5061)`` without a format prints ``%lf``: 6 decimals, maybe ``-0.000000``."""
    log = parse_dprnt("PGSTART O7 V1\nPT F 1 X1.234568 Y-0.000000 Z-2.500000\nPGEND O7\n",
                      strict=True)
    assert log.touches[0].xyz == (1.234568, 0.0, -2.5)


def test_a_move_to_where_the_last_one_ended_is_dropped_but_counted() -> None:
    move = ir.Move((1.0, 2.0, 3.0), ir.MoveMode.PROTECTED)
    text = program(move, move, ir.Move((1.0, 2.0, 4.0), ir.MoveMode.PROTECTED))
    assert text.count("G38.3 X1.0000 Y2.0000 Z3.0000 F2000\n") == 1
    assert "COLLISION NONE 1)" in text and "COLLISION NONE 3)" in text
    assert "COLLISION NONE 2)" not in text  # the numbers stay those of the Fanuc program


def test_a_move_after_an_assignment_is_kept() -> None:
    move = ir.Move((ir.Var("A"), 0.0, 0.0), ir.MoveMode.RAPID)
    text = program(ir.Assign("A", 1.0), move, ir.Assign("A", 2.0), move)
    assert text.count("G0 X#<_pg_a> Y0.0000 Z0.0000\n") == 2
