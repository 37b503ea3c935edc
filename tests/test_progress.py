"""Progress bars draw only on a terminal and only when not --quiet."""

from __future__ import annotations

import io

import pytest

from probegen.cli import progress


class Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_bar_draws_on_a_terminal() -> None:
    out = Tty()
    with progress.Bar("planning", 4, unit="steps", stream=out) as bar:
        for _ in range(4):
            bar(1)
    assert out.getvalue().endswith("\rplanning [" + "#" * 30 + "] 4/4 steps\n")


def test_bar_is_silent_off_a_terminal_and_when_quiet(monkeypatch: pytest.MonkeyPatch) -> None:
    out = io.StringIO()
    with progress.Bar("x", 2, stream=out) as bar:
        bar(2)
    assert out.getvalue() == ""
    monkeypatch.setattr(progress, "ENABLED", False)
    tty = Tty()
    with progress.Bar("x", 2, stream=tty) as bar:
        bar(2)
    assert tty.getvalue() == ""


def test_quiet_is_for_one_command(monkeypatch: pytest.MonkeyPatch) -> None:
    """``--quiet`` turns the bars off for its command only (test_bad_cli checks that the
    command sees them off): what runs after it in the same process draws them again."""
    from probegen.cli.app import main

    monkeypatch.setattr(progress, "ENABLED", True)
    assert main(["--quiet", "sphere-points"]) == 0
    assert progress.ENABLED is True
