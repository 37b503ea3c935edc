"""Locate the shipped grammars and templates.

In a source checkout they live at the top level (``grammars/``, ``templates/``); in an
installed wheel they are the data packages ``probegen._grammars`` and
``probegen._templates``.  This module is the one place that knows both.
"""

from __future__ import annotations

import functools
from importlib import resources
from importlib.abc import Traversable
from pathlib import Path

_CHECKOUT = Path(__file__).resolve().parent.parent


@functools.cache
def _root(kind: str) -> Traversable:
    local = _CHECKOUT / kind
    if local.is_dir() and (_CHECKOUT / "pyproject.toml").is_file():
        return local
    return resources.files(f"probegen._{kind}")


def grammar_text(name: str) -> str:
    """Return the text of ``grammars/<name>.lark``."""
    return _root("grammars").joinpath(f"{name}.lark").read_text(encoding="utf-8")


def templates_root() -> Traversable:
    """Return the directory holding ``<dialect>/*.j2`` templates."""
    return _root("templates")


def template_text(dialect: str, name: str) -> str:
    """Return the text of ``templates/<dialect>/<name>``."""
    return templates_root().joinpath(dialect).joinpath(name).read_text(encoding="utf-8")
