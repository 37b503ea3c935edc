"""Planning: spec features → an ``ir.Program`` whose every move the collision check cleared.

``plan_program`` is the entry point.  It loads the spec's part model once (or is handed
it) and passes the :class:`probegen.cad.Part` down to every feature planner and the
collision check.  It needs one fact about the target dialect, whether
the controller can compute at run time (``runtime_variables``): the planner asks for it as
a plain flag so that planning never imports the dialects.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from probegen import ir
from probegen.machine.profile import MachineProfile
from probegen.planning import locate
from probegen.planning.actions import (
    check_options,
    final_actions,
    planar_check,
    revolved_check,
    sphere_offset,
)
from probegen.planning.collision import ClearanceReport, check_program, obstacle_for
from probegen.planning.freeform_spec import FreeformPlan, plan_freeform
from probegen.planning.identity import program_identity
from probegen.planning.order import Stop, Tour, order_stops
from probegen.planning.planar import plan_planar, planar_nodes
from probegen.planning.reroute import Sweeper
from probegen.planning.revolved import Comparison
from probegen.planning.revolved_spec import RevolvedPlan, plan_revolved
from probegen.planning.setup import calibration_header, make_setup, part_of, setup_for
from probegen.planning.sphere_test import SphereTestPlan, plan_points, resolve_sphere
from probegen.planning.travel import (
    Linker,
    linked_nodes,
    over_obstacles,
    stop_of,
    tour_figures,
)
from probegen.spec.actions import PlanarSpec
from probegen.spec.model import FreeformSpec, RevolvedSpec, Spec

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
    """
    machine = spec.machine
    if part is None:
        part = part_of(spec)
    body: list[ir.Node] = []
    plans: list[SphereTestPlan] = []
    revolved: list[RevolvedPlan] = []
    checked: list[tuple[RevolvedSpec | PlanarSpec, ir.Check]] = []
    spheres: list[ir.SetWorkOffset] = []
    freeform: list[FreeformPlan] = []
    setup = make_setup(spec)
    for feature in spec.features:
        if isinstance(feature, RevolvedSpec):
            revolved.append(plan_revolved(feature, part, machine, spec.clearance_z))
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
            sphere = resolve_sphere(feature, part)
            p = plan_points(feature, sphere, machine)
            plans.append(p)
            offset = sphere_offset(feature, sphere.centre, machine.work_offset)
            spheres += [offset] if offset is not None else []
            if not feature.locate:
                body += locate.measure_nominal(p, machine, spec.clearance_z)
            elif runtime_variables:
                body += locate.locate_runtime(p, machine, spec.clearance_z)
            else:
                body += locate.locate_frame(p, machine, spec.clearance_z)
        if progress is not None:
            progress(1)
    tour = figures = None
    obstacle = obstacle_for(part, [p.sphere for p in plans])
    sweeper = Sweeper(obstacle, machine, machine.probe.ball_radius)
    body = over_obstacles(body, sweeper, spec.clearance_z)
    if revolved:
        stops = [stop_of(r) for r in revolved]
        linker = Linker(sweeper, stops, spec.clearance_z)
        tour = order_stops(stops, clearance_z=spec.clearance_z, route=linker.route,
                           cost=linker.time)
        revolved = [revolved[k] for k in tour.order]
        nodes = linked_nodes(revolved, machine, spec.clearance_z, linker)
        figures = tour_figures(revolved, nodes, machine, spec.clearance_z)
        body += _with_checks(nodes, {r.spec.id: r for r in revolved}, machine, checked)
    if freeform:
        order = order_stops([Stop(f.entry, f.exit) for f in freeform],
                            clearance_z=spec.clearance_z).order
        freeform = [freeform[k] for k in order]
        body += [n for f in freeform for n in f.nodes]
    body += final_actions(checked, setup.work_offset, spheres)
    program = ir.Program(setup, tuple(body))
    program = ir.Program(replace(setup, identity=program_identity(program)), program.body)
    report = (check_program(program, obstacle, plans, machine, progress=progress)
              if check_collisions else ClearanceReport(()))
    return PlannedProgram(program, tuple(plans), report, tuple(revolved), tour, figures,
                          tuple(freeform))


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
