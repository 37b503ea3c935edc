"""Touches the evaluation can use: the planner's side of the evaluation's rules.

Every revolved feature the planner keeps must be evaluable from the touches it plans
(:func:`unevaluable`), on every dialect:

* probegen's evaluation of a Macro B log fits from the nominal and leaves a feature NOT
  EVALUATED below its *complete measurement* (:func:`probegen.geometry.determined.incomplete`:
  enough touches, sections, and touches in each section of a cylinder or a cone) or
  when its fit fails; the planner applies the same rule to the touches the collision
  check leaves, and runs the fit on their exact ball centres
  (:func:`~probegen.geometry.determined.unfit`, well conditioned with a margin),
  whatever the dialect;
* a DMIS program goes to a CMM that fits every measured feature freely
  (``Dialect.FREE_FIT``): the touches must also determine it
  (:func:`probegen.geometry.determined.undetermined`: a cone or cylinder in two
  sections, a sphere off one circle, a torus in three tube positions, a circle of three
  points).

The dialect that writes the program decides (:func:`free_fit`: the profile's dialect, as
``plan_program`` hands it the spec's, which ``compile -d`` and ``plan -d`` set).  The
revolved planner (:func:`probegen.planning.revolved_plan.plan_revolved`) prefers the
choice of sections whose touches are evaluable and refuses the feature when none is (a
``PlanningError`` with :func:`refused_reason`: another stylus and orientation are tried,
and ``--all-revolved`` leaves the feature out with that line), so no feature is written
whose result cannot come out.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from probegen.errors import PlanningError
from probegen.geometry.determined import incomplete, undetermined, unfit
from probegen.machine.profile import MachineProfile
from probegen.planning.revolved import FeaturePlan
from probegen.spec.model import Spec


class IllPosedError(PlanningError):
    """A revolved feature whose planned touches cannot be evaluated: too few for the
    evaluation, or, for a target that fits freely, not determining it
    (:func:`refused_reason`)."""


def fits_freely(dialect: str) -> bool:
    """Whether programs in ``dialect`` go to a target that fits features freely (DMIS)."""
    from probegen.dialects import REGISTRY

    cls = REGISTRY.get(dialect)
    return cls is not None and cls.FREE_FIT


def free_fit(machine: MachineProfile) -> bool:
    """Whether the profile's programs are fitted freely (its dialect, :func:`fits_freely`;
    the planner is handed the profile with the dialect that writes the program,
    :func:`for_dialect`)."""
    return fits_freely(machine.dialect)


def for_dialect(spec: Spec, dialect: str) -> Spec:
    """``spec`` as a program in ``dialect`` is planned: the spec's dialect and its
    profile's set to ``dialect``, so the dialect that writes the program decides the
    rules of :func:`unevaluable` (``compile -d dmis`` of a spec on a Fanuc profile is
    checked for a CMM's free fit), not the profile's; ``spec`` itself when both are
    already ``dialect``."""
    if spec.dialect == dialect and spec.machine.dialect == dialect:
        return spec
    return replace(spec, dialect=dialect, machine=with_dialect(spec.machine, dialect))


def with_dialect(machine: MachineProfile, dialect: str) -> MachineProfile:
    """``machine`` planning for programs in ``dialect`` (itself when it is its own)."""
    return machine if machine.dialect == dialect else replace(machine, dialect=dialect)


def strictest(dialects: Sequence[str], default: str) -> str:
    """The dialect whose rules a plan for all of ``dialects`` must meet: the first that
    fits freely (its rules include the others'), else the first; ``default`` (the
    profile's) when none is given.  ``plan --all-revolved -d fanuc -d dmis`` chooses the
    features both programs can evaluate."""
    return next((d for d in dialects if fits_freely(d)), dialects[0] if dialects else default)


def for_every_dialect(machine: MachineProfile) -> MachineProfile:
    """``machine`` planning for a spec that compiles in every dialect (``init``'s
    skeleton): with the :func:`strictest` of them."""
    from probegen.dialects import REGISTRY

    return with_dialect(machine, strictest(sorted(REGISTRY), machine.dialect))


def for_log(spec: Spec) -> Spec:
    """``spec`` as the program that printed a DPRNT log was planned: in the spec's
    dialect, or, where that one prints no such log (DMIS, which fits freely), in the
    profile's Macro B dialect (``fanuc`` for a CMM's profile): ``compile -d fanuc`` of a
    DMIS spec planned it so (:func:`for_dialect`)."""
    if not fits_freely(spec.dialect):
        return for_dialect(spec, spec.dialect)
    return for_dialect(spec, "fanuc" if fits_freely(spec.machine.dialect)
                       else spec.machine.dialect)


def ill_posed(kind: str, feature: Any, plan: FeaturePlan, free: bool = True) -> str:
    """Why the fit of the touches of ``plan`` would not give a spec feature of ``kind``,
    or ``""``: for a target that fits freely (``free``) the touches must determine it
    (:func:`~probegen.geometry.determined.undetermined`); on every target the fit of the
    exact ball centres must succeed well conditioned on the nominal axis
    (:func:`~probegen.geometry.determined.unfit`: the fit a CMM runs, and probegen's
    from the nominal, which starts from the same axis).

    Args:
        kind: the spec kind (``circle``, ``cylinder``, ``cone``, ``sphere``, ``torus``).
        feature: the recognised feature (``cad.revolved.RevolvedFeature``: its ``axis``,
            in the plan's frame).
        plan: the planned touches (``PathPoint.contact`` of each touch).
        free: the target fits freely (:func:`free_fit`).
    """
    pairs = [(p.contact, p.normal) for p in plan.path
             if p.normal is not None and p.contact is not None]
    contacts = np.array([c for c, _ in pairs], dtype=np.float64).reshape(-1, 3)
    # the ball centres the CMM records and fits: the contacts out along the normals (on
    # a short inner arc they lie nearer a line than the contacts: the CMM's rule is
    # applied to them too, sim.cmm does)
    normals = np.array([n for _, n in pairs], dtype=np.float64).reshape(-1, 3)
    centres = contacts + plan.sections[0].ball * normals
    why = (undetermined(kind, contacts, feature.axis)
           or undetermined(kind, centres, feature.axis)) if free else ""
    return why or unfit(kind, centres, feature.axis)


def unevaluable(kind: str, feature: Any, plan: FeaturePlan, free: bool) -> str:
    """Why the touches of ``plan`` cannot be evaluated, or ``""``: too few for a complete
    measurement (:func:`~probegen.geometry.determined.incomplete`), then
    :func:`ill_posed` (``free``: the target fits freely, :func:`free_fit`)."""
    why = incomplete(kind, [p.section for p in plan.path
                            if p.normal is not None and p.contact is not None])
    if why:
        return f"{TOO_FEW}{why}"
    return ill_posed(kind, feature, plan, free)


TOO_FEW = "too few touches to evaluate it: "
"""How :func:`unevaluable` starts the reason of a feature below the complete measurement."""


def refused_reason(kind: str, why: str, free: bool, lost: str = "") -> str:
    """The sentence of a feature refused for ``why`` (:func:`unevaluable`; ``free``: for
    a target that fits freely), with what the user can do; ``lost``: for too few
    touches, what took the others (the collision check's first dropped touch, e.g.
    ``touch 1 dropped: its approach ... comes within 0.140 mm of face 190; ...``)."""
    if why.startswith(TOO_FEW):  # no ": " after the counts: pick_stylus quotes from them
        lost = f" (the rest dropped by the collision check, e.g. {lost})" if lost else ""
        return (f"{kind}: {why}{lost}; give more points or sections where the part lets the "
                "probe reach them (points = N, sections = [...]), or another stylus, "
                "orientation or a setup")
    fits = "a CMM fits it freely" if free else "probegen fits it"
    return (f"{kind}: {why}: {fits} from the touches; where the part lets the probe reach "
            "more sections, give them (sections = [...]), another orientation or a setup")
