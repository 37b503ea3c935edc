"""Whether touch points determine a revolved feature in a *free* least-squares fit.

A CMM (PC-DMIS, Calypso, the virtual CMM of :mod:`probegen.sim.cmm`) fits every measured
feature freely: it does not know the nominal axis, apex or centre, the points alone must
fix them.  probegen's own evaluation of a Macro B log fits from the nominal
(:mod:`probegen.geometry.fits_nominal`), which serves on fewer points; a DMIS program
must give the CMM points that determine the shape, else the CMM refuses the feature or
reports one of the many shapes the points lie on.

The rule (:func:`undetermined`), per kind, on the points and the feature's axis:

* the fit's fewest points (:data:`MINIMUM_POINTS`);
* a *level* is a group of points at one height along the axis (heights sorted, a gap
  over :data:`LEVEL_GAP` and over :data:`LEVEL_SHARE` of the height range starts a new
  level: a section of a tilted real part stays one level);
* circle: its points not on one line;
* cylinder, cone: two levels (two sections: the points of one section lie on one
  circle, and one circle lies on many cylinders and cones);
* sphere: two levels (a second section or a pole touch: one circle lies on many
  spheres); a sphere's levels are taken along the normal of its points' best-fit plane,
  so it needs no axis;
* torus: :data:`TORUS_LEVELS` levels (three tube positions: two circles of a torus lie
  on a family of tori).

These are what the points must have for the fit to be determined at all, not a
programmer's good practice (sections far apart, points spread around): the virtual CMM
refuses what no CMM can fit, and the planner never writes it.

probegen's own evaluation (``ingest`` of a Macro B log, fitted from the nominal) has its
rule of a *complete measurement* (:func:`incomplete`), on the section of each touch: at
least one touch more than the fit's unknowns (:data:`EVALUATED_POINTS`), the sections of
:data:`EVALUATED_SECTIONS`, and for a cylinder or a cone :data:`SECTION_POINTS` touches
in every section (each section's diameter and roundness are a circle fitted there).  The
evaluation leaves a feature that breaks it NOT EVALUATED; the planner, for every
dialect, refuses to plan one (``planning/well_posed.py``): one rule, here, for both.

Lengths in mm.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from probegen.errors import ProbegenError
from probegen.geometry.fits import fit_circle_3d, fit_sphere
from probegen.geometry.fits_axial import fit_cone, fit_cylinder, fit_torus
from probegen.geometry.fits_conditioning import CONDITION_LIMIT
from probegen.geometry.fits_results import ConeFit, CylinderFit, TorusFit
from probegen.geometry.frames import FloatArray, unit

MINIMUM_POINTS = {"circle": 3, "cylinder": 5, "cone": 6, "sphere": 4, "torus": 7}
"""Fewest points of each free least-squares fit (its unknowns: a cylinder's axis line
and radius are five, a cone's six with the angle, a torus's seven)."""
LEVEL_GAP = 0.05
"""Two points further apart than this along the axis (mm), with no point between, may be
on two levels (sections) ..."""
LEVEL_SHARE = 0.1
"""... when they are also further apart than this share of the points' whole height
range: the touches of one section of a real part tilted off the nominal axis spread in
height (2 deg on a 30 mm ring: 2 mm) and stay one level; the planner's sections are at
least a fifth of the feature's extent apart."""
TORUS_LEVELS = 3
"""Levels (tube positions) a torus needs."""
LEVELS = {"circle": 1, "cylinder": 2, "cone": 2, "sphere": 2, "torus": TORUS_LEVELS}
"""Levels each kind needs."""
WHY = {
    "cylinder": "one circle lies on many cylinders",
    "cone": "one circle lies on many cones",
    "sphere": "one circle lies on many spheres",
    "torus": "two circles of a torus lie on a family of tori",
}
"""Why a kind needs more than one level, for the message."""
COLLINEAR = 1e-3
"""A ring whose points lie within this (mm) of one line fixes no circle."""


def levels(points: ArrayLike, axis: ArrayLike) -> list[int]:
    """The number of points on each level along ``axis``, lowest level first.

    Args:
        points: ``(n, 3)`` float, mm.
        axis: ``(3,)``, the feature's axis (any length but zero).
    """
    heights = np.sort(np.asarray(points, dtype=np.float64) @ unit(axis, what="axis"))
    if heights.size == 0:
        return []
    gap = max(LEVEL_GAP, LEVEL_SHARE * float(heights[-1] - heights[0]))
    cuts = np.flatnonzero(np.diff(heights) > gap) + 1
    return [len(group) for group in np.split(heights, cuts)]


def plane_normal(points: FloatArray) -> FloatArray:
    """The unit normal of the points' best-fit plane (the direction they spread least)."""
    centred = points - points.mean(axis=0)
    return np.asarray(np.linalg.svd(centred)[2][2], dtype=np.float64)


def undetermined(kind: str, points: ArrayLike, axis: ArrayLike | None) -> str:
    """Why ``points`` do not determine a ``kind`` in a free least-squares fit, or ``""``.

    Args:
        kind: ``circle``, ``cylinder``, ``cone``, ``sphere`` or ``torus``.
        points: ``(n, 3)`` float, the contact points (or the ball centres: they lie on
            the offset surface, on the same levels), mm.
        axis: the feature's axis (a circle's normal); ignored for a sphere, whose levels
            are taken along the normal of the points' best-fit plane.

    Returns:
        ``""`` when determined, else a sentence such as "6 points in one section: a free
        cone fit needs two sections (one circle lies on many cones)".
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    least = MINIMUM_POINTS[kind]
    if len(p) < least:
        return f"{_count(len(p), 'point')}: a free {kind} fit needs at least {least}"
    if kind == "circle":
        return _collinear(p)
    counts = levels(p, plane_normal(p) if kind == "sphere" or axis is None else axis)
    need = LEVELS[kind]
    if len(counts) < need:
        where = "one section" if len(counts) == 1 else f"{_count(len(counts), 'section')}"
        return (f"{_count(len(p), 'point')} in {where}: a free {kind} fit needs "
                f"{_count(need, 'section')} ({WHY[kind]})")
    return ""


def _collinear(p: FloatArray) -> str:
    """Why points meant for a circle fix none (all within :data:`COLLINEAR` of a line)."""
    centred = p - p.mean(axis=0)
    spread = np.linalg.svd(centred, compute_uv=False)
    if spread[1] / np.sqrt(len(p)) < COLLINEAR:
        return "the points lie on one line: a free circle fit needs them on an arc"
    return ""


def _count(n: int, word: str) -> str:
    names = {1: "one", 2: "two", 3: "three"}
    return f"{names.get(n, str(n))} {word}{'' if n == 1 else 's'}"


def unfit(kind: str, points: ArrayLike, axis: ArrayLike | None) -> str:
    """Why the fit of exact ``points`` (the ball centres a plan will record) fails, or
    ``""``: the fit a CMM runs, started from ``axis``, which is also probegen's own fit
    from the nominal (``fits_nominal.fit_near`` keeps the solution from the nominal
    axis; a circle's and a sphere's fit has one optimum), refuses points that determine
    the shape in theory but too weakly (two sections of a cone, each a degree of arc:
    condition number 8e8), or converges to another shape than the nominal's axis.

    Args:
        kind: as :func:`undetermined`.
        points: ``(n, 3)`` float, mm.
        axis: the nominal axis (not used for a circle or a sphere).
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    try:
        if kind == "circle":
            condition = fit_circle_3d(p).condition
        elif kind == "sphere":
            condition = fit_sphere(p).condition
        else:
            found: CylinderFit | ConeFit | TorusFit
            if kind == "cylinder":
                found = fit_cylinder(p, axis, nearest=axis is not None)
            elif kind == "cone":
                found = fit_cone(p, axis, nearest=axis is not None)
            else:
                found = fit_torus(p, axis, nearest=axis is not None)
            if axis is not None and abs(float(unit(found.axis) @ unit(axis))) < AXIS_AGREES:
                return f"the {kind} fit of the planned touches ends off the nominal axis"
            condition = found.condition
    except ProbegenError as exc:
        return str(exc)
    if not condition <= PLANNED_CONDITION:
        return (f"the {kind} fit of the planned touches is ill-conditioned (condition "
                f"number {condition:.1e}, a planned feature keeps below "
                f"{PLANNED_CONDITION:.0e}): too short an arc or too close sections")
    return ""


PLANNED_CONDITION = CONDITION_LIMIT / 100.0
"""The largest condition number of the free fit of a planned feature's exact touches:
a hundred times below the fits' own limit (``fits_conditioning.CONDITION_LIMIT``), as
the touches come back rounded to the output's decimals and scattered by the probe, which
moves a near-singular solution (NIST FTC 7's cone R146: the exact touches' fit passed
the limit, the virtual CMM's fit of its recorded touches ended at 2.7e8)."""


AXIS_AGREES = 0.9998
"""The cosine (1 deg) within which the fit of exact touches must find the nominal axis."""


EVALUATED_POINTS = {"circle": 4, "cylinder": 6, "cone": 7, "sphere": 5, "torus": 8}
"""Fewest touches each revolved kind is evaluated from: one more than its fit's
parameters (circle 3 in its plane, cylinder 5, cone 6, sphere 4, torus 7), so at least
one touch checks the form."""
EVALUATED_SECTIONS = {"circle": 1, "cylinder": 2, "cone": 2, "sphere": 2, "torus": 3}
"""Fewest sections (distinct section planes) each kind is evaluated from."""
SECTION_POINTS = 3
"""Fewest touches in each section of a cylinder or a cone (its ``D_Sk`` and ``RON_Sk``:
a circle fitted in the section)."""
PER_SECTION = ("cylinder", "cone")
"""The kinds whose every section is fitted on its own."""


def incomplete(kind: str, sections: Sequence[int]) -> str:
    """Why touches in ``sections`` are too few for probegen's evaluation of a ``kind``
    (a complete measurement), or ``""``: the rule ``ingest`` applies to the touches it
    reads and the planner to the touches it keeps.

    Args:
        kind: ``circle``, ``cylinder``, ``cone``, ``sphere`` or ``torus``.
        sections: the 0-based section of each touch.

    Returns:
        ``""``, or a sentence such as "2 touches in 1 sections (at least 4 needed)".
    """
    counts = Counter(int(k) for k in sections)
    n, least, need = len(sections), EVALUATED_POINTS[kind], EVALUATED_SECTIONS[kind]
    if n < least or len(counts) < need:
        return (f"{n} touches in {len(counts)} sections (at least {least} needed"
                f"{f', in {need} sections' if need > 1 else ''})")
    thin = sorted(j for j, c in counts.items() if c < SECTION_POINTS)
    if kind in PER_SECTION and thin:
        return (f"{counts[thin[0]]} touches in section {thin[0] + 1} (at least "
                f"{SECTION_POINTS} needed in each section of a {kind}: its diameter and "
                "roundness there)")
    return ""
