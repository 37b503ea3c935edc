"""Revolved features of a spec: what serves the whole spec (``--all-revolved``: a spec
feature for every recognised feature some orientation reaches, each checked alone; the
metrics table), with the planning of one feature re-exported from
:mod:`probegen.planning.revolved_plan` (resolve, plan, IR) and
:mod:`probegen.planning.oriented` (the orientation and the stylus).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from probegen.errors import CollisionError, ModelError, PlanningError, SpecError
from probegen.machine.profile import MachineProfile
from probegen.planning.orient import orientation_for, orientation_label
from probegen.planning.oriented import OrientedPlan, approaches, plan_oriented, reorientable
from probegen.planning.revolved_plan import (
    ALTERNATIVE_SECTIONS,
    DEFAULT_SECTIONS,
    TYPE_OF_KIND,
    ResolvedRevolved,
    RevolvedPlan,
    check_alone,
    definition,
    find_owner,
    plan_revolved,
    resolve_revolved,
    revolved_nodes,
    smallest_bore,
    top_z,
)
from probegen.planning.well_posed import IllPosedError
from probegen.spec.model import RevolvedSpec, Spec

if TYPE_CHECKING:
    from probegen.cad import Part

__all__ = ["ALTERNATIVE_SECTIONS", "CLEARANCE_ABOVE_MODEL", "DEFAULT_SECTIONS", "KIND_OF_TYPE",
           "TYPE_OF_KIND", "ResolvedRevolved", "RevolvedPlan", "all_revolved",
           "all_revolved_spec", "check_alone", "definition", "find_owner", "metrics_table",
           "plan_revolved", "resolve_revolved", "revolved_nodes", "smallest_bore", "top_z"]


KIND_OF_TYPE = {"cylinder": "cylinder", "cone": "cone", "sphere": "sphere", "torus": "torus"}
"""The spec kind that measures each recognised type."""


def all_revolved(part: Part, machine: MachineProfile, clearance_z: float, *,
                 check: bool = True, faces: frozenset[int] | None = None
                 ) -> tuple[tuple[RevolvedSpec, ...], tuple[str, ...]]:
    """A spec feature for every revolved feature of a part that some orientation of the
    machine reaches and that plans with some stylus of the rack (default sections, 8
    points; :func:`probegen.planning.oriented.plan_oriented`) and, with ``check``, whose
    moves clear the collision check on their own in its frame (:func:`check_alone`); a
    line for each one left out with the reason
    (:func:`probegen.planning.left_out.revolved_left_out`); with ``faces``, only the
    features that have a face among them (the others neither planned nor noted)."""
    from probegen.cad.revolved import revolved_features
    from probegen.planning.left_out import revolved_left_out
    from probegen.planning.styli import smallest_stylus

    least = smallest_bore(machine.with_stylus(smallest_stylus(machine)))
    found = [f for f in revolved_features(part)
             if faces is None or not faces.isdisjoint(f.faces)]
    done: dict[int, RevolvedSpec | str] = {}
    for k in planning_order(found, part, machine):
        f = found[k]
        if f.type not in KIND_OF_TYPE or not (f.accessible or reorientable(f, machine)):
            done[k] = revolved_left_out(f, part, machine, f.reason, least)
            continue
        spec = RevolvedSpec(f"R{f.id}", f"{part.path}: revolved feature {f.id}",
                            _spec_kind(f, part, machine), f.faces[0], None, None, 8, None)
        try:
            spec, planned = _plan_or_circle(spec, part, machine, clearance_z)
        except (PlanningError, ModelError, SpecError) as exc:
            done[k] = revolved_left_out(f, part, machine, str(exc), least)
            continue
        if check:
            try:
                check_alone(planned.plan, planned.part, machine.with_stylus(planned.stylus),
                            planned.clearance_z)
            except CollisionError as exc:
                done[k] = revolved_left_out(f, part, machine,
                                            f"left out, it collides: {exc}", least)
                continue
        done[k] = spec
    results = [done[k] for k in range(len(found))]
    return (tuple(r for r in results if not isinstance(r, str)),
            tuple(r for r in results if isinstance(r, str)))


GROUPED = True
"""Whether :func:`all_revolved` plans the features grouped by the frame that first
reaches them (:func:`planning_order`); False: in the order they were recognised (the
baseline of ``benchmarks/bench_grouped_order.py``)."""


def planning_order(found: list[Any], part: Part, machine: MachineProfile) -> list[int]:
    """The order :func:`all_revolved` plans the recognised features ``found`` in (their
    indices): grouped by the frame of the first orientation that reaches them
    (:func:`approaches`, :func:`~probegen.planning.orient.orientation_for`; one group
    for those reached from above, one for those no orientation reaches), the groups in
    the order their first feature was recognised, each in recognition order.  A
    feature's plan does not depend on the order (what planning keeps per frame is a
    function of the frame): the order only decides how often a frame's height maps, of
    which the part keeps the most recently used (:class:`probegen.cad.Recent`), are
    built again (the collision trees are the loaded part's) (NIST CTC 4 with the CMM: 293
    features in 120 runs of 12 first frames as recognised).  Without :data:`GROUPED`,
    the recognised order."""
    if not GROUPED:
        return list(range(len(found)))
    first: dict[Any, int] = {}
    keys: list[int] = []
    for f in found:
        key: Any = "above"
        if not f.accessible and f.type in KIND_OF_TYPE and reorientable(f, machine):
            key = "none"
            for a in approaches(f, part):
                o = orientation_for(machine, a)
                if not isinstance(o, str):
                    key = tuple(round(x, 9) + 0.0 for row in o.rotation for x in row)
                    break
        keys.append(first.setdefault(key, len(first)))
    return sorted(range(len(found)), key=lambda k: (keys[k], k))


def _plan_or_circle(spec: RevolvedSpec, part: Part, machine: MachineProfile,
                    clearance_z: float) -> tuple[RevolvedSpec, OrientedPlan]:
    """The spec feature and its plan; a cylinder whose touches a CMM cannot fit as one
    (one section kept: :class:`~probegen.planning.well_posed.IllPosedError`) is measured
    as a circle, as a short land is (:func:`_kind`)."""
    try:
        return spec, plan_oriented(spec, part, machine, clearance_z)
    except IllPosedError as exc:
        if spec.kind != "cylinder":
            raise
        circle = replace(spec, kind="circle")
        try:
            return circle, plan_oriented(circle, part, machine, clearance_z)
        except PlanningError:
            raise exc from None


def _spec_kind(f: Any, part: Part, machine: MachineProfile) -> str:
    """:func:`_kind` of the feature as the frame that reaches it sees it (its sections
    reachable there); as recognised on the part when it is reachable from above or no
    orientation reaches it."""
    if f.accessible:
        return _kind(f)
    from probegen.cad.revolved import revolved_features

    for a in approaches(f, part):
        o = orientation_for(machine, a)
        if isinstance(o, str):
            continue
        turned = part.turned(o.plan_rotation)
        seen = next((g for g in revolved_features(turned) if f.faces[0] in g.faces), None)
        if seen is not None and seen.accessible:
            return _kind(seen)
    return _kind(f)


CLEARANCE_ABOVE_MODEL = 10.0
"""``all_revolved_spec``: the clearance plane is at least this far above the model, mm."""


def all_revolved_spec(part: Part, machine: MachineProfile) -> tuple[Spec, tuple[str, ...]]:
    """The spec of ``probegen plan MODEL --all-revolved``: every cylinder, cone, sphere and
    torus some orientation reaches that plans and clears the collision check alone
    (default sections, 8 points; :func:`all_revolved`), the clearance plane at least
    ``CLEARANCE_ABOVE_MODEL`` above the model; and a note for each feature left out (with
    the reason or the collision).  A model with no such feature gives a spec without
    features (an empty program) and the notes that say why.
    """
    top = part.bbox_max[2]
    clearance = max(machine.clearance_z, top + CLEARANCE_ABOVE_MODEL)
    features, notes = all_revolved(part, machine, clearance)
    spec = Spec(source=part.path, model=Path(part.path), machine=machine,
                dialect=machine.dialect, clearance_z=clearance, program_number=1001,
                program_name="ALL REVOLVED", features=features, raised=part.raised)
    return spec, notes


def _kind(f: Any) -> str:
    """The spec kind ``--all-revolved`` gives a recognised feature: its type's, but a
    cylinder with one reachable default section (a short land) is a circle."""
    if f.type == "cylinder" and sum(s.reachable for s in f.sections) < 2:
        return "circle"
    return KIND_OF_TYPE[f.type]


def metrics_table(plans: tuple[RevolvedPlan, ...], machine: MachineProfile,
                  oriented: tuple[OrientedPlan, ...] = ()) -> str:
    """Per feature: touches, path length (mm) and nominal cycle time (s) of the plan,
    the common baseline (up to the clearance level after every touch) and the lower
    bound (:func:`probegen.planning.revolved.compare`), with totals.  With ``oriented``
    (the program's plans with their orientation and stylus) where any feature is measured
    turned or with another stylus than ``[probe]``'s: two more columns, the orientation
    (``A90BM90``, ``TILT``: the tilt angle, ``-``: vertical) and the stylus label."""
    from probegen.planning.revolved import compare

    extra = {o.plan.spec.id: o for o in oriented}
    wide = any(not o.orientation.identity or o.stylus != machine.stylus for o in oriented)
    head = (f"{'feature':<8} {'kind':<8} {'side':<5} {'sect':>4} {'pts':>4}  "
            f"{'plan mm':>9} {'s':>7}  {'baseline mm':>11} {'s':>7}  {'bound mm':>9} {'s':>7}")
    rows = [head + (f"  {'orient':<10} {'stylus':<8}" if wide else "")]
    total = [0.0] * 6
    for p in plans:
        o = extra.get(p.spec.id)
        m = machine if o is None or o.stylus == machine.stylus else machine.with_stylus(
            o.stylus)
        c = compare(p.plan, m)
        values = (c.plan.length, c.plan.time, c.baseline.length, c.baseline.time,
                  c.lower_bound.length, c.lower_bound.time)
        total = [a + b for a, b in zip(total, values, strict=True)]
        row = _row(p.spec.id, p.spec.kind, "inner" if p.definition.inner else "outer",
                   len(p.plan.sections), len(p.normals), values)
        if wide and o is not None:
            row += f"  {orientation_label(o.orientation):<10} {o.stylus.label:<8}"
        rows.append(row)
    rows.append(_row("total", "", "", sum(len(p.plan.sections) for p in plans),
                     sum(len(p.normals) for p in plans), tuple(total)))
    return "\n".join(rows) + "\n"


def _row(fid: str, kind: str, side: str, sections: int, points: int,
         v: tuple[float, ...]) -> str:
    return (f"{fid:<8} {kind:<8} {side:<5} {sections:>4} {points:>4}  {v[0]:>9.1f} "
            f"{v[1]:>7.1f}  {v[2]:>11.1f} {v[3]:>7.1f}  {v[4]:>9.1f} {v[5]:>7.1f}")
