"""A message made when it is first read: planning tries and drops many attempts (another
retract, section, stylus or head index), and what each refused attempt ran into is
measured (how deep the stylus cuts into the part: :func:`probegen.planning.collision.describe`)
only for the messages a user reads."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

__all__ = ["Text"]


class Text:
    """A message made when it is first read (``str``, ``format``), then kept: what a
    refused move ran into is measured (:func:`probegen.planning.collision.describe`:
    how deep the stylus cuts into the part) only for the messages a user reads, not for
    each of the many attempts a planner tries and drops (another retract, section,
    stylus or head index).  The same text either way."""

    __slots__ = ("_make", "_text")

    def __init__(self, make: Callable[[], str]) -> None:
        self._make: Callable[[], str] | None = make
        self._text: str | None = None

    def __str__(self) -> str:
        if self._text is None:
            assert self._make is not None
            self._text, self._make = self._make(), None
        return self._text

    def __format__(self, spec: str) -> str:
        return format(str(self), spec)

    def __repr__(self) -> str:
        return f"Text({str(self)!r})"

    @classmethod
    def format(cls, template: str, *args: object) -> Text:
        """``template.format(*args)`` when first read (a :class:`Text` among ``args``
        read then)."""
        return cls(partial(template.format, *args))
