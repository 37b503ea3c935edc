"""The executable half of DMIS 5.3 (probegen/dmis/execute.py): variables, expressions,
control flow, macros and queries, on the virtual CMM and through ``probegen post``.

The corpus programs ``tests/dmis_corpus/exec_*`` were written for these tests in the
style of one vendor each (studied from public programs, none copied) and each has a flat
twin ``exec_*.flat.dmi``: the same touches written out without variables or control flow
(numbers computed independently, 10 decimals).  Truth: the twin.  Every program gives
its twin's touches, touch for touch, on the virtual CMM and through ``post`` + the
virtual machine, to 1e-6 mm; the evaluation of the posted run equals the twin's to
1e-6 mm and the CMM's to the log's rounding (4 decimals, amplified by the fit: 1e-3 mm).

* ``exec_camio_loop.dmi`` (LK CAMIO: Latin-1, CRLF, lines wrapped at 80): ``DECL/GLOBAL``
  of INTGR, LONG, REAL, DOUBLE; ``X=ASSIGN/`` with ``/``, ``+``, ``-``, ``*``; ``DO``
  with its index and a step (a DOUBLE into an INTGR index); ``SIN``/``COS`` in
  degrees; variables and expressions inside ``FEAT``, ``MEAS`` (the point count),
  ``PTMEAS`` and ``GOTO``.
* ``exec_pcdmis_macro.dmi`` (PC-DMIS: UTF-8 with BOM, lower case, indented):
  ``DECL/COMMON`` VECTOR, ``GLOBAL``, ``LOCAL`` BOOL; ``M(x)=MACRO/'dir',via`` with a
  quoted and a bare parameter, ``CALL/M(x),...`` five times; ``VCART``, ``VUNIT``,
  ``VMAG``, vector arithmetic and unary minus; ``IF/ELSE/ENDIF``; a VECTOR where three
  numbers stand (``GOTO/CART,q``, ``PTMEAS/CART,p,dir``); ``.FALSE.``.
* ``exec_modus_select.dmi`` (MODUS: ``x = ASSIGN/...``, jump labels): ``TEXT/OPER``,
  ``TEXT/QUERY`` (default GROB, or an answer), ``SELECT``/``CASE``/``DFTCAS``/
  ``ENDCAS``/``ENDSEL`` on ``SUBSTR``, ``INDX``, ``LEN``, ``CONCAT``, ``STR``, ``NINT``,
  ``INT``, ``SQRT``, ``ABS``, ``MOD``; a loop of ``(label)`` + ``IF`` + ``JUMPTO``; an
  array; BOOL with ``.AND.``, ``.OR.``, ``.NOT.``, ``.EQ.``, ``.NE.``, ``.GE.``,
  ``.LT.``, ``.GT.``, ``.LE.``; ``IF``/``ELSE`` choosing the approach distance;
  a feature label from a CHAR variable (``F(nom)``).
* ``exec_werth_wrapped.dms`` (WinWerth: blanks around ``/``, a ``BEGIN/CHFILE``
  characterisation block of ``KEY = value`` data): the program wrapped whole in a
  ``MACRO`` without a label and a ``BEGIN/END`` block; a 2-D array, nested ``DO``;
  ``OBTAIN`` of a nominal (known when posting) and of an actual (measured: used only in
  an ``ASSIGN``, which posting allows).
"""

from __future__ import annotations

import math
import re
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate
from test_dmis_corpus import CORPUS, HOME, MODEL, PROFILE, model, vm

from probegen.cli.app import main
from probegen.dmis.execute import MAX_STEPS, execute, is_control
from probegen.dmis.reader import (
    Label,
    Param,
    format_statement,
    parse_dmis,
    read_dmis,
    read_dmis_text,
)
from probegen.dmis.values import DmisProgramError
from probegen.errors import ProbegenError, UnsupportedError
from probegen.post.evaluate import evaluate_log
from probegen.post.featuremap import dumps, parse_feature_map, read_feature_map
from probegen.post.files import PostOutput, post_file
from probegen.post.frontend import post_dmis
from probegen.results import parse_dprnt
from probegen.sim.cmm.features import Vec3
from probegen.sim.cmm.interpreter import DmisRunResult, run_dmis
from probegen.sim.vm import CmmAdapter, run_text

EXEC = {
    "exec_camio_loop.dmi": 7,
    "exec_pcdmis_macro.dmi": 5,
    "exec_modus_select.dmi": 6,
    "exec_werth_wrapped.dms": 5,
}
"""Each executable corpus program and its number of touches."""


def twin(name: str) -> str:
    return name.rsplit(".", 1)[0] + ".flat.dmi"


class Recording:
    """A ``Cmm`` around another that keeps every ball centre it touched."""

    def __init__(self, inner: CmmAdapter) -> None:
        self.inner = inner
        self.hits: list[Vec3] = []

    @property
    def ball_radius(self) -> float:
        return self.inner.ball_radius

    def move(self, start: Vec3, end: Vec3) -> None:
        self.inner.move(start, end)

    def probe(self, start: Vec3, direction: Vec3, distance: float) -> Vec3 | None:
        hit = self.inner.probe(start, direction, distance)
        if hit is not None:
            self.hits.append(hit)
        return hit


def on_cmm(name: str, answers: dict[str, str | int | float] | None = None
           ) -> tuple[DmisRunResult, np.ndarray]:
    cmm = Recording(CmmAdapter(vm()))
    result = run_dmis(read_dmis(CORPUS / name), cmm, home=HOME, answers=answers)
    assert result.alarm is None, result.alarm
    return result, np.array(cmm.hits)


@cache
def posted(name: str) -> PostOutput:
    return post_file(CORPUS / name, PROFILE, model(), dialect="fanuc")


def numbers(result: DmisRunResult) -> list[np.ndarray]:
    return [np.array([*f.location, *(f.vector or ()), f.size or 0.0])
            for f in result.features.values()]


def assert_features(a: DmisRunResult, b: DmisRunResult, atol: float = 1e-6) -> None:
    assert list(a.features) == list(b.features) and a.features
    for x, y in zip(numbers(a), numbers(b), strict=True):
        np.testing.assert_allclose(x, y, atol=atol)


# -------------------------------------------------------------- the corpus and its twins


@pytest.mark.parametrize("name", EXEC)
def test_program_has_variables_and_its_twin_none(name: str) -> None:
    """The program uses the executable half; its twin is straight DMIS."""
    program = read_dmis(CORPUS / name).statements
    flat = read_dmis(CORPUS / twin(name)).statements
    assert sum(is_control(s) for s in program) >= 5
    assert not any(is_control(s) for s in flat)
    assert sum(s.major == "PTMEAS" for s in flat) == EXEC[name]


@pytest.mark.parametrize("name", EXEC)
def test_virtual_cmm_touches_as_the_flat_twin(name: str) -> None:
    result, hits = on_cmm(name)
    flat, flat_hits = on_cmm(twin(name))
    assert hits.shape == flat_hits.shape == (EXEC[name], 3)
    np.testing.assert_allclose(hits, flat_hits, atol=1e-6)
    assert_features(result, flat)
    size = next(iter(result.features.values())).size
    assert size == pytest.approx(25.0, abs=1e-6)


@pytest.mark.parametrize("name", EXEC)
def test_post_touches_as_the_flat_twin_and_evaluates_as_the_cmm(name: str) -> None:
    out, flat = posted(name), posted(twin(name))
    assert len(out.fmap.touches) == len(flat.fmap.touches) == EXEC[name]
    for a, b in zip(out.fmap.touches, flat.fmap.touches, strict=True):
        assert (a.feature, a.index) == (b.feature, b.index)
        np.testing.assert_allclose(a.start, b.start, atol=1e-6)
        np.testing.assert_allclose(a.direction, b.direction, atol=1e-6)
        assert a.reach == pytest.approx(b.reach, abs=1e-6)
    runs = [run_text(o.text, vm(), kind="macrob", source=name) for o in (out, flat)]
    assert all(r.alarm is None and r.touches == EXEC[name] for r in runs)
    logs = [parse_dprnt(r.output, strict=True) for r in runs]
    points = [np.array([t.xyz for t in log.latest_touches()]) for log in logs]
    np.testing.assert_allclose(points[0], points[1], atol=1e-6)
    evaluated = [evaluate_log(log, o.fmap) for log, o in zip(logs, (out, flat), strict=True)]
    assert_features(evaluated[0], evaluated[1])
    # the CMM's touches unrounded, the log's to 4 decimals (a 5-point cap fit amplifies)
    assert_features(evaluated[0], on_cmm(name)[0], atol=1e-3)


def test_post_lists_every_control_statement_reached_as_a_comment() -> None:
    """Loops are unrolled: the DO line is commented once, the ENDDO and the loop body once
    per pass; nothing of the executable half is left as a skipped statement."""
    out = posted("exec_camio_loop.dmi")
    assert out.text.count("(L26 DO/IDX,0,360-PAS,PAS)") == 1
    assert out.text.count("(L31 ENDDO)") == 6
    assert out.text.count("(L27 ANGLE=ASSIGN/IDX)") == 6
    assert not out.posted.skipped
    assert len(re.findall(r"G31", out.text)) >= EXEC["exec_camio_loop.dmi"]


def test_query_answers_from_a_file_on_the_cmm_post_and_the_evaluation(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The answer FEIN makes the MODUS program measure 8 points; the feature map keeps the
    answer so ``post-ingest`` runs the same flow; without an answer, the default."""
    result, hits = on_cmm("exec_modus_select.dmi", {"VARIANTE": "FEIN"})
    assert len(hits) == 8 and list(result.features) == ["ÄQUATOR_8"]
    assert "answered 'FEIN' (from the answers file)" in result.notes[0].reason
    answers = tmp_path / "answers.toml"
    answers.write_text('variante = "FEIN"\n')
    nc = tmp_path / "modus.nc"
    args = ["post", str(CORPUS / "exec_modus_select.dmi"), "--machine",
            str(REPO / "samples/post/vmc-fanuc-d4.toml"), "--model", str(MODEL), "-o", str(nc)]
    assert main([*args, "--answers", str(answers)]) == 0
    printed = capsys.readouterr()
    assert "8 touches" in printed.out
    assert "exec_modus_select.dmi:11: TEXT/QUERY,(variante),12,A,L,'Variante GROB oder " \
        "FEIN?','GROB' (answered 'FEIN' (from the answers file)" in printed.err
    fmap = read_feature_map(tmp_path / "modus.features.json")
    assert fmap.answers == (("VARIANTE", "FEIN"),)
    assert parse_feature_map(dumps(fmap)) == fmap
    run = run_text(nc.read_text(), vm(), kind="macrob")
    evaluated = evaluate_log(parse_dprnt(run.output, strict=True), fmap)
    assert_features(evaluated, result, atol=1e-4)
    assert main(args) == 0
    assert "6 touches" in capsys.readouterr().out
    dmo = tmp_path / "modus.dmo"
    assert main(["sim", str(CORPUS / "exec_modus_select.dmi"), "--part", str(MODEL),
                 "--machine", str(REPO / "samples/post/vmc-fanuc-d4.toml"),
                 "--answers", str(answers), "-o", str(dmo)]) == 0
    assert "QUATOR_8) = FEAT/CIRCLE" in dmo.read_text(encoding="latin-1")


def test_query_without_an_answer_or_a_default_is_a_located_error() -> None:
    text = ("DECL/LOCAL,INTGR,N\nTEXT/QUERY,(N),3,N,L,'How many?'\nENDFIL\n")
    with pytest.raises(DmisProgramError, match=r"q.dmi:2: TEXT/QUERY \(N\) has no answer"):
        run_dmis(parse_dmis(text, source="q.dmi"), Recording(CmmAdapter(vm())))


# ----------------------------------------------------------- measured values and refusals

MEASURED = """DMISMN/'branch on a measured value',05.0
UNITS/MM,ANGDEC
DECL/LOCAL,REAL,DIA
S(P)=SNSDEF/PROBE,FIXED,CART,0,0,30,0,0,-1,4.0
SNSLCT/S(P)
SNSET/APPRCH,3
SNSET/SEARCH,3
SNSET/RETRCT,3
GOTO/CART,0,0,30
F(S1)=FEAT/SPHERE,OUTER,CART,0,0,0,25
MEAS/SPHERE,F(S1),5
PTMEAS/CART,0,0,12.5,0,0,1
GOTO/CART,20,0,30
GOTO/CART,20,0,0
PTMEAS/CART,12.5,0,0,1,0,0
GOTO/CART,20,20,0
PTMEAS/CART,0,12.5,0,0,1,0
GOTO/CART,-20,20,0
PTMEAS/CART,-12.5,0,0,-1,0,0
GOTO/CART,-20,-20,0
PTMEAS/CART,0,-12.5,0,0,-1,0
ENDMES
DIA=OBTAIN/FA(S1),7
IF/(DIA .GT. 24.9)
GOTO/CART,0,0,60
ELSE
GOTO/CART,0,0,80
ENDIF
ENDFIL
"""


def test_branch_on_a_measured_value_runs_on_the_cmm_and_is_refused_by_post() -> None:
    cmm = Recording(CmmAdapter(vm()))
    result = run_dmis(parse_dmis(MEASURED), cmm, home=HOME)
    assert result.alarm is None and len(cmm.hits) == 5
    program = parse_dmis(MEASURED, source="m.dmi")
    for skip in (False, True):  # never skipped: the posted flow would not be the CMM's
        with pytest.raises(UnsupportedError, match=r"m.dmi:24: cannot post-process IF for a "
                           r"machine tool: branches on a value measured at run time "
                           r"\(OBTAIN at line 23\)"):
            post_dmis(program, PROFILE, skip_unsupported=skip)


@pytest.mark.parametrize(("statement", "major", "what"), [
    ("DO/K,1,NINT(DIA/10)\nENDDO", "DO", "loops over"),
    ("SELECT/NINT(DIA)\nCASE/25\nENDCAS\nENDSEL", "SELECT", "selects on"),
    ("K=ASSIGN/DIA\nF(P)=FEAT/POINT,CART,0,0,K,0,0,1", "FEAT", "uses"),
])
def test_loops_selections_and_definitions_on_a_measured_value_are_refused_by_post(
        statement: str, major: str, what: str) -> None:
    text = MEASURED.replace("DECL/LOCAL,REAL,DIA", "DECL/LOCAL,REAL,DIA\nDECL/LOCAL,INTGR,K")
    text = text.replace("IF/(DIA .GT. 24.9)\nGOTO/CART,0,0,60\nELSE\nGOTO/CART,0,0,80\nENDIF",
                        statement)
    assert statement in text
    cmm = Recording(CmmAdapter(vm()))
    assert run_dmis(parse_dmis(text), cmm, home=HOME).alarm is None and len(cmm.hits) == 5
    with pytest.raises(UnsupportedError, match=rf"m.dmi:2\d: cannot post-process {major} "
                                               rf"for a machine tool: {what} a value measured"):
        post_dmis(parse_dmis(text, source="m.dmi"), PROFILE)


def test_a_move_to_a_measured_value_is_refused_by_post() -> None:
    text = MEASURED.replace("IF/(DIA .GT. 24.9)", "GOTO/CART,0,0,DIA*3\nIF/(1 .EQ. 1)")
    with pytest.raises(UnsupportedError, match=r"m.dmi:24: cannot post-process GOTO .* uses "
                                               r"a value measured at run time"):
        post_dmis(parse_dmis(text, source="m.dmi"), PROFILE)
    nominal = MEASURED.replace("OBTAIN/FA(S1)", "OBTAIN/F(S1)")  # known when posting
    posted_ = post_dmis(parse_dmis(nominal), PROFILE)
    heights = {node.target[2] for node in posted_.program.body if hasattr(node, "target")}
    assert len(posted_.touches) == 5 and 60.0 in heights and 80.0 not in heights


# ------------------------------------------------------------------------ the language


class NoHost:
    def obtain(self, label: Label, index: int) -> tuple[Param, bool]:
        raise AssertionError("no OBTAIN here")


def values(text: str) -> list[tuple[Param, ...]]:
    """The parameters of every TEXT/OUTFIL the program executes."""
    program = parse_dmis(text + "\nENDFIL\n", source="x.dmi")
    return [s.params[1:] for s in execute(program, NoHost()) if s.major == "TEXT"]


@pytest.mark.parametrize(("expression", "expected"), [
    ("SIN(30)", 0.5), ("COS(60)", 0.5), ("TAN(45)", 1.0), ("ASIN(0.5)", 30.0),
    ("ACOS(0.5)", 60.0), ("ATAN(1)", 45.0), ("ATAN2(1,-1)", 135.0), ("SQRT(2)**2", 2.0),
    ("ABS(-3)", 3), ("INT(-2.7)", -2), ("NINT(-2.5)", -3), ("NINT(2.4)", 2), ("MOD(7,3)", 1),
    ("MOD(7.5,2)", 1.5), ("7/2", 3.5), ("8/2", 4), ("2**10", 1024), ("-2+3*4", 10),
    ("DTOR(180)", math.pi), ("RTOD(PI())", 180.0), ("LN(EXP(1))", 1.0), ("LOG(1000)", 3.0),
    ("SIGN(3,-1)", -3), ("LEN('abc')", 3), ("INDX('ABCDE','CD')", 3), ("INDX('A','Z')", 0),
    ("VAL('2.5')", 2.5), ("ORD('A')", 65), ("VMAG(VCART(3,4,0))", 5.0),
    ("VDOT(VCART(1,2,3),VCART(4,5,6))", 32.0), ("VMAG(VPOL(2,30,0))", 2.0),
])
def test_intrinsic_functions(expression: str, expected: float) -> None:
    [(value,)] = values(f"TEXT/OUTFIL,{expression}")
    assert value == pytest.approx(expected, abs=1e-12)
    assert type(value) is type(expected) or isinstance(expected, float)


@pytest.mark.parametrize(("expression", "expected"), [
    ("SUBSTR('PROBEGEN',3,5)", "OBE"), ("CONCAT('A','B','C')", "ABC"), ("STR(12)", "12"),
    ("STR(2.5)", "2.5"), ("UPC('ab')", "AB"), ("LWC('AB')", "ab"), ("TRIM('  x ')", "x"),
    ("CHR(66)", "B"), ("'a'+'b'", "ab"),
])
def test_string_functions(expression: str, expected: str) -> None:
    [(value,)] = values(f"TEXT/OUTFIL,{expression}")
    assert value == parse_dmis(f"X/'{expected}'\n").statements[0].params[0]


@pytest.mark.parametrize(("expression", "expected"), [
    ("1 .EQ. 1", ".TRUE."), ("1 .NE. 1", ".FALSE."), ("2 .LT. 3", ".TRUE."),
    ("3 .LE. 2", ".FALSE."), ("'B' .GT. 'A'", ".TRUE."), ("2 .GE. 2.0", ".TRUE."),
    (".TRUE. .AND. .FALSE.", ".FALSE."), (".FALSE. .OR. .NOT. .FALSE.", ".TRUE."),
    ("1 .LT. 2 .AND. 2 .LT. 3", ".TRUE."),
])
def test_comparisons_and_logic(expression: str, expected: str) -> None:
    assert values(f"TEXT/OUTFIL,{expression}") == [(expected,)]


def test_types_scopes_arrays_loops_and_select() -> None:
    program = """DECL/GLOBAL,INTGR,I,N
DECL/LOCAL,REAL,A[3]
DECL/LOCAL,CHAR,3,C
DECL/COMMON,BOOL,B
N=ASSIGN/7.9
TEXT/OUTFIL,N
DO/I,3,1,-1
A[I]=ASSIGN/I*1.5
ENDDO
TEXT/OUTFIL,I,A[1],A[3]
DO/I,5,1
TEXT/OUTFIL,'never'
ENDDO
ASSIGN/C='AB'
SELECT/C
CASE/'X'
TEXT/OUTFIL,'X'
ENDCAS
DFTCAS
TEXT/OUTFIL,'default'
ENDCAS
ENDSEL
M(TWICE)=MACRO/X
DECL/LOCAL,REAL,Y
Y=ASSIGN/X*2
TEXT/OUTFIL,Y
ENDMAC
CALL/M(TWICE),N
CALL/M(TWICE),A[3]
B=ASSIGN/N .GT. 5"""
    assert values(program) == [(7,), (0, 1.5, 4.5), (parse_dmis("X/'default'\n")
                                                    .statements[0].params[0],), (14,), (9.0,)]


@pytest.mark.parametrize(("program", "message"), [
    ("ENDIF", r"x.dmi:1: ENDIF without its IF \(no open block\)"),
    ("IF/(1 .EQ. 1)\nENDDO", r"x.dmi:2: ENDDO without its DO \(the IF of line 1\)"),
    ("DO/I,1,2", r"x.dmi:1: DO is never closed \(ENDDO\)"),
    ("DECL/LOCAL,INTGR,I\nJUMPTO/(IN)\nDO/I,1,2\n(IN)\nENDDO",
     r"x.dmi:2: JUMPTO \(IN\) jumps into the DO loop of line 3"),
    ("JUMPTO/(NOWHERE)", r"x.dmi:1: JUMPTO: no label \(NOWHERE\)"),
    ("CALL/M(NONE)", r"x.dmi:1: M\(NONE\) is not defined"),
    ("M(A)=MACRO/X\nENDMAC\nCALL/M(A)", r"x.dmi:3: M\(A\) has 1 parameters, found 0"),
    ("X=ASSIGN/1", r"x.dmi:1: X is not declared"),
    ("DECL/LOCAL,INTGR,A[2]\nA[3]=ASSIGN/1", r"x.dmi:2: A: index 3 outside 1..2"),
    ("DECL/LOCAL,CHAR,2,C\nC=ASSIGN/'ABC'", r"x.dmi:2: C is CHAR,2: 'ABC' is 3 long"),
    ("DECL/LOCAL,REAL,R\nR=ASSIGN/SQRT(-1)", r"x.dmi:2: SQRT of a negative number"),
    ("DECL/LOCAL,REAL,R\nR=ASSIGN/1/0", r"x.dmi:2: division by zero"),
    ("DECL/LOCAL,INTGR,I\nDO/I,1,5,0\nENDDO", r"x.dmi:2: DO: the step is 0"),
    ("DECL/LOCAL,INTGR,I\nDO/I,1,1E9\nENDDO", r"x.dmi:2: DO runs 1000000000 times"),
    ("(LOOP)\nJUMPTO/(LOOP)", rf"x.dmi:\d: more than {MAX_STEPS} statements executed"),
    ("M(R)=MACRO\nCALL/M(R)\nENDMAC\nCALL/M(R)", r"x.dmi:2: macro calls nested more than"),
])
def test_wrong_programs_are_located_errors(program: str, message: str) -> None:
    with pytest.raises(DmisProgramError, match=message):
        values(program)


def test_an_endless_loop_on_the_virtual_cmm_is_a_located_error_not_a_hang() -> None:
    text = "DECL/LOCAL,INTGR,K\n(L)\nK=ASSIGN/K+1\nGOTO/CART,0,0,K\nJUMPTO/(L)\nENDFIL\n"
    with pytest.raises(DmisProgramError, match=r"loop.dmi:\d: more than 200000 statements"):
        run_dmis(parse_dmis(text, source="loop.dmi"), NominalCmm())


# ----------------------------------------------------------------------- properties


class NominalCmm:
    """A fast ``Cmm``: moves always free, every probe touches at half its reach."""

    ball_radius = 2.0

    def move(self, start: Vec3, end: Vec3) -> None:
        pass

    def probe(self, start: Vec3, direction: Vec3, distance: float) -> Vec3:
        return (start[0] + direction[0] * distance / 2, start[1] + direction[1] * distance / 2,
                start[2] + direction[2] * distance / 2)


SOURCES = [read_dmis_text(CORPUS / name) for name in EXEC]
ALPHABET = "()[],=/.+-*'$ \n0123456789IJKNXDOENDIFASGTLMCRQUEL"


def run_both(text: str) -> None:
    """The program on the CMM and through post: a result or a ProbegenError."""
    try:
        program = parse_dmis(text, source="m.dmi")
    except ProbegenError:
        return
    for run in (lambda: run_dmis(program, NominalCmm(), skip_unsupported=True),
                lambda: post_dmis(program, PROFILE, skip_unsupported=True)):
        try:
            run()
        except ProbegenError as exc:
            assert re.match(r"m\.dmi(:\d+)?: ", str(exc)), str(exc)  # located


@st.composite
def shuffled(draw: st.DrawFn) -> str:
    """A corpus program with statements dropped, repeated or moved (an ENDDO lost, a
    JUMPTO doubled ...)."""
    lines = draw(st.sampled_from(SOURCES)).splitlines()
    for _ in range(draw(st.integers(1, 4))):
        k = draw(st.integers(0, len(lines) - 1))
        op = draw(st.sampled_from(["drop", "repeat", "move"]))
        line = lines.pop(k) if op != "repeat" else lines[k]
        if op != "drop":
            lines.insert(draw(st.integers(0, len(lines))), line)
    return "\n".join(lines) + "\n"


@settings(max_examples=examples(60), suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_mutated_executable_programs_end_in_a_result_or_a_located_error(
        data: st.DataObject) -> None:
    source = data.draw(st.sampled_from(SOURCES))
    run_both(data.draw(st.composite(lambda draw: mutate(draw, source, ALPHABET, most=6))()))


@settings(max_examples=examples(40), suppress_health_check=[HealthCheck.too_slow])
@given(shuffled())
def test_reordered_statements_end_in_a_result_or_a_located_error(text: str) -> None:
    run_both(text)


def test_reader_forms_of_the_executable_half() -> None:
    """``X=ASSIGN/`` reads as ``ASSIGN/X=``; ``(label)`` is a statement of its own (a
    wrapped comment never swallows it); ``.TRUE.`` is a word; every form writes back."""
    text = ("$$ a comment wrapped $\n(LOOP)\n$$ another $\nX = ASSIGN/1\n"
            "a[2,J]=assign/.true.\nASSIGN/X=1\n")
    statements = parse_dmis(text).statements
    assert [(s.line, s.major, s.label) for s in statements] == [
        (2, "", Label("", "LOOP")), (4, "ASSIGN", None), (5, "ASSIGN", None),
        (6, "ASSIGN", None)]
    assert statements[1].params == statements[3].params
    assert statements[1].text == "X = ASSIGN/1"
    for s in statements:
        again = parse_dmis(format_statement(s) + "\n").statements[0]
        assert (again.label, again.major, again.params) == (s.label, s.major, s.params)
    assert format_statement(statements[2]) == "ASSIGN/A[2,J]=.TRUE."
