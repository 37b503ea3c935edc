"""Planning: spec features → an ``ir.Program`` whose every move the collision check cleared.

``plan_program`` is the entry point.  It loads the spec's part model once (or is handed
it) and passes the :class:`probegen.cad.Part` down to every feature planner and the
collision check.  It needs one fact about the target dialect, whether
the controller can compute at run time (``runtime_variables``): the planner asks for it as
a plain flag so that planning never imports the dialects.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from probegen import ir
from probegen.errors import SpecError
from probegen.machine.profile import MachineProfile
from probegen.planning import locate
from probegen.planning.actions import (
    check_options,
    final_actions,
    planar_check,
    revolved_check,
    sphere_offset,
)
from probegen.planning.collision import ClearanceReport, Obstacle, check_program, obstacle_for
from probegen.planning.freeform_spec import FreeformPlan, plan_freeform
from probegen.planning.groups import grouped_nodes, with_index_moves
from probegen.planning.identity import program_identity
from probegen.planning.order import Stop, Tour, order_stops
from probegen.planning.orient import needs_index, select_node, top_of
from probegen.planning.oriented import OrientedPlan, plan_oriented
from probegen.planning.planar import plan_planar, planar_nodes
from probegen.planning.reroute import Sweeper
from probegen.planning.revolved import Comparison
from probegen.planning.revolved_metrics import Figures
from probegen.planning.revolved_spec import RevolvedPlan
from probegen.planning.setup import calibration_header, make_setup, part_of, setup_for
from probegen.planning.sphere_test import (
    SphereTestPlan,
    plan_points,
    resolve_sphere,
    sphere_test_profile,
)
from probegen.planning.styli import profile_with
from probegen.planning.travel import (
    Linker,
    linked_nodes,
    over_obstacles,
    stop_of,
    tour_figures,
)
from probegen.planning.well_posed import for_dialect
from probegen.spec.actions import PlanarSpec
from probegen.spec.model import FreeformSpec, RevolvedSpec, Spec, SphereTest

if TYPE_CHECKING:
    from probegen.cad import Part

__all__ = ["PlannedProgram", "calibration_header", "check_options", "make_setup", "part_of",
           "plan_program",
           "setup_for"]


@dataclass(frozen=True, slots=True)
class PlannedProgram:
    """A planned program with the figures behind it.

    Attributes:
        program: the IR, ready for a dialect.
        sphere_tests: the M1 plans, one per sphere-test feature.
        clearance: the collision check's report (smallest clearance per segment).
        revolved: the M2 plans of the revolved features, in measuring order.
        tour: the order of the revolved features (travel straight, at a local height
            or at the clearance plane: :mod:`probegen.planning.travel`).
        figures: length and time of the revolved features' whole tour, the baseline and
            the lower bound (:func:`probegen.planning.travel.tour_figures`).
        freeform: the M3 plans of the free-form features, in measuring order (after the
            revolved features; travel between them at the clearance plane).
    """

    program: ir.Program
    sphere_tests: tuple[SphereTestPlan, ...]
    clearance: ClearanceReport
    revolved: tuple[RevolvedPlan, ...] = ()
    tour: Tour | None = None
    figures: Comparison | None = None
    freeform: tuple[FreeformPlan, ...] = ()
    oriented: tuple[OrientedPlan, ...] = ()
    """The revolved features in measuring order with their orientation and stylus."""
    stylus_changes: int = 0
    """``SelectStylus`` nodes of the program (the return to the first stylus included)."""
    orientation_changes: int = 0
    """``Orient`` nodes of the program (the return to the vertical included)."""


def plan_program(spec: Spec, *, runtime_variables: bool,
                 progress: Callable[[int], None] | None = None,
                 check_collisions: bool = True, part: Part | None = None) -> PlannedProgram:
    """Plan every feature of ``spec`` and check the whole path for collisions.

    Args:
        spec: the validated spec.
        part: the spec's model, loaded (:func:`probegen.planning.setup.part_of`); loaded
            here when not given.  Hand it in to plan one spec more than once (one
            program per dialect) without loading the model again.
        runtime_variables: whether the target controller computes at run time (Macro B
            yes, DMIS no); decides how a sphere of uncertain position is located.
        progress: called with 1 for every feature planned and every node checked.
        check_collisions: run the collision check of the whole path (``False``: ``clearance`` is
            empty; ``ingest`` needs the planned touches only, the features' own
            planning still checks what it checks).

    Returns:
        The planned program.

    Raises:
        SpecError: a value the geometry rules out (e.g. a retract below the safe minimum).
        ModelError: the model or the referenced face is unusable.
        CollisionError: a move would bring the stylus into the part.

    The spec's dialect (``[machine] dialect``, or what ``compile -d`` set with
    :func:`~probegen.planning.well_posed.for_dialect`) decides which touches are
    evaluable (:mod:`probegen.planning.well_posed`), not the profile's.
    """
    spec = for_dialect(spec, spec.dialect)
    machine = spec.machine
    if part is None:
        part = part_of(spec)
    elif abs(part.raised - spec.raised) > 1e-9:  # the table the check keeps the stylus off
        raise SpecError(f"{spec.source}: [part] raised = {spec.raised:g} mm, but the part "
                        f"handed in stands {part.raised:g} mm above the table (load it "
                        "with load_part(path, raised=spec.raised))")
    body: list[ir.Node] = []
    plans: list[SphereTestPlan] = []
    revolved: list[RevolvedPlan] = []
    oriented: list[OrientedPlan] = []
    checked: list[tuple[RevolvedSpec | PlanarSpec, ir.Check]] = []
    spheres: list[ir.SetWorkOffset] = []
    freeform: list[FreeformPlan] = []
    setup = make_setup(spec)
    for feature in spec.features:
        if isinstance(feature, RevolvedSpec):
            oriented.append(plan_oriented(feature, part, machine, spec.clearance_z))
        elif isinstance(feature, FreeformSpec):
            freeform.append(plan_freeform(feature, part, machine, setup))
        elif isinstance(feature, PlanarSpec):
            planar = plan_planar(feature, part, machine)
            axes, check = planar_check(planar, machine)
            body += planar_nodes(planar, machine, spec.clearance_z, axes)
            if check is not None:
                body.append(check)
                checked.append((feature, check))
        else:
            body += _sphere_test(feature, part, spec, runtime_variables, plans, spheres)
        if progress is not None:
            progress(1)
    tour = figures = None
    obstacle = obstacle_for(part, [p.sphere for p in plans])
    sweeper = Sweeper(obstacle, machine, machine.probe.ball_radius)
    body = over_obstacles(body, sweeper, spec.clearance_z)
    grouped = None
    if oriented:
        tours: list[tuple[Tour, Comparison]] = []

        def lay_out(members: Sequence[OrientedPlan]
                    ) -> tuple[list[ir.Node], list[OrientedPlan]]:
            nodes, order, done = _tour(members, machine, checked,
                                       obstacle if members[0].part is part else None)
            tours.append(done)
            return nodes, [members[k] for k in order]

        grouped = grouped_nodes(oriented, machine, spec.clearance_z, lay_out)
        revolved = [p.plan for p in grouped.plans]
        tour, figures = _combined(tours)
        body += grouped.nodes
    if freeform:
        order = order_stops([Stop(f.entry, f.exit) for f in freeform],
                            clearance_z=spec.clearance_z).order
        freeform = [freeform[k] for k in order]
        body += [n for f in freeform for n in f.nodes]
    body += final_actions(checked, setup.work_offset, spheres)
    top = top_of(part, plans)
    if top is not None and any(needs_index(n, machine) for n in body):
        body = list(with_index_moves(body, top, machine, machine.stylus))
    program = ir.Program(setup, tuple(body))
    program = ir.Program(replace(setup, identity=program_identity(program)), program.body)
    report = (check_program(program, obstacle, plans, machine, progress=progress, part=part,
                           top=top)
              if check_collisions else ClearanceReport(()))
    return PlannedProgram(program, tuple(plans), report, tuple(revolved), tour, figures,
                          tuple(freeform), grouped.plans if grouped else (),
                          grouped.stylus_changes if grouped else 0,
                          grouped.orientation_changes if grouped else 0)


def _sphere_test(feature: SphereTest, part: Part | None, spec: Spec, runtime_variables: bool,
                 plans: list[SphereTestPlan], spheres: list[ir.SetWorkOffset]) -> list[ir.Node]:
    """A sphere test's nodes (recording its plan in ``plans`` and its work offset in
    ``spheres``); one that names a stylus of the rack takes it before and the ``[probe]``
    stylus back after (:func:`probegen.planning.sphere_test.sphere_test_profile`)."""
    machine = sphere_test_profile(feature, spec.machine)
    sphere = resolve_sphere(feature, part)
    p = plan_points(feature, sphere, machine)
    plans.append(p)
    offset = sphere_offset(feature, sphere.centre, machine.work_offset)
    spheres += [offset] if offset is not None else []
    if not feature.locate:
        nodes = locate.measure_nominal(p, machine, spec.clearance_z)
    elif runtime_variables:
        nodes = locate.locate_runtime(p, machine, spec.clearance_z)
    else:
        nodes = locate.locate_frame(p, machine, spec.clearance_z)
    if machine is spec.machine:
        return list(nodes)
    return [select_node(machine.stylus), *nodes, select_node(spec.machine.stylus)]


def _tour(members: Sequence[OrientedPlan], machine: MachineProfile,
          checked: list[tuple[RevolvedSpec | PlanarSpec, ir.Check]],
          obstacle: Obstacle | None) -> tuple[list[ir.Node], tuple[int, ...],
                                              tuple[Tour, Comparison]]:
    """One (stylus, orientation) group's tour, as every program's revolved features were
    toured before there were groups: ordered with clear links at the group's frame
    clearance, with its checks; the nodes, the order (indices of ``members``) and the
    figures.  ``obstacle``: the part's (the identity group's, built with the spheres),
    else the turned part's."""
    first = members[0]
    m = profile_with(machine, first.stylus)
    clear = first.clearance_z
    if obstacle is None:
        obstacle = obstacle_for(first.part, [])
    revolved = [p.plan for p in members]
    stops = [stop_of(r) for r in revolved]
    linker = Linker(Sweeper(obstacle, m, m.probe.ball_radius), stops, clear)
    tour = order_stops(stops, clearance_z=clear, route=linker.route, cost=linker.time)
    revolved = [revolved[k] for k in tour.order]
    nodes = linked_nodes(revolved, m, clear, linker)
    figures = tour_figures(revolved, nodes, m, clear)
    out = _with_checks(nodes, {r.spec.id: r for r in revolved}, m, checked)
    return out, tour.order, (tour, figures)


def _combined(tours: Sequence[tuple[Tour, Comparison]]) -> tuple[Tour, Comparison]:
    """The tours of the groups as one: one group's as it is, else the orders one after
    the other and the lengths and times summed (the moves of each orientation or stylus
    change are not in them)."""
    if len(tours) == 1:
        return tours[0]
    order: list[int] = []
    nearest: list[int] = []
    for t, _ in tours:
        order += [len(order) + k for k in t.order]
        nearest += [len(nearest) + k for k in t.nearest]

    def total(pick: Callable[[Comparison], Figures]) -> Figures:
        return Figures(sum(pick(c).length for _, c in tours), sum(pick(c).time for _, c in tours))

    tour = Tour(tuple(order), sum(t.length for t, _ in tours), tuple(nearest),
                sum(t.nearest_length for t, _ in tours))
    return tour, Comparison(total(lambda c: c.plan), total(lambda c: c.baseline),
                            total(lambda c: c.lower_bound))


def _with_checks(nodes: list[ir.Node], plans: dict[str, RevolvedPlan],
                 machine: MachineProfile,
                 checked: list[tuple[RevolvedSpec | PlanarSpec, ir.Check]]) -> list[ir.Node]:
    """The revolved features' nodes with each feature block's run-time stores and
    ``Check`` (in-process decisions, :func:`revolved_check`) after it; records the
    checks in ``checked``."""
    out: list[ir.Node] = []
    for node in nodes:
        plan = plans.get(node.feature.id) if isinstance(node, ir.FeatureBlock) else None
        if plan is None:
            out.append(node)
            continue
        done = revolved_check((node,), plan.spec, plan.definition, machine)
        out += done
        checked += [(plan.spec, n) for n in done if isinstance(n, ir.Check)]
    return out
