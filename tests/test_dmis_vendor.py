"""Vendor prologues and habits (issue 18 item 4): tests/dmis_corpus/vendor_*.

Each program there was written for these tests in the style of one vendor's DMIS (no
file copied from anywhere) and measures the five points of ``flat.dmi``, its flat twin,
on the sample sphere (D25 at the origin):

* ``vendor_camio.dmi`` (LK CAMIO, Latin-1, CRLF): DMESWV, DECPL, VFORM, DISPLY,
  SNSET/CLRSRF and DEPTH, FLY on a variable, MODE/MAN and MODE/PROG,MAN, RECALL/SA +
  SNSLCT/SA, SAVE/DA, a shifted frame, RECALL/DA, PAUSE.
* ``vendor_pcdmis.dmi`` (PC-DMIS export, UTF-8 BOM, CRLF): WKPLAN, PRCOMP, TECOMP,
  FEDRAT, MODE, GEOALG/LSTSQR, an indexed SNSDEF/PROBE,INDEX,POL tip, TOL/DIAM.
* ``vendor_calypso.dmi`` (Zeiss Calypso export): TECOMP, CRMODE, CRSLCT, WKPLAN, MODE,
  SNSDEF/PROBE,INDEX,VEC, SNSLCT with a head index, CZSLCT, one SNSET with APPRCH,
  RETRCT, SEARCH and CLRSRF.
* ``vendor_modus.dmi`` (Renishaw MODUS, Latin-1): TECOMP/OFF, CALIB/SENS on a reference
  sphere, SNSET and SNSLCT repeated inside the MEAS block.
* ``vendor_werth.dms`` (WinWerth): ``BEGIN/CHFILE``, blanks around ``/`` and ``,``, a
  VIDEO sensor, a zero-diameter PROBE, FILDEF/ALGDEF/LITDEF, FILNAM, TECOMP, W3D, the
  program wrapped in MACRO/ENDMAC, an actual given as ``FA(x)=FEAT``, TRANS on it,
  WKPLAN/NONE, MODE, POINTDIST, PIEZOWFP, SNSET/VA, SNSLCT and CZSLCT inside MEAS.

Truth: the flat twin.  Every program gives its touches to 1e-6 mm on the virtual CMM
and through ``post`` + the virtual machine, without ``--skip-unsupported``; every
statement left out is in the report with its reason.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate
from test_dmis_corpus import CORPUS, HOME, PROFILE, model, vm
from test_dmis_exec import on_cmm, posted, run_both

from probegen.cli.app import main
from probegen.dmis.reader import parse_dmis, read_dmis, read_dmis_text
from probegen.errors import UnsupportedError
from probegen.post.evaluate import evaluate_log
from probegen.post.featuremap import read_feature_map
from probegen.post.files import post_file
from probegen.post.frontend import post_dmis
from probegen.results import parse_dprnt
from probegen.sim.cmm.interpreter import DmisRunResult, run_dmis
from probegen.sim.cmm.sensors import NOTED
from probegen.sim.vm import CmmAdapter, run_text

FLAT = "flat.dmi"
DISTANCES = {"APPRCH", "RETRCT", "SEARCH", "DEPTH"}

SKIPPED = {
    "vendor_camio.dmi": {"DMESWV", "DECPL", "VFORM", "SNSET", "FLY", "MODE", "PAUSE"},
    "vendor_pcdmis.dmi": {"WKPLAN", "TECOMP", "MODE", "GEOALG"},
    "vendor_calypso.dmi": {"TECOMP", "CRMODE", "CRSLCT", "WKPLAN", "MODE", "CZSLCT"},
    "vendor_modus.dmi": {"TECOMP", "CALIB"},
    "vendor_werth.dms": {"SNSDEF", "FILDEF", "ALGDEF", "LITDEF", "TECOMP", "W3D", "WKPLAN",
                         "MODE", "POINTDIST", "PIEZOWFP", "SNSET", "CZSLCT"},
}
"""Each vendor program and the major words it leaves out with a note."""


def sphere(result: DmisRunResult) -> np.ndarray:
    """The measured sphere's centre and diameter (the feature names differ)."""
    found = [f for f in result.features.values() if f.kind == "SPHERE"]
    assert len(found) == 1
    return np.array([*found[0].location, found[0].size])


@pytest.mark.parametrize("name", SKIPPED)
def test_virtual_cmm_touches_as_the_flat_twin(name: str) -> None:
    result, hits = on_cmm(name)
    flat, flat_hits = on_cmm(FLAT)
    assert hits.shape == flat_hits.shape == (5, 3)
    np.testing.assert_allclose(hits, flat_hits, atol=1e-6)
    np.testing.assert_allclose(sphere(result), sphere(flat), atol=1e-6)
    assert sphere(result)[3] == pytest.approx(25.0, abs=1e-6)
    assert {s.text.split("/")[0].split("=")[-1].strip() for s in result.skipped} \
        == SKIPPED[name]


@pytest.mark.parametrize("name", SKIPPED)
def test_post_touches_as_the_flat_twin(name: str) -> None:
    out, flat = posted(name), posted(FLAT)
    assert len(out.fmap.touches) == len(flat.fmap.touches) == 5
    for a, b in zip(out.fmap.touches, flat.fmap.touches, strict=True):
        assert a.index == b.index
        np.testing.assert_allclose(a.start, b.start, atol=1e-6)
        np.testing.assert_allclose(a.direction, b.direction, atol=1e-6)
        assert a.reach == pytest.approx(b.reach, abs=1e-6)
    runs = [run_text(o.text, vm(), kind="macrob", source=name) for o in (out, flat)]
    assert all(r.alarm is None and r.touches == 5 for r in runs)
    logs = [parse_dprnt(r.output, strict=True) for r in runs]
    points = [np.array([t.xyz for t in log.latest_touches()]) for log in logs]
    np.testing.assert_allclose(points[0], points[1], atol=1e-6)
    evaluated = [evaluate_log(log, o.fmap) for log, o in zip(logs, (out, flat), strict=True)]
    np.testing.assert_allclose(sphere(evaluated[0]), sphere(evaluated[1]), atol=1e-6)


@pytest.mark.parametrize("name", SKIPPED)
def test_every_statement_left_out_is_reported_with_its_reason(name: str) -> None:
    """The feature map lists each skipped statement (line, text, reason), the posted
    program carries a SKIPPED comment for it, and nothing else is skipped."""
    out = posted(name)
    program = read_dmis(CORPUS / name)
    expected = [s for s in program.statements if s.major in SKIPPED[name] and (
        s.major in NOTED or s.major == "SNSDEF" and s.params[0] != "PROBE"
        or s.major == "SNSET" and not set(map(str, s.params)) & DISTANCES)]
    skipped = out.fmap.skipped
    assert [(line, text) for line, text, _ in skipped] == [(s.line, s.text) for s in expected]
    assert all(reason for _, _, reason in skipped)
    for line, _, _ in skipped:
        assert f"(L{line} SKIPPED " in out.text


def test_post_prints_every_skipped_statement(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "camio.nc"
    code = main(["post", str(CORPUS / "vendor_camio.dmi"), "--dialect", "fanuc",
                 "--machine", str(CORPUS.parent.parent / "samples/post/vmc-fanuc-d4.toml"),
                 "--model", str(CORPUS.parent.parent / "samples/sphere25/sphere25.step"),
                 "-o", str(target)])
    assert code == 0
    err = capsys.readouterr().err
    fmap = read_feature_map(target.with_suffix(".features.json"))
    assert len(fmap.skipped) == 8
    for line, text, reason in fmap.skipped:
        assert f"vendor_camio.dmi:{line}: {text} ({reason})" in err


def test_recall_da_restores_the_saved_frame() -> None:
    """Without the RECALL/DA the shifted frame would move every touch by (10, -5, 0)."""
    text = (CORPUS / "vendor_camio.dmi").read_bytes().decode("latin-1")
    shifted = text.replace("RECALL/DA(Référence_MCS)", "$$ no recall")
    result = run_dmis(parse_dmis(shifted), CmmAdapter(vm()), home=HOME)
    assert result.alarm is not None  # the first touch goes 10 mm beside the sphere
    assert sphere(on_cmm("vendor_camio.dmi")[0])[:3] == pytest.approx((0, 0, 0), abs=1e-6)


VIDEO = """DMISMN/'VIDEO'
UNITS/MM,ANGDEC
S(CAM)=SNSDEF/VIDEO,FIXED,CART,0,0,0,0,0,1,0
S(P)=SNSDEF/PROBE,FIXED,CART,0,0,0,0,0,1,4
SNSLCT/S(CAM)
F(P1)=FEAT/POINT,CART,0,0,12.5,0,0,1
MEAS/POINT,F(P1),1
PTMEAS/CART,0,0,12.5,0,0,1
ENDMES
ENDFIL
"""


@pytest.mark.parametrize("skip", [False, True])
def test_a_measurement_with_a_sensor_that_is_not_a_touch_probe_is_refused(skip: bool) -> None:
    """Refused at its MEAS naming the SNSDEF, even with --skip-unsupported."""
    with pytest.raises(UnsupportedError, match=r"<v>:7: cannot post-process MEAS .*VIDEO "
                                               r"sensor, not a touch probe \(SNSDEF at line 3"):
        post_dmis(parse_dmis(VIDEO, source="<v>"), PROFILE, skip_unsupported=skip)
    with pytest.raises(UnsupportedError, match=r"<v>:7: the virtual CMM cannot execute MEAS"):
        run_dmis(parse_dmis(VIDEO, source="<v>"), CmmAdapter(vm()), home=HOME)
    fixed = VIDEO.replace("SNSLCT/S(CAM)", "SNSLCT/S(P)")
    assert len(post_dmis(parse_dmis(fixed), PROFILE).touches) == 1


@pytest.mark.parametrize(("old", "new", "where"), [
    ("PTMEAS/CART", "PTMEAS/POL", "8: cannot post-process PTMEAS"),
    ("PTMEAS/CART", "SCNSET/DRAG,0.1\nPTMEAS/CART", "8: cannot post-process SCNSET .*inside "
                                                   "the MEAS block of line 7"),
])
def test_a_measuring_move_is_never_skipped(old: str, new: str, where: str) -> None:
    """A PTMEAS the post cannot turn into a touch, a scanning setting inside a MEAS block:
    refused even with --skip-unsupported."""
    program = VIDEO.replace("SNSLCT/S(CAM)", "SNSLCT/S(P)").replace(old, new)
    with pytest.raises(UnsupportedError, match=f"<v>:{where}.*never skipped"):
        post_dmis(parse_dmis(program, source="<v>"), PROFILE, skip_unsupported=True)


def test_snset_words_other_than_the_distances_and_clearance_are_refused() -> None:
    program = VIDEO.replace("SNSLCT/S(CAM)", "SNSLCT/S(P)\nSNSET/SCALE,2")
    with pytest.raises(UnsupportedError, match=r"<v>:6: cannot post-process SNSET .*SCALE"):
        post_dmis(parse_dmis(program, source="<v>"), PROFILE)
    out = post_dmis(parse_dmis(program, source="<v>"), PROFILE, skip_unsupported=True)
    assert [s.line for s in out.skipped] == [3, 6]


def test_geoalg_other_than_least_squares_is_refused() -> None:
    program = VIDEO.replace("SNSLCT/S(CAM)", "SNSLCT/S(P)\nGEOALG/POINT,MINMAX")
    with pytest.raises(UnsupportedError, match=r"<v>:6: .*only least-squares"):
        post_dmis(parse_dmis(program, source="<v>"), PROFILE)


def test_thousands_of_output_statements() -> None:
    """A program writing 5000 OUTPUT statements (a CAMIO report of every feature) posts
    and runs on the virtual CMM, each one echoed."""
    text = (CORPUS / FLAT).read_text()
    many = text.replace("OUTPUT/FA(S1)\n", "OUTPUT/FA(S1)\n" * 5000)
    program = parse_dmis(many, source="<many>")
    out = post_dmis(program, PROFILE)
    assert len(out.touches) == 5 and out.skipped == ()
    result = run_dmis(program, CmmAdapter(vm()), home=HOME)
    assert result.output.count("OUTPUT/FA(S1)") == 5000


SOURCES = [read_dmis_text(CORPUS / name) for name in SKIPPED]
ALPHABET = "()[],=/.+-*'$ \n0123456789SNETAPRCHLZOFKMDVWIX"


@settings(max_examples=examples(60), suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_mutated_vendor_programs_end_in_a_result_or_a_located_error(
        data: st.DataObject) -> None:
    source = data.draw(st.sampled_from([*SOURCES, CONSTRUCT]))
    run_both(data.draw(st.composite(lambda draw: mutate(draw, source, ALPHABET, most=6))()))


def test_sim_prints_every_skipped_and_noted_statement(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``probegen sim`` on a DMIS program lists what the virtual CMM left out or noted."""
    program = CORPUS / "vendor_calypso.dmi"
    assert main(["sim", str(program), "--part",
                 str(CORPUS.parent.parent / "samples/sphere25/sphere25.step"),
                 "--machine", str(CORPUS.parent.parent / "samples/post/vmc-fanuc-d4.toml"),
                 "-o", str(tmp_path / "out.dmo")]) == 0
    err = capsys.readouterr().err
    for line, major in ((4, "TECOMP"), (5, "CRMODE"), (6, "CRSLCT"), (7, "WKPLAN"),
                        (8, "MODE"), (11, "CZSLCT")):
        assert f"probegen: skipped {program}:{line}: {major}/" in err
    for line in (9, 10, 13):
        assert f"probegen: note {program}:{line}: " in err


CONSTRUCT = """DMISMN/'CAMIO CONSTRUCTIONS'
UNITS/MM,ANGDEC
SNSET/APPRCH,3
SNSET/SEARCH,3
SNSET/RETRCT,3
GOTO/CART,0,0,30
F(PNT001)=FEAT/POINT,CART,0,0,12.5,0,0,1
MEAS/POINT,F(PNT001),1
PTMEAS/CART,0,0,12.5,0,0,1
ENDMES
GOTO/CART,20,0,30
GOTO/CART,20,0,0
F(PNT002)=FEAT/POINT,CART,12.5,0,0,1,0,0
MEAS/POINT,F(PNT002),1
PTMEAS/CART,12.5,0,0,1,0,0
ENDMES
GOTO/CART,20,20,0
F(PNT003)=FEAT/POINT,CART,0,12.5,0,0,1,0
MEAS/POINT,F(PNT003),1
PTMEAS/CART,0,12.5,0,0,1,0
ENDMES
GOTO/CART,-20,20,0
F(PNT004)=FEAT/POINT,CART,-12.5,0,0,-1,0,0
MEAS/POINT,F(PNT004),1
PTMEAS/CART,-12.5,0,0,-1,0,0
ENDMES
GOTO/CART,0,0,60
F(PNT001_Décalé)=FEAT/POINT,CART,0,0,0,0,0,1
CONST/POINT,F(PNT001_Décalé),MOVEPT,FA(PNT001),0,0,-12.5
F(PLN_Equateur)=FEAT/PLANE,CART,0,0,0,0,0,1
CONST/PLANE,F(PLN_Equateur),BF,FA(PNT002),FA(PNT003),FA(PNT004)
F(LINE001)=FEAT/LINE,UNBND,CART,0,0,0,1,0,0,0,0,1
CONST/LINE,F(LINE001),BF,FA(PNT004),FA(PNT002)
F(PLN_Haut)=FEAT/PLANE,CART,0,0,12.5,0,0,1
CONST/PLANE,F(PLN_Haut),PARTO,FA(PLN_Equateur),THRU,FA(PNT001)
F(PNT_Milieu)=FEAT/POINT,CART,0,0,0,0,0,1
CONST/POINT,F(PNT_Milieu),BF,FA(PNT002),FA(PNT004)
DATDEF/FA(PLN_Equateur),DAT(A)
DATDEF/FA(LINE001),DAT(B)
DATDEF/FA(PNT_Milieu),DAT(C)
D(Ref)=DATSET/DAT(A),ZDIR,ZORIG,DAT(B),XDIR,YORIG,DAT(C),XORIG
OUTPUT/FA(PNT001_Décalé),FA(PLN_Equateur),FA(LINE001),FA(PLN_Haut),FA(PNT_Milieu)
ENDFIL
"""
CONSTRUCTED = {"PNT001_DÉCALÉ": (0, 0, 0, 0, 0, 1), "PLN_EQUATEUR": (0, 0, 0, 0, 0, 1),
               "LINE001": (0, 0, 0, 1, 0, 0), "PLN_HAUT": (0, 0, 12.5, 0, 0, 1),
               "PNT_MILIEU": (0, 0, 0, 0, 0, 1)}


def test_camio_constructions_on_the_cmm_and_through_post(tmp_path: Path) -> None:
    """MOVEPT, BF (point, line, plane) and PARTO ... THRU, and a DATSET on them: the
    sphere's touched points give the planted truth on the virtual CMM and through post
    + the virtual machine + the evaluation."""
    program = parse_dmis(CONSTRUCT, source="<c>")
    on = run_dmis(program, CmmAdapter(vm()), home=HOME)
    out = post_dmis(program, PROFILE)
    assert out.skipped == () and len(out.touches) == 4
    source = tmp_path / "construct.dmi"
    source.write_text(CONSTRUCT, encoding="utf-8")
    posted_file = post_file(source, PROFILE, model(), dialect="fanuc")
    run = run_text(posted_file.text, vm(), kind="macrob", source="c.nc")
    assert run.alarm is None and run.touches == 4
    evaluated = evaluate_log(parse_dprnt(run.output, strict=True), posted_file.fmap)
    for result in (on, evaluated):
        for name, truth in CONSTRUCTED.items():
            feature = result.features[name]
            got = (*feature.location, *(feature.vector or ()))
            assert got == pytest.approx(truth, abs=1e-4), name  # the log's 4 decimals

