"""Every sample's DMIS program runs on the virtual CMM (issue 19: every dialect's program of
every sample runs on a virtual machine).

Each sample spec with features is compiled to DMIS; the program runs on the virtual CMM
with the part at its nominal placement and the spec's ball, ends without an alarm, notes
nothing about its own probe definition (``SNSDEF/PROBE,INDEX,POL,0,0,...``: the stylus
straight down), touches the part exactly as often as the plan says, and writes an output
file the strict reader takes.  The one sample DMIS cannot express is named with its
reason.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO

from probegen import ir
from probegen.cli.app import main
from probegen.errors import ExitCode, UnsupportedError
from probegen.planning import plan_program
from probegen.results import parse_dmis_output
from probegen.spec.model import load_spec

SPECS = sorted(p.relative_to(REPO) for p in (REPO / "samples").glob("*/*.toml")
               if "[[feature]]" in p.read_text(encoding="utf-8"))
REFUSED = {"bore_block_actions": "cannot express on_out_of_tolerance"}
"""Samples the DMIS dialect refuses, with the words of the refusal: an in-process alarm
is a machine tool's (a CMM reports OUTOL)."""


def test_the_samples_are_here() -> None:
    assert len(SPECS) == 10


@pytest.mark.parametrize("spec_path", SPECS, ids=lambda p: p.stem)
def test_sample_dmis_program_runs_on_the_virtual_cmm(
        in_repo: Path, spec_path: Path, tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    program = tmp_path / f"{spec_path.stem}.dmi"
    code = main(["-q", "compile", str(spec_path), "-d", "dmis", "-o", str(program)])
    if spec_path.stem in REFUSED:
        assert code == UnsupportedError.exit_code
        assert REFUSED[spec_path.stem] in capsys.readouterr().err
        return
    assert code == ExitCode.OK
    output = tmp_path / "out.dms"
    assert main(["-q", "sim", str(program), "--spec", str(spec_path), "-o",
                 str(output)]) == ExitCode.OK
    err = capsys.readouterr().err
    assert "SNSDEF" not in err  # its own probe, straight down: nothing to note
    planned = plan_program(load_spec(spec_path), runtime_variables=False).program
    touches = sum(isinstance(n, ir.Touch) for n in ir.walk(planned.body))
    assert touches > 0 and f"({touches} touches)" in err
    assert parse_dmis_output(output.read_text(encoding="latin-1"), strict=True) is not None
