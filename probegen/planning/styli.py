"""Which stylus of the rack measures a feature (issue 17).

The rule a CMM programmer follows: the largest ball that reaches every point with the
margin (a larger ball filters the surface's roughness less, bends less and is less
likely to break), and of two equal balls the shorter stylus (stiffer; the longer one is
tried next, for the depth it reaches).  :func:`pick_stylus` plans the feature with each
stylus in that order (the caller's ``plan_with``, handed ``machine.with_stylus(s)``) and
keeps the first plan that succeeds; a spec's ``stylus = "D2"`` forces one.  It is the
one choice of the whole planner (:mod:`probegen.planning.oriented` plans every revolved
feature through it, in each orientation it tries).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import TypeVar

from probegen.errors import PlanningError, SpecError
from probegen.machine.profile import MachineProfile, Stylus
from probegen.machine.rack import is_star, star_refusal
from probegen.planning.text import Text

T = TypeVar("T")

SAID_LENGTH = 90
"""Longest excerpt of each stylus's error in the message when none plans, characters."""
NONE_PLANS = "the smallest stylus; no stylus of the rack plans it, largest first: "
"""What the message of a feature no stylus plans says after the smallest stylus's own
error and its label (:func:`own_reason` cuts there)."""


def rack_order(machine: MachineProfile) -> tuple[Stylus, ...]:
    """Every stylus of ``machine`` the planner takes, in the order they are tried:
    largest ball first, then shorter, then thicker shank, then label (repeatable).  A
    star stylus (a tip ``offset`` off the probe axis) is not among them
    (:data:`probegen.machine.rack.STAR_REFUSAL`)."""
    return tuple(sorted((s for s in machine.styli() if not is_star(s)),
                        key=lambda s: (-s.ball_diameter, s.length, -s.shank_diameter,
                                       s.label)))


def smallest_stylus(machine: MachineProfile) -> Stylus:
    """The stylus tried last: the smallest ball (and of equal balls the longest, which
    reaches deepest); what a feature too small for the whole rack is left out for."""
    return rack_order(machine)[-1]


def stylus_named(machine: MachineProfile, label: str, where: str) -> Stylus:
    """The stylus labelled ``label``.

    Raises:
        SpecError: no stylus of the profile has it, or a star stylus has it
            (:data:`probegen.machine.rack.STAR_REFUSAL`); names ``where`` and the labels.
    """
    star = star_refusal(machine.styli(), label, machine.source)
    if star is not None:
        raise SpecError(f"{where}: {star}: expected one of "
                        f"{', '.join(t.label for t in rack_order(machine))}")
    for s in machine.styli():
        if s.label == label:
            return s
    labels = ", ".join(s.label for s in rack_order(machine))
    raise SpecError(f"{where}: expected a stylus of the machine's rack ({labels}; "
                    f"{machine.source}: [[probe.stylus]]), found {label!r}")


def pick_stylus(machine: MachineProfile, plan_with: Callable[[MachineProfile], T],
                force: str | None = None) -> tuple[Stylus, T]:
    """The stylus a feature is measured with, and its plan.

    Args:
        machine: the profile; its rack (``machine.styli()``) is tried in
            :func:`rack_order`.
        plan_with: plans the feature on a profile (``machine.with_stylus(s)``; the
            profile itself for its ``[probe]`` stylus); raises ``PlanningError`` (or
            ``CollisionError``) when it cannot.
        force: a stylus label (a spec's ``stylus`` key): plan with that one only.

    Returns:
        The first stylus whose plan succeeds, and that plan.

    Raises:
        SpecError: ``force`` names no stylus of the rack.
        PlanningError: no stylus plans the feature: the error of the smallest stylus (of
            its class; the one the user can act on: a smaller stylus or the part), naming
            it, with what each stylus said; any other error of ``plan_with`` (a
            ``ModelError``, a ``SpecError`` of the spec or of a calibration without the
            stylus) goes through at once.
    """
    if force is not None:
        s = stylus_named(machine, force, "stylus")
        return s, plan_with(profile_with(machine, s))
    failures: list[tuple[Stylus, PlanningError]] = []
    for s in rack_order(machine):
        try:
            return s, plan_with(profile_with(machine, s))
        except PlanningError as exc:
            failures.append((s, exc))
    raise _none_plans(failures)


def profile_with(machine: MachineProfile, s: Stylus) -> MachineProfile:
    """``machine`` with ``s`` as its probe's stylus (itself for its ``[probe]`` stylus)."""
    return machine if s == machine.stylus else machine.with_stylus(s)


LAZY = True
"""Whether the message of a feature no stylus plans (:func:`_none_plans`) is made when
it is first read (:class:`~probegen.planning.text.Text`): each stylus's error then
measures what its refused moves ran into only for a message a user reads, not for a
feature the probe along its axis does not reach and a leaning index then does (the
same text either way; ``benchmarks/bench_lazy_styli.py`` times both)."""


def _none_plans(failures: list[tuple[Stylus, PlanningError]]) -> PlanningError:
    """The smallest stylus's error (the most permissive stylus: what the user acts on),
    naming it, with a sentence of what every stylus said (one stylus: its error
    unchanged); the message made when first read (:data:`LAZY`)."""
    smallest, last = failures[-1]
    if len(failures) == 1:
        return last

    def message() -> str:
        said_by = [(str(exc), type(exc).__name__) for _, exc in failures]
        texts = [text.splitlines()[0] if text else name for text, name in said_by]
        # the common lead up to its last ": " before any parenthesis (a detail in
        # parentheses, such as the touch a collision dropped, is each stylus's own)
        common = os.path.commonprefix(texts).split(" (", 1)[0]
        cut = common.rfind(": ") + 2 if ": " in common else 0
        said = "; ".join(f"{s.label} (ball {s.ball_diameter:g} mm): {_short(text[cut:])}"
                         for (s, _), text in zip(failures, texts, strict=True))
        return f"{said_by[-1][0]} (with {smallest.label}, {NONE_PLANS}{said})"

    text = Text(message)
    return type(last)(text if LAZY else str(text))


def own_reason(message: str) -> str:
    """The smallest stylus's own error of a :func:`pick_stylus` message where no stylus
    plans (without what each stylus said, whose texts would be taken for its reason);
    any other message unchanged."""
    at = message.find(NONE_PLANS)
    if at < 0:
        return message
    return message[:message.rfind(" (with ", 0, at)]


def _short(text: str) -> str:
    """``text`` cut to :data:`SAID_LENGTH` characters at a word."""
    if len(text) <= SAID_LENGTH:
        return text
    return text[:SAID_LENGTH].rsplit(" ", 1)[0] + " ..."
