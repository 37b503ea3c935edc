"""Alarm messages within the control's limit (``MacroB.ALARM_TEXT_LENGTH``, 26 on Fanuc;
docs/actions.md): probegen's own texts shorten deterministically, the feature id whole;
any longer ``#3000``/``#3006`` message is refused at compile time."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from conftest import REPO

from probegen.dialects import Fanuc, Haas, get_dialect
from probegen.dialects.fanuc_actions import SHORT_TEXTS, alarm_text
from probegen.errors import UnsupportedError
from probegen.planning import plan_program
from probegen.spec.model import load_spec

SPEC = REPO / "samples/bore_block/bore_block_actions.toml"
MESSAGE = re.compile(r"^#300[06]=\d+\((.*)\)$", re.M)


def test_the_limit_is_fanucs_and_haas_inherits_it() -> None:
    assert Fanuc.ALARM_TEXT_LENGTH == 26 and Haas.ALARM_TEXT_LENGTH == 26


@pytest.mark.parametrize(("feature", "text", "message"), [
    ("BORE", "TOOL CORR TOO BIG", "BORE TOOL CORR TOO BIG"),           # 22: whole
    ("BORE12345", "TOOL CORR TOO BIG", "BORE12345 BIGCORR"),           # 27: short
    ("HOUSINGBORE1", "TOOL CORR TOO BIG", "HOUSINGBORE1 BIGCORR"),
    ("BOSSDIAMETER", "NO CIRCLE FIT", "BOSSDIAMETER NO CIRCLE FIT"),   # 26 exactly
    ("HOUSINGBORE1", "OUT OF TOL", "HOUSINGBORE1 OUT OF TOL"),
])
def test_the_text_shortens_and_the_id_stays_whole(feature: str, text: str,
                                                  message: str) -> None:
    assert alarm_text(Fanuc(), feature, text) == message
    assert len(message) <= 26


def test_every_short_form_fits_a_twelve_character_id() -> None:
    """Spec ids have at most 12 characters: no spec can be refused at 26."""
    assert all(len(f"{'X' * 12} {short}") <= 26 for short in SHORT_TEXTS.values())


def test_too_long_even_when_short_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    """A control with 12-character messages (the limit is the dialect's constant)."""
    monkeypatch.setattr(Haas, "ALARM_TEXT_LENGTH", 12)
    assert alarm_text(Haas(), "EDGE", "OUT OF TOL") == "EDGE OUTTOL"
    with pytest.raises(UnsupportedError, match=r"dialect 'haas': feature HOUSINGBORE1: "
                       r"expected an alarm message of at most 12 characters, found 20: "
                       r"'HOUSINGBORE1 BIGCORR'; use a shorter feature id"):
        alarm_text(Haas(), "HOUSINGBORE1", "TOOL CORR TOO BIG")
    assert alarm_text(Fanuc(), "HOUSINGBORE1", "OUT OF TOL") == "HOUSINGBORE1 OUT OF TOL"


def test_any_long_message_in_the_text_is_refused() -> None:
    Fanuc().check_messages("#3000=1(" + "A" * 26 + ")\n#3006=1(STOP)\n")
    with pytest.raises(UnsupportedError, match=r"line 2: expected an alarm message of at "
                                               r"most 26 characters, found 27: 'A{27}'"):
        Fanuc().check_messages("G0 X0\n#3006=1(" + "A" * 27 + ")\n")


@pytest.mark.parametrize("dialect", ["fanuc", "haas"])
def test_long_feature_ids_compile_within_the_limit(tmp_path: Path, dialect: str) -> None:
    text = SPEC.read_text(encoding="utf-8")
    stop = 'on_out_of_tolerance = "{}"\nalign'
    for old, new in (('id = "BORE"', 'id = "HOUSINGBORE1"'),
                     ('id = "BOSS"', 'id = "BOSSDIAMETER"'),
                     ('id = "EDGE"', 'id = "FRONTEDGE123"'),
                     (stop.format("alarm"), stop.format("stop")),
                     ('"../machines/', f'"{REPO}/samples/machines/'),
                     ('"bore_block.step"', f'"{REPO}/samples/bore_block/bore_block.step"')):
        assert old in text
        text = text.replace(old, new)
    spec = tmp_path / "spec.toml"
    spec.write_text(text, encoding="utf-8")
    program = get_dialect(dialect).generate(
        plan_program(load_spec(spec), runtime_variables=True).program)
    messages = MESSAGE.findall(program)
    assert max(len(m) for m in messages) == 26
    assert {"HOUSINGBORE1 BIGCORR", "HOUSINGBORE1 OUT OF TOL", "BOSSDIAMETER NO CIRCLE FIT",
            "FRONTEDGE123 OUT OF TOL"} <= set(messages)
    assert "#3006=1(FRONTEDGE123 OUT OF TOL)" in program
