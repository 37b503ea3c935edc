"""Every DPRNT statement our Fanuc programs contain prints a line the log reader accepts.

Each ``DPRNT[...]`` of the golden programs is rendered as a Fanuc control prints it
(``*`` as a blank, ``#n[ab]`` as a number with ``b`` decimals, leading zeros as blanks),
then the whole log is parsed: no diagnostics, and every record comes back.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from conftest import REPO

from probegen.results import parse_dprnt

PROGRAMS = sorted(p for p in (REPO / "tests" / "golden").glob("*/*.nc")
                  if p.parent.name not in ("macros", "split", "orient", "setups"))
"""The golden inline programs (as tests/test_macrob.py ``GOLDENS``: the library, compact,
split, hand-made orientation and setup programs are run by their own tests)."""
VAR = re.compile(r"#(\d+)\[(\d)(\d)\]")


def render(statement: str, value: float) -> str:
    def number(m: re.Match[str]) -> str:
        digits, decimals = int(m.group(2)), int(m.group(3))
        text = f"{abs(value):.{decimals}f}".rjust(digits + decimals + 1)
        return ("-" if value < 0 else " ") + text

    return VAR.sub(number, statement).replace("*", " ")


@pytest.mark.parametrize("path", PROGRAMS, ids=lambda p: p.name)
def test_program_log_lines_parse(path: Path) -> None:
    text = path.read_text()
    statements = re.findall(r"^DPRNT\[(.*)\]$", text, flags=re.M)
    assert statements[0].startswith("PGSTART") and statements[-1].startswith("PGEND")
    lines = [render(s, -12.3456 if k % 2 else 7.5) for k, s in enumerate(statements)]
    log = parse_dprnt("%\n" + "\n".join(lines) + "\n%\n", source=path.name)
    assert log.diagnostics == ()
    assert log.complete
    n_touch = sum(s.startswith(("PT", "LOC")) for s in statements)
    n_err = sum(s.startswith("ERR") for s in statements)
    assert (len(log.touches), len(log.errors)) == (n_touch, n_err)
    assert n_touch == text.count("F300.") and n_err == text.count("#3000=")
