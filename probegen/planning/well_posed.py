"""Touches a CMM can fit: the planner's side of the free-fit rule.

A DMIS program goes to a CMM that fits every measured feature freely
(``Dialect.FREE_FIT``): the touches of a revolved feature must determine it
(:func:`probegen.geometry.determined.undetermined`: a cone or cylinder in two sections, a
sphere off one circle, a torus in three tube positions, a circle of three points).  The
revolved planner (:func:`probegen.planning.revolved_plan.plan_revolved`) prefers, for
such a target, the choice of sections that is well posed and refuses the feature when
none is (a ``PlanningError`` with :func:`ill_posed_reason`: another stylus is tried, and
``--all-revolved`` leaves the feature out with that line), so no ill-posed feature is
written.  A Macro B program is fitted by probegen from the nominal and keeps what it
plans.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from probegen.errors import PlanningError
from probegen.geometry.determined import undetermined, unfit
from probegen.machine.profile import MachineProfile
from probegen.planning.revolved import FeaturePlan


class IllPosedError(PlanningError):
    """A revolved feature whose touches do not determine it, for a target that fits
    freely (:func:`ill_posed_reason`)."""


def fits_freely(dialect: str) -> bool:
    """Whether programs in ``dialect`` go to a target that fits features freely (DMIS)."""
    from probegen.dialects import REGISTRY

    cls = REGISTRY.get(dialect)
    return cls is not None and cls.FREE_FIT


def free_fit(machine: MachineProfile) -> bool:
    """Whether the profile's programs are fitted freely (its dialect, :func:`fits_freely`)."""
    return fits_freely(machine.dialect)


def ill_posed(kind: str, feature: Any, plan: FeaturePlan) -> str:
    """Why the touches of ``plan`` do not determine a spec feature of ``kind`` in a free
    fit, or ``""``.

    Args:
        kind: the spec kind (``circle``, ``cylinder``, ``cone``, ``sphere``, ``torus``).
        feature: the recognised feature (``cad.revolved.RevolvedFeature``: its ``axis``,
            in the plan's frame).
        plan: the planned touches (``PathPoint.contact`` of each touch).
    """
    pairs = [(p.contact, p.normal) for p in plan.path
             if p.normal is not None and p.contact is not None]
    contacts = np.array([c for c, _ in pairs], dtype=np.float64).reshape(-1, 3)
    # the ball centres the CMM records and fits: the contacts out along the normals (on
    # a short inner arc they lie nearer a line than the contacts: the CMM's rule is
    # applied to them too, sim.cmm does)
    normals = np.array([n for _, n in pairs], dtype=np.float64).reshape(-1, 3)
    centres = contacts + plan.sections[0].ball * normals
    why = undetermined(kind, contacts, feature.axis) or undetermined(kind, centres,
                                                                     feature.axis)
    return why or unfit(kind, centres, feature.axis)


def ill_posed_reason(kind: str, why: str) -> str:
    """The sentence of a feature refused for a CMM, with what the user can do."""
    return (f"{kind}: {why}: a CMM fits it freely from the touches; where the part lets "
            "the probe reach more sections, give them (sections = [...]), another "
            "orientation or a setup")
