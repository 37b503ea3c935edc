"""Method M2: revolved features measured in sections, with adaptive arc transitions.

A *section* is a circle of a surface of revolution square to its axis: centre ``O0``,
axis ``V``, radius ``R``, inner (bore) or outer (boss), and the azimuth intervals that
lie on the part (all of it, or arcs).  Per section (``docs/methods.md``, M2):

1. ``M1 = rotation_to_z(V)`` takes ``V`` onto +Z (identity for +Z, the half-turn about
   X for -Z); ``M2 = M1ᵀ`` takes section-plane coordinates back.  Azimuths ``φ`` are
   polar angles in that plane (the convention of :mod:`probegen.cad.revolved`).
2. ``n`` contact points ``p_i`` at equal arc length; on a partial arc they keep an end
   margin (arc length, default ``r + margin``) from its ends.
3. Retract vector ``N_i``: the unit outward normal, away from the axis for an outer
   feature and towards it for an inner one.  A section may carry a ``tilt`` (the angle
   of the normal out of the section plane, cones and off-equator sections of spheres
   and tori): ``N_i = cos τ·(±e_ρ) + sin τ·V``; ``tilt = 0`` is M2 exactly.
4. Ball-centre target ``P_ci = p_i + r·N_i``; safe point ``P_di = P_ci + d·N_i``.  The
   safe points lie on the *safe circle* of radius ``R_s = R ± (r + d)·cos τ``.
5. Outer feature: a chord of central angle ``α`` between safe points keeps the margin
   ``m`` from the offset surface iff ``R_s·cos(α/2) ≥ R_s − (d − m)/cos τ``, so
   ``α_max = 2·arccos((R + r + m)/(R + r + d))`` for ``τ = 0`` (``m = 0``: the
   methods.md formula).  Between consecutive safe points ``Δφ`` apart
   ``m = ceil(Δφ/α_max) − 1`` transitions are inserted, equally spaced on the safe
   circle.  Inner feature: chords inside a circle stay inside it, so a full circle
   needs none; it needs ``R_s > 0`` (else :class:`PlanningError`).  On a partial arc
   an inner step never exceeds :data:`INNER_MAX_STEP`, so that each chord stays in
   the sector between its ends and never crosses the missing arc.
6. Per section: safe → target → safe → transitions → next safe …; the path runs along
   each arc from one end to the other and never crosses a missing arc.  Between the
   arcs of one section, and between sections where the last azimuth is not
   accessible in the next one, the stylus leaves by the *clearance level* ``clear_z``
   (up along +Z, across, down).  Otherwise sections are linked along the axis at the
   safe radius, the next one traversed the other way (serpentine).

The clearance level is a world Z above the feature; entry and exit are straight above
the first and last safe points.  Tilted sections (cones, spheres and tori off their
equator) use the tangent cone of the surface for the chord condition: exact for cones,
conservative for convex profiles; the collision check is the final judge.

The method is split by responsibility: :mod:`~probegen.planning.revolved_geometry`
(steps 1-5: sections, rotations, azimuths, the safe circle), :mod:`~probegen.planning.revolved_path`
(step 6: the path and its IR nodes) and :mod:`~probegen.planning.revolved_metrics` (path
length and time against the baseline and the lower bound); this module re-exports their
public names.
"""

from probegen.planning.revolved_geometry import (
    FULL_CIRCLE,
    INNER_MAX_STEP,
    STEP_SLACK,
    TWO_PI,
    Arc,
    FeatureLike,
    FloatArray,
    Section,
    SectionLike,
    SectionPlan,
    Vec3,
    alpha_max,
    m1_rotation,
    m2_rotation,
    plan_section,
    point_azimuths,
    section_of,
    transition_count,
)
from probegen.planning.revolved_metrics import (
    Comparison,
    Figures,
    Segment,
    baseline_segments,
    compare,
    cycle_time,
    lower_bound_segments,
    path_length,
    plan_segments,
)
from probegen.planning.revolved_path import (
    FeaturePlan,
    PathKind,
    PathPoint,
    feature_nodes,
    plan_feature,
)

__all__ = [
    "FULL_CIRCLE",
    "INNER_MAX_STEP",
    "STEP_SLACK",
    "TWO_PI",
    "Arc",
    "Comparison",
    "FeatureLike",
    "FeaturePlan",
    "Figures",
    "FloatArray",
    "PathKind",
    "PathPoint",
    "Section",
    "SectionLike",
    "SectionPlan",
    "Segment",
    "Vec3",
    "alpha_max",
    "baseline_segments",
    "compare",
    "cycle_time",
    "feature_nodes",
    "lower_bound_segments",
    "m1_rotation",
    "m2_rotation",
    "path_length",
    "plan_feature",
    "plan_section",
    "plan_segments",
    "point_azimuths",
    "section_of",
    "transition_count",
]
