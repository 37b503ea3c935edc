"""Planning: spec features → an ``ir.Program`` whose every move the collision check cleared.

``plan_program`` is the entry point.  It needs one fact about the target dialect, whether
the controller can compute at run time (``runtime_variables``): the planner asks for it as
a plain flag so that planning never imports the dialects.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from probegen import ir
from probegen.machine.profile import MachineProfile
from probegen.planning import locate
from probegen.planning.collision import ClearanceReport, check_program, obstacle_for
from probegen.planning.order import Tour, order_stops
from probegen.planning.reroute import Sweeper
from probegen.planning.revolved import Comparison
from probegen.planning.revolved_spec import RevolvedPlan, plan_revolved
from probegen.planning.sphere_test import SphereTestPlan, plan_points, resolve_sphere
from probegen.planning.travel import Linker, linked_nodes, stop_of, tour_figures
from probegen.spec import RevolvedSpec, Spec


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
    """

    program: ir.Program
    sphere_tests: tuple[SphereTestPlan, ...]
    clearance: ClearanceReport
    revolved: tuple[RevolvedPlan, ...] = ()
    tour: Tour | None = None
    figures: Comparison | None = None


def make_setup(spec: Spec) -> ir.Setup:
    """The program's setup block from the spec and its machine profile."""
    m: MachineProfile = spec.machine
    return ir.Setup(
        program_number=spec.program_number, program_name=spec.program_name, units=m.units,
        work_offset=m.work_offset, clearance_z=spec.clearance_z,
        ball_diameter=m.probe.ball_diameter, shank_diameter=m.probe.shank_diameter,
        tool_number=m.probe.tool_number, tool_change=m.controller.tool_change,
        position_feed=m.feeds.position, probe_feed=m.feeds.probe,
        probe_on=m.controller.probe_on, probe_off=m.controller.probe_off,
        variable_base=m.controller.variable_base, reset_codes=m.controller.reset_codes,
        probe_length=m.probe.length,
    )


def plan_program(spec: Spec, *, runtime_variables: bool,
                 progress: Callable[[int], None] | None = None) -> PlannedProgram:
    """Plan every feature of ``spec`` and check the whole path for collisions.

    Args:
        spec: the validated spec.
        runtime_variables: whether the target controller computes at run time (Macro B
            yes, DMIS no); decides how a sphere of uncertain position is located.
        progress: called with 1 for every feature planned and every node checked.

    Returns:
        The planned program.

    Raises:
        SpecError: a value the geometry rules out (e.g. a retract below the safe minimum).
        ModelError: the model or the referenced face is unusable.
        CollisionError: a move would bring the stylus into the part.
    """
    machine = spec.machine
    body: list[ir.Node] = []
    plans: list[SphereTestPlan] = []
    revolved: list[RevolvedPlan] = []
    for feature in spec.features:
        if isinstance(feature, RevolvedSpec):
            revolved.append(plan_revolved(feature, spec.model, machine, spec.clearance_z))
        else:
            sphere = resolve_sphere(feature, spec.model)
            p = plan_points(feature, sphere, machine)
            plans.append(p)
            if not feature.locate:
                body += locate.measure_nominal(p, machine, spec.clearance_z)
            elif runtime_variables:
                body += locate.locate_runtime(p, machine, spec.clearance_z)
            else:
                body += locate.locate_frame(p, machine, spec.clearance_z)
        if progress is not None:
            progress(1)
    tour = figures = None
    obstacle = obstacle_for(spec.model, [p.sphere for p in plans])
    if revolved:
        stops = [stop_of(r) for r in revolved]
        linker = Linker(Sweeper(obstacle, machine, machine.probe.ball_radius), stops,
                        spec.clearance_z)
        tour = order_stops(stops, clearance_z=spec.clearance_z, route=linker.route)
        revolved = [revolved[k] for k in tour.order]
        nodes = linked_nodes(revolved, machine, spec.clearance_z, linker)
        figures = tour_figures(revolved, nodes, machine, spec.clearance_z)
        body += nodes
    program = ir.Program(make_setup(spec), tuple(body))
    report = check_program(program, obstacle, plans, machine, progress=progress)
    return PlannedProgram(program, tuple(plans), report, tuple(revolved), tour, figures)
