"""Value types of command-line options: a value outside its range is a usage error (exit
64, ``probegen: error: <command>: argument --x: expected ..., found ...``), never a
traceback from deep inside a command."""

from __future__ import annotations

import argparse
import math


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, found {text!r}") from None


def finite(text: str) -> float:
    """A finite number (no nan, no inf)."""
    value = _number(text)
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, found {text!r}")
    return value


RAISED_HELP = ("how far the part's lowest point stands above the machine table (a fixture, "
               "parallels), mm: the collision check keeps every stylus off the table that "
               "far below it (default 0: on the table)")
"""The help of ``--raised`` (``plan --all-revolved``, ``init``, ``post``)."""


def non_negative(text: str) -> float:
    """A finite number >= 0 (a noise sigma, a delay in seconds)."""
    value = finite(text)
    if value < 0.0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, found {text!r}")
    return value


def positive(text: str) -> float:
    """A finite number > 0 (a timeout in seconds)."""
    value = finite(text)
    if value <= 0.0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, found {text!r}")
    return value


def seed(text: str) -> int:
    """A random seed: a whole number >= 0."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, found {text!r}") \
            from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, found {text!r}")
    return value


def dialect_help(*, machine_tool: bool = False) -> str:
    """The dialects a ``-d`` option accepts, named from the dialect registry with what each
    writes (``machine_tool``: only those with a DPRNT-style log, i.e. not DMIS)."""
    from probegen.dialects import REGISTRY

    return "; ".join(f"{name}: {_first_line(cls.__doc__)}"
                     for name, cls in sorted(REGISTRY.items())
                     if cls.RUNTIME_VARIABLES or not machine_tool)


def _first_line(doc: str | None) -> str:
    return (doc or "").strip().splitlines()[0].rstrip(".") if doc else ""
