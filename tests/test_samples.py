"""Every sample's committed STEP model is what its ``make_model.py`` writes, byte for byte."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO, sample_script

SAMPLES = {"sphere25": "sphere25.step", "bore_block": "bore_block.step",
           "revolved_block": "revolved_block.step", "freeform": "freeform.step"}


@pytest.mark.parametrize("sample", sorted(SAMPLES))
def test_committed_step_is_what_the_script_writes(sample: str, tmp_path: Path) -> None:
    fresh = sample_script(sample).main(tmp_path / SAMPLES[sample])
    assert fresh.read_bytes() == (REPO / "samples" / sample / SAMPLES[sample]).read_bytes()
