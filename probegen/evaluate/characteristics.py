"""Characteristics and their verdicts: what every evaluated feature reports.

A :class:`Characteristic` is one checked quantity (measured, nominal, deviation, limits,
uncertainty); a feature's verdict is :func:`accepted` over its characteristics, a run's
status :func:`run_status` over its features (the status strings and their meaning:
docs/results.md).  The kinds' evaluations (sphere test, revolved, planar, free-form)
live in the modules beside this one and all build on it.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Protocol

from probegen.geometry.uncertainty import COVERAGE_FACTOR, decide, verdict

OK, NOT_OK, NOT_EVALUATED, UNTOLERANCED = "OK", "NOT OK", "NOT EVALUATED", "-"
"""The status strings of a characteristic, a feature and a run (``results.json``
``status``, ``results.csv``, the table, the report): within its limits; out of them;
toleranced but not evaluated (missing or no-contact touches, a failed fit, a run cut
short); not toleranced (a run: nothing toleranced at all)."""
STATUSES = (OK, NOT_OK, NOT_EVALUATED, UNTOLERANCED)


@dataclass(frozen=True, slots=True)
class Characteristic:
    """One checked quantity of a feature.

    Attributes:
        name: e.g. ``X``, ``D``, ``P_FTU``.
        measured: the measured value, mm.
        nominal: the nominal value, mm.
        deviation: measured − nominal, mm.
        lower: lowest allowed deviation, or None when not toleranced.
        upper: highest allowed deviation, or None.
        u: standard uncertainty of the value, same unit, or None when not estimated
            (``probegen.geometry.uncertainty`` says how it is found).
        method: how a form value was evaluated (``"minimum zone"``, ``"least
            squares"``), ``""`` for other characteristics.
    """

    name: str
    measured: float
    nominal: float
    deviation: float
    lower: float | None = None
    upper: float | None = None
    u: float | None = None

    @property
    def U(self) -> float | None:
        """Expanded uncertainty ``k·u`` (``k = 2``), or None."""
        return None if self.u is None else COVERAGE_FACTOR * self.u

    @property
    def decision(self) -> str | None:
        """ISO 14253-1: ``conforming``, ``non-conforming`` or ``undecided`` (the value lies
        within ``U`` of a limit); None when not toleranced."""
        return decide(self.deviation, self.lower, self.upper, self.u)

    def accepted(self, rule: str = "simple") -> bool | None:
        """The verdict under ``rule`` (``simple``: ``ok``; ``guard_band``: conforming)."""
        return verdict(self.ok, self.decision, rule)
    method: str = ""

    @property
    def ok(self) -> bool | None:
        """Within tolerance (None when not toleranced)."""
        if self.lower is None and self.upper is None:
            return None
        lo = -math.inf if self.lower is None else self.lower
        hi = math.inf if self.upper is None else self.upper
        return lo <= self.deviation <= hi


def status_of(ok: bool | None) -> str:
    """The status string of a verdict of an evaluated characteristic or feature."""
    return UNTOLERANCED if ok is None else (OK if ok else NOT_OK)


def run_status(verdicts: Iterable[bool | None], *, not_evaluated: bool,
               complete: bool) -> str:
    """The status of a whole run from its evaluated features' verdicts.

    ``NOT OK`` as soon as one evaluated feature is out of tolerance, even when others
    could not be evaluated: a nonconformity measured completely is a definite finding
    that no further measurement can reverse (the part is rejected either way).  Else
    ``NOT EVALUATED`` when a spec feature could not be evaluated or the run did not
    finish (the run cannot be signed); else ``OK`` when something is toleranced, ``-``
    when nothing is.
    """
    checks = [v for v in verdicts if v is not None]
    if not all(checks):
        return NOT_OK
    if not_evaluated or not complete:
        return NOT_EVALUATED
    return OK if checks else UNTOLERANCED


def accepted(characteristics: Iterable[Characteristic], rule: str = "simple"
             ) -> bool | None:
    """A feature's verdict under the decision ``rule`` (``simple``: every toleranced
    characteristic within its limits): None when nothing is toleranced."""
    found = [v for v in (c.accepted(rule) for c in characteristics) if v is not None]
    return all(found) if found else None


class Evaluated(Protocol):
    """What every evaluated feature result has (sphere test, revolved, free-form,
    planar)."""

    @property
    def feature(self) -> str:
        """Feature id."""
        ...

    @property
    def characteristics(self) -> tuple[Characteristic, ...]:
        """The checked quantities."""
        ...

    @property
    def points(self) -> tuple[tuple[float, float, float], ...]:
        """The contact points, mm."""
        ...

    @property
    def ok(self) -> bool | None:
        """All toleranced characteristics within limits (None if none is toleranced)."""
        ...


@dataclass(frozen=True, slots=True)
class NotEvaluated:
    """A spec feature that could not be evaluated completely: its status, and that of
    each of its toleranced characteristics, is ``NOT EVALUATED``, never OK.

    Attributes:
        feature: feature id.
        kind: feature kind (``sphere_test``, ``cylinder``, ``plane`` ...).
        reason: why, for people (``no touch for points 17-18``, ``no contact at point
            5 (ERR NOTOUCH, line 12)``, the fit's error ...).
        characteristics: names of the toleranced characteristics the spec asks for
            (as an evaluation would name them).
        limits: the ``(lower, upper)`` limits of each of ``characteristics``.
        partial: the fit of the touches there were, when they sufficed for one: shown
            for information only, its verdicts do not count.
    """

    feature: str
    kind: str
    reason: str
    characteristics: tuple[str, ...] = ()
    limits: tuple[tuple[float | None, float | None], ...] = ()
    partial: Evaluated | None = None
