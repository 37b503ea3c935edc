"""DMIS as CMM software writes it: the corpus in tests/dmis_corpus/.

Each program there was written for these tests in the style of one vendor (no file is
copied from anywhere) and measures the same five points on the sample sphere (D25 at the
origin, samples/sphere25) as ``flat.dmi``, its flat twin written plainly:

* ``lk_camio.dmi``: LK CAMIO habits: Latin-1, CRLF, every line longer than 80 characters
  wrapped at column 80 with ``$`` (mid-word, mid-number, inside strings and labels), long
  ``$$`` comments wrapped the same way, labels with ``é``, ``Ø``, ``.`` and ``-``, and the
  sensor as ``RECALL/SA`` + ``SNSLCT/SA`` (the machine's calibrated stylus).
* ``pcdmis.dmi``: a PC-DMIS export: UTF-8 with BOM, CRLF, lower-case keywords, indented
  continuation lines, a probe tip ``SNSDEF`` of diameter 0 (the machine's stylus).
* ``modus.dmi``: Renishaw MODUS habits: Latin-1 labels (ø, ü, É), numbers and labels split
  with ``$`` in the middle.

Truth: the flat twin.  Every program gives the flat twin's touches, touch for touch, on
the virtual CMM and through ``probegen post`` + the virtual machine, to 1e-6 mm.
"""

from __future__ import annotations

import random
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from fuzzing import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mutations import mutate

from probegen import cad
from probegen.cli.app import main
from probegen.dmis.reader import (
    DmisFile,
    logical_statements,
    parse_dmis,
    parse_dmis_recovering,
    read_dmis,
    read_dmis_all,
    read_dmis_text,
)
from probegen.errors import ProgramParseError, UnsupportedError
from probegen.machine.probe_model import Lobing, ProbeModel
from probegen.machine.profile import load_profile
from probegen.post.evaluate import evaluate_log
from probegen.post.featuremap import read_feature_map
from probegen.post.files import PostOutput, post_file
from probegen.results import parse_dprnt
from probegen.sim.cmm.interpreter import DmisRunResult, run_dmis
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import CmmAdapter, VirtualMachine, run_text

CORPUS = REPO / "tests" / "dmis_corpus"
FLAT = CORPUS / "flat.dmi"
PROGRAMS = ["lk_camio.dmi", "pcdmis.dmi", "modus.dmi"]
MODEL = REPO / "samples" / "sphere25" / "sphere25.step"
PROFILE = load_profile(REPO / "samples" / "post" / "vmc-fanuc-d4.toml")
HOME = (0.0, 0.0, 100.0)
NOTES = {"lk_camio.dmi": 2, "pcdmis.dmi": 1, "modus.dmi": 0}


@cache
def model() -> cad.Part:
    return cad.load_part(MODEL)


def vm() -> VirtualMachine:
    """The virtual machine with the sphere at the origin and a 4 mm ball, no errors."""
    return VirtualMachine(PlacedPart.from_model(cad.load_step(MODEL)),
                          ProbeModel(2.0, Lobing(0.0, 0.0, 0.0)))


def on_cmm(program: Path | DmisFile | str, **kwargs: object) -> DmisRunResult:
    parsed = read_dmis(program) if isinstance(program, Path) else program
    result = run_dmis(parsed, CmmAdapter(vm()), home=HOME, **kwargs)  # type: ignore[arg-type]
    assert result.alarm is None, result.alarm
    return result


@cache
def posted(name: str) -> PostOutput:
    return post_file(CORPUS / name, PROFILE, model(), dialect="fanuc")


def features(result: DmisRunResult) -> list[np.ndarray]:
    """Every feature's numbers in program order (names differ between the twins)."""
    return [np.array([*f.location, *(f.vector if f.vector is not None else ()),
                      f.size if f.size is not None else 0.0])
            for f in result.features.values()]


def assert_same(a: DmisRunResult, b: DmisRunResult) -> None:
    fa, fb = features(a), features(b)
    assert len(fa) == len(fb) == 1
    for x, y in zip(fa, fb, strict=True):
        np.testing.assert_allclose(x, y, atol=1e-6)


# ------------------------------------------------------------------ reading the corpus


@pytest.mark.parametrize("name", PROGRAMS)
def test_program_reads_as_its_flat_twin(name: str) -> None:
    """The motions and touches parse to exactly the flat twin's (labels aside)."""
    moves = [(s.major, s.params) for s in read_dmis(CORPUS / name).statements
             if s.major in ("GOTO", "PTMEAS")]
    flat = [(s.major, s.params) for s in read_dmis(FLAT).statements
            if s.major in ("GOTO", "PTMEAS")]
    assert moves == flat and len(flat) == 12


def test_lk_camio_wraps_words_numbers_strings_labels_and_comments() -> None:
    dmis = read_dmis(CORPUS / "lk_camio.dmi")
    first = dmis.statements[0]
    assert first.major == "DMISMN" and first.line == 1
    assert str(first.params[0]).endswith("(lignes coupées à 80)'")  # a string split at col 80
    feat = next(s for s in dmis.statements if s.major == "FEAT")
    assert str(feat.label) == "F(SPH_RÉFØ25-A.1)" and feat.params[-1] == 25.0
    assert [s.line for s in dmis.statements if s.major == "MEAS"] == [21]
    history = next(text for line, text in dmis.comments if line == 7)
    assert history.endswith("quatre-vingts caractères est coupée par un dollar, comme CAMIO le "
                            "fait")  # a wrapped comment is one comment, the next line its text
    assert [s.major for s in dmis.statements[4:6]] == ["RECALL", "SNSLCT"]


def test_encodings_read_the_same(tmp_path: Path) -> None:
    """UTF-8, UTF-8 with BOM and Latin-1 give the same statements, by every reader."""
    text = read_dmis_text(CORPUS / "modus.dmi")
    variants = {"utf8.dmi": text.encode(), "bom.dmi": b"\xef\xbb\xbf" + text.encode(),
                "latin1.dmi": text.encode("latin-1")}
    parsed = []
    for file, data in variants.items():
        (tmp_path / file).write_bytes(data)
        assert read_dmis_text(tmp_path / file) == text
        parsed.append([(s.label, s.major, s.params) for s in read_dmis(tmp_path / file).statements])
    assert parsed[0] == parsed[1] == parsed[2]


def test_sim_command_reads_bom_and_latin1(tmp_path: Path) -> None:
    """``probegen sim`` on a DMIS file with a BOM or Latin-1 labels (it read ASCII before)."""
    outputs = []
    for name in ("pcdmis.dmi", "modus.dmi"):
        out = tmp_path / f"{name}.dmo"
        code = main(["sim", str(CORPUS / name), "--part", str(MODEL), "--machine",
                     str(REPO / "samples" / "post" / "vmc-fanuc-d4.toml"), "-o", str(out)])
        assert code == 0
        outputs.append(out.read_text(encoding="utf-8", errors="replace"))
    for text in outputs:
        assert "ENDFIL" in text and "SPHERE" in text


# --------------------------------------------------------------- the virtual CMM and post


@pytest.mark.parametrize("name", PROGRAMS)
def test_virtual_cmm_measures_as_the_flat_twin(name: str) -> None:
    result, flat = on_cmm(CORPUS / name), on_cmm(FLAT)
    assert_same(result, flat)
    assert len(result.notes) == NOTES[name]
    assert all("machine's calibrated stylus D4 mm" in n.reason for n in result.notes)
    sphere = features(flat)[0]
    assert sphere[-1] == pytest.approx(25.0, abs=1e-6)


@pytest.mark.parametrize("name", PROGRAMS)
def test_post_touches_as_the_flat_twin_and_evaluates_as_the_cmm(name: str) -> None:
    out, flat = posted(name), posted("flat.dmi")
    assert len(out.fmap.touches) == len(flat.fmap.touches) == 5
    for a, b in zip(out.fmap.touches, flat.fmap.touches, strict=True):
        np.testing.assert_allclose(a.start, b.start, atol=1e-6)
        np.testing.assert_allclose(a.direction, b.direction, atol=1e-6)
        assert a.reach == pytest.approx(b.reach, abs=1e-6)
    assert len(out.posted.notes) == NOTES[name] and out.fmap.notes == tuple(
        (n.line, n.text, n.reason) for n in out.posted.notes)
    res = run_text(out.text, vm(), kind="macrob", source=name)
    assert res.alarm is None and res.touches == 5
    evaluated = evaluate_log(parse_dprnt(res.output, strict=True), out.fmap)
    assert_same(evaluated, on_cmm(CORPUS / name))


def test_a_sensor_ball_other_than_the_machines_is_refused_not_mismeasured() -> None:
    """A 6 mm SNSDEF on the 4 mm virtual CMM used to compensate 3 mm while touching with
    2 mm: a silent 2 mm size error.  Now it is refused, or skipped with the flag."""
    text = FLAT.read_text().replace("-1,4.0", "-1,6.0")
    with pytest.raises(UnsupportedError, match=r"sensor's ball is D6 mm, the machine's "
                                               r"stylus D4 mm"):
        on_cmm(parse_dmis(text, source="six.dmi"))
    skipped = on_cmm(parse_dmis(text), skip_unsupported=True)
    assert [s.text for s in skipped.skipped] == ["SNSLCT/S(P)"]
    assert_same(skipped, on_cmm(FLAT))


# ------------------------------------------------------------------------- recovery


def test_every_bad_statement_is_located_and_the_rest_read(tmp_path: Path) -> None:
    lines = FLAT.read_text().splitlines()
    lines[4] = "D(M)=DATSET/MCS ?"
    lines.insert(9, "Mettre en place l'échelle")
    path = tmp_path / "bad.dmi"
    path.write_text("\n".join(lines) + "\n", encoding="latin-1")
    dmis, diagnostics = parse_dmis_recovering(read_dmis_text(path), source=str(path))
    assert [(d.line, d.column, d.text) for d in diagnostics] == [
        (5, 17, "D(M)=DATSET/MCS ?"), (10, 8, "Mettre en place l'échelle")]
    assert len(dmis.statements) == len(lines) - 2
    with pytest.raises(ProgramParseError) as info:
        read_dmis_all(path)
    assert str(info.value).startswith(f"{path}: 2 statements do not parse:\n{path}:5:17: ")
    assert f"{path}:10:8: " in str(info.value)


def test_wrapped_comment_never_swallows_a_statement() -> None:
    text = "$$ a comment that ends in a dollar $\nGOTO/1,2,3\n$$ wrapped $\ntext\nENDMES\n"
    dmis = parse_dmis(text)
    assert [(s.line, s.major) for s in dmis.statements] == [(2, "GOTO"), (5, "ENDMES")]
    assert dmis.comments == ((1, "a comment that ends in a dollar $"), (3, "wrapped text"))
    banner = parse_dmis("$$$$$$$$$$$$\nGOTO/1,2,3\n")
    assert [s.major for s in banner.statements] == ["GOTO"]


def test_keywords_and_labels_are_case_insensitive() -> None:
    a = parse_dmis("f(kugel_ø.1-a)=feat/point,cart,1,2,3,0,0,1\n").statements[0]
    b = parse_dmis("F(KUGEL_Ø.1-A)=FEAT/POINT,CART,1,2,3,0,0,1\n").statements[0]
    assert (a.label, a.major, a.params) == (b.label, b.major, b.params)


# ----------------------------------------------------------------------- properties

SOURCES = [read_dmis_text(CORPUS / n) for n in [*PROGRAMS, "flat.dmi"]]


def split_at(text: str, seed: int, count: int) -> str:
    """``text`` with ``$`` + line end inserted at ``count`` random places of statement
    lines (lines without ``$``), as a vendor's line wrapping does."""
    rng = random.Random(seed)
    lines = text.split("\n")
    for _ in range(count):
        candidates = [k for k, line in enumerate(lines) if line and "$" not in line]
        if not candidates:
            break
        k = rng.choice(candidates)
        cut = rng.randint(0, len(lines[k].rstrip("\r")))
        lines[k : k + 1] = [lines[k][:cut] + "$", lines[k][cut:]]
    return "\n".join(lines)


def shapes(dmis: DmisFile) -> list[tuple[object, ...]]:
    return [(s.label, s.major, s.params) for s in dmis.statements]


@settings(max_examples=examples(100))
@given(st.sampled_from(SOURCES), st.integers(0, 2**32), st.integers(1, 30))
def test_dollar_split_program_reads_as_the_unsplit(text: str, seed: int, count: int) -> None:
    split = split_at(text, seed, count)
    assert shapes(parse_dmis(split)) == shapes(parse_dmis(text))
    assert len(logical_statements(split)) == len(logical_statements(text))


ALPHABET = "$$$'' \n\r\t,/()=.-_éØüF0123456789ASGOTPMEX\ufeff"


def located(text: str) -> None:
    lines = max(1, text.count("\n") + text.count("\r") + 1)
    try:
        dmis = parse_dmis(text, source="m")
    except ProgramParseError as exc:
        assert exc.diagnostics and all(1 <= d.line <= lines for d in exc.diagnostics)
    else:
        assert all(1 <= s.line <= lines for s in dmis.statements)
    recovered, diagnostics = parse_dmis_recovering(text, source="m")
    assert all(1 <= d.line <= lines and d.column >= 1 for d in diagnostics)
    assert all(1 <= s.line <= lines for s in recovered.statements)


@settings(max_examples=examples(200), suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_mutated_statements_and_continuations_end_in_a_result_or_a_located_error(
        data: st.DataObject) -> None:
    source = data.draw(st.sampled_from(SOURCES))
    text = data.draw(st.composite(lambda draw: mutate(draw, source, ALPHABET, most=12))())
    located(text)


@settings(max_examples=examples(200))
@given(st.text(ALPHABET, max_size=200))
def test_random_text_ends_in_a_result_or_a_located_error(text: str) -> None:
    located(text)


def test_cli_post_prints_and_writes_notes_and_skipped(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``post`` prints every noted and skipped statement and writes them in the map
    (an SNSET word it does not know is refused without --skip-unsupported; VFORM, the
    CMM's report format, is skipped with its reason without it: test_dmis_vendor.py)."""
    program = tmp_path / "lk.dmi"
    text = read_dmis_text(CORPUS / "lk_camio.dmi").replace(
        "MODE/PROG,MAN", "SNSET/SCALE,2")
    program.write_bytes(text.encode("latin-1"))
    args = ["post", str(program), "--machine", str(REPO / "samples/post/vmc-fanuc-d4.toml"),
            "--model", str(MODEL), "-o", str(tmp_path / "lk.nc")]
    assert main(args) != 0
    assert f"{program}:5: " in capsys.readouterr().err
    assert main([*args, "--skip-unsupported"]) == 0
    err = capsys.readouterr().err
    assert f"probegen: skipped {program}:5: SNSET/SCALE,2" in err
    assert f"probegen: note {program}:10: RECALL/SA(Étoile_Zd2-Z_A90.0_B90.0) (SA(ÉTOILE_" \
        in err
    saved = read_feature_map(tmp_path / "lk.features.json")
    assert [row[0] for row in saved.skipped] == [5]
    assert [row[0] for row in saved.notes] == [10, 11]
    assert all(row[2].endswith("mapped to the machine's calibrated stylus D4 mm")
               for row in saved.notes)


def test_virtual_cmm_lists_every_bad_statement() -> None:
    text = FLAT.read_text().replace("UNITS/MM,ANGDEC", "UNITS/MM,ANGDEC ?").replace(
        "ENDMES", "ENDMES\n/oops")
    with pytest.raises(ProgramParseError) as info:
        run_dmis(text, CmmAdapter(vm()), source="two.dmi")
    assert [(d.line, d.column) for d in info.value.diagnostics] == [(2, 17), (23, 1)]
    assert str(info.value).startswith("two.dmi: 2 statements do not parse:\ntwo.dmi:2:17: ")
