"""The planning half of :mod:`probegen.ir.identity`: a planned program's identity and its
touches evaluated at nominal (see there for what the identity covers and why)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal

import numpy as np

from probegen import ir
from probegen.ir.identity import PlannedTouch, canonical, identity_of, vec3_of
from probegen.planning.collision import _Walker


def planned_touches(program: ir.Program, plans: Sequence[Any] = ()) -> tuple[PlannedTouch, ...]:
    """Every probing move of ``program`` in order, evaluated at nominal.

    ``plans`` are the located features (see :func:`probegen.planning.collision.located`):
    their uncertainty goes to every touch placed from a run-time value or a local frame.
    After an ``ir.Rotary`` the points are those the control reports, the ball centre less
    the head shift (the dialects command and print that point).  After an ``ir.Orient``
    they stay in its frame, as a control under G68.2 prints them (``#5061``-``#5063``);
    after an ``ir.SelectStylus`` they are the ball centres of that stylus.
    """
    r = program.setup.ball_diameter / 2.0
    w = _Walker(plans, r)
    out: list[PlannedTouch] = []
    shift = np.zeros(3)
    for node in ir.walk(program.body):
        if isinstance(node, ir.Rotary):
            shift = np.array(node.head_shift)
        elif isinstance(node, ir.SelectStylus):
            r = node.ball_diameter / 2.0
        elif w.follow(node):
            pass
        elif isinstance(node, ir.Touch):
            n = np.array(node.normal)
            contact = w.point(node.contact)
            start = contact + (r + node.approach) * n
            end = contact + (r - node.overtravel) * n
            moved = bool(w.frames) or any(isinstance(c, ir.Var) for c in node.contact)
            kind: Literal["PT", "LOC"] = "LOC" if node.role is ir.TouchRole.LOCATE else "PT"
            out.append(PlannedTouch(kind, node.feature, node.index, vec3_of(start - shift),
                                    vec3_of(end - shift), w.uncertainty if moved else 0.0))
            for axis, name in enumerate(node.store):
                if name is not None:
                    w.values[name] = float((contact + r * n - w.origin())[axis])
    return tuple(out)


def program_identity(program: ir.Program) -> str:
    """The identity of ``program`` (see the module docstring)."""
    return identity_of(canonical(program))
