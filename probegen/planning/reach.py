"""Sections a stylus reaches with the probe body clear (issue 17).

Above the stylus hangs the probe body (``[probe] body_diameter``, ``body_length``), wider
than most bores: a ball deeper below a feature's open end than its stylus is long takes
the body down into the feature.  The sections of a long feature taken at fractions of its
whole length (``revolved_plan.ALTERNATIVE_SECTIONS``: a bend 223 mm long measured from its
end at 55 % and 90 % of its length) lie beyond any stylus's reach there, while a CMM
programmer would measure it near the end the probe enters from: :func:`reach_fractions`
gives sections spread over the part of the feature the stylus reaches, the collision check
judging them as every other choice.

Conventions: the feature as recognised in the probe's frame (the probe along frame -Z,
entering from frame +Z), its extent ``(low, high)`` along its axis, mm.
"""

from __future__ import annotations

from typing import Any

from probegen.machine.profile import MachineProfile

REACH_SECTIONS = {"circle": (0.5,), "cylinder": (0.1, 0.9), "cone": (0.1, 0.9),
                  "sphere": (0.3, 0.7), "torus": (0.1, 0.5, 0.9)}
"""Sections (fractions of the reached part of the feature, from its deepest point up)."""


def reach_fractions(feature: Any, machine: MachineProfile, kind: str,
                    top: float | None = None) -> tuple[tuple[float, ...], ...]:
    """Sections of ``feature`` (fractions of its extent, low to high, as
    ``revolved_plan`` takes them) spread over the depth the stylus of ``machine`` reaches
    with the body above the feature's upper end by the margin (the stylus's length less
    the margin below that end), then (with ``top``, the frame Z of the part's top, mm)
    over the depth it reaches with the body above the whole part (a counterbore too
    narrow for the body above the feature); none without a probe body, where the stylus
    reaches the whole feature (the other sections serve), or where it reaches nothing."""
    probe = machine.probe
    if probe.body_diameter <= 0.0 or kind not in REACH_SECTIONS:
        return ()
    low, high = feature.extent
    length = high - low
    up = feature.axis[2] > 0.0  # the extent's high end is the upper one
    upper = feature.origin[2] + (high if up else low) * feature.axis[2]  # frame Z
    out: list[tuple[float, ...]] = []
    for above in (upper, *(() if top is None else (top,))):
        deepest = above + machine.margin - probe.length  # frame Z of the lowest ball
        reach = upper - max(deepest, upper - length)
        if length <= 0.0 or reach <= 0.0 or reach >= length - 1e-9:
            continue
        fractions = []
        for q in REACH_SECTIONS[kind]:
            depth = (1.0 - q) * reach  # below the upper end
            fractions.append(1.0 - depth / length if up else depth / length)
        if tuple(fractions) not in out:
            out.append(tuple(fractions))
    return tuple(out)
