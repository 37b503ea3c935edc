"""Standard uncertainties of the revolved features' and the sphere test's characteristics.

The least-squares fit of each kind is linearised at its solution, in a local frame whose
origin is the fitted centre (a cone: the axis in the top gauge plane) and whose third
axis is the fitted axis.  The parameters are a small pose change ``(dx, dy, dz, a, b)``
(translation, and the new axis along ``(a, b, 1)``) and the shape's size changes; the
residuals are the orthogonal distances of the ball centres to the perturbed offset
surface.  ``probegen.geometry.uncertainty.fit_covariance`` gives ``σ²(JᵀJ)⁻¹`` and
``propagate`` carries it to the derived values (centre, axis, sizes), from which each
characteristic's ``u`` is assembled with the calibration's and the machine's
contributions (``probegen.geometry.uncertainty`` has the rules).

Sections of a circle or cylinder (``D_Sk``): the least-squares circle of the section's
ball centres about the fitted axis, with the main fit's pooled ``σ``.  ``TAPER``: the
slope of the least-squares line through the section diameters, from their ``u``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from probegen.evaluate.characteristics import Characteristic
from probegen.geometry.frames import rotation_to_z
from probegen.geometry.uncertainty import (
    Budget,
    FitCovariance,
    combine,
    fit_covariance,
    form_u,
    magnitude_u,
    propagate,
)

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
FORM_NAMES = ("FORM", "P_FTU")
"""Form characteristics besides the sections' ``RON_Sk``."""


@dataclass(frozen=True, slots=True)
class FittedShape:
    """A fitted offset surface of the ball centres, as the uncertainty needs it.

    Attributes:
        kind: ``circle``, ``cylinder``, ``cone``, ``sphere`` or ``torus``.
        centre: the reported centre (a cone: the axis in the top gauge plane), mm.
        axis: the fitted unit axis (a cone: towards the growing radius).
        radius: the ball-centre surface's radius (a cone: in the top gauge plane; a
            torus: the tube), mm.
        grow: surface size minus ball-centre size, as a radius (``±r``), mm.
        half_angle: a cone's half angle, rad.
        major_radius: a torus's major radius, mm.
        gauges: a cone's gauge planes (point, unit normal), top first.
    """

    kind: str
    centre: Array
    axis: Array
    radius: float
    grow: float
    half_angle: float = 0.0
    major_radius: float = 0.0
    gauges: tuple[tuple[Array, Array], ...] = ()


def _pose(q: Array, p: Array) -> Array:
    """Local points ``q : (n, 3)`` in the frame moved by ``p = (dx, dy, dz, a, b)`` (first
    order in the tilt)."""
    x, y, z = q[:, 0] - p[0], q[:, 1] - p[1], q[:, 2] - p[2]
    return np.column_stack([x - p[3] * z, y - p[4] * z, z + p[3] * x + p[4] * y])


@dataclass(frozen=True, slots=True)
class _Model:
    """A linearised fit: its residuals and derived values ``[centre(3), axis(3), sizes]``
    of a parameter perturbation, and the names of the sizes."""

    residuals: Callable[[Array], Array]
    derived: Callable[[Array], Array]
    size: int
    names: tuple[str, ...]


def _model(shape: FittedShape, q: Array, frame: Array) -> _Model:
    """The linearised least-squares problem of ``shape`` for local ball centres ``q``."""
    o, rb, g = shape.centre, shape.radius, shape.grow

    def world(p: Array, *sizes: float) -> Array:
        axis = frame.T @ np.array([p[3], p[4], 1.0])
        return np.concatenate([o + frame.T @ p[:3], axis / np.linalg.norm(axis), sizes])

    if shape.kind == "sphere":
        return _Model(lambda p: np.linalg.norm(q - p[:3], axis=1) - (rb + p[3]),
                      lambda p: world(np.r_[p[:3], 0, 0], 2 * (rb + p[3] + g)), 4, ("D",))
    if shape.kind == "cylinder":
        def cyl(p: Array) -> Array:
            return np.r_[p[0], p[1], 0.0, p[2], p[3]]
        return _Model(lambda p: np.hypot(*_pose(q, cyl(p))[:, :2].T) - (rb + p[4]),
                      lambda p: world(cyl(p), 2 * (rb + p[4] + g)), 5, ("D",))
    if shape.kind == "torus":
        big = shape.major_radius

        def tor(p: Array) -> Array:
            loc = _pose(q, p[:5])
            return np.hypot(np.hypot(loc[:, 0], loc[:, 1]) - (big + p[5]), loc[:, 2]) \
                - (rb + p[6])
        return _Model(tor, lambda p: world(p[:5], 2 * (rb + p[6] + g), 2 * (big + p[5])),
                      7, ("D", "DMAJ"))
    return _cone_model(shape, q, world)


def _cone_model(shape: FittedShape, q: Array, world: Callable[..., Array]) -> _Model:
    """The cone: parameters ``(dx, dy, a, b, dα, dρ)``; ``ρ`` the ball cone's radius in
    the frame's plane; derived: the axis in the top gauge plane, ``ANGLE`` (degrees) and
    the gauge diameters."""
    alpha, rb, g = shape.half_angle, shape.radius, shape.grow

    def pose(p: Array) -> Array:
        return np.r_[p[0], p[1], 0.0, p[2], p[3]]

    def residuals(p: Array) -> Array:
        loc = _pose(q, pose(p))
        a = alpha + p[4]
        return (np.hypot(loc[:, 0], loc[:, 1]) - (rb + p[5]) - loc[:, 2] * math.tan(a)) \
            * math.cos(a)

    def derived(p: Array) -> Array:
        base = world(pose(p))
        point, axis = base[:3], base[3:6]
        a = alpha + p[4]
        out, top = [], point
        for k, (centre, normal) in enumerate(shape.gauges):
            t = float((centre - point) @ normal) / float(axis @ normal)
            if k == 0:
                top = point + t * axis
            out.append(2.0 * (rb + p[5] + t * math.tan(a) + g / math.cos(a)))
        return np.concatenate([top, axis, [math.degrees(a)], out])

    names = ("ANGLE", *(f"D_S{k + 1}" for k in range(len(shape.gauges))))
    return _Model(residuals, derived, 6, names)


def _circle(shape: FittedShape, q: Array, budget: Budget) -> tuple[FitCovariance, Array]:
    """The 3-D circle: its plane ``(dz, a, b)`` and its in-plane circle ``(dx, dy, dr)``,
    two independent least-squares problems; returns the in-plane fit and the derived
    covariance of ``[centre, axis, D]``."""
    rb, g = shape.radius, shape.grow
    plane = fit_covariance(lambda p: q[:, 2] - p[0] - p[1] * q[:, 0] - p[2] * q[:, 1], 3,
                           budget)
    ring = fit_covariance(lambda p: np.hypot(q[:, 0] - p[0], q[:, 1] - p[1]) - (rb + p[2]),
                          3, budget)
    cov = np.zeros((6, 6))
    cov[:3, :3], cov[3:, 3:] = ring.cov, plane.cov
    joint = FitCovariance(cov, ring.sigma, ring.dof, ring.few)
    frame = rotation_to_z(shape.axis)

    def derived(p: Array) -> Array:
        axis = frame.T @ np.array([p[4], p[5], 1.0])
        centre = shape.centre + frame.T @ np.array([p[0], p[1], p[3]])
        return np.concatenate([centre, axis / np.linalg.norm(axis), [2 * (rb + p[2] + g)]])

    return joint, propagate(derived, joint)


def uncertainties(shape: FittedShape, ball_centres: Array, sections: IntArray,
                  chars: tuple[Characteristic, ...], *, nominal_centre: Array,
                  nominal_axis: Array | None, budget: Budget,
                  position_factor: float = 2.0) -> tuple[Characteristic, ...]:
    """``chars`` with their standard uncertainty ``u`` filled in.

    Args:
        shape: the fitted surface.
        ball_centres: ``(n, 3)`` the ball centres fitted, mm.
        sections: ``(n,)`` section of each ball centre.
        chars: the characteristics (names as in ``evaluate_revolved``).
        nominal_centre: the nominal point ``POS`` is measured from, mm.
        nominal_axis: the nominal axis ``POS`` is square to, or None (a sphere: the
            distance in space).
        budget: the stated contributions.
        position_factor: ``POS`` over the centre's distance (2: a zone diameter).
    """
    frame = rotation_to_z(shape.axis)
    q = (ball_centres - shape.centre) @ frame.T
    if shape.kind == "circle":
        fit, cov_g = _circle(shape, q, budget)
        names: tuple[str, ...] = ("D",)
    else:
        model = _model(shape, q, frame)
        fit = fit_covariance(model.residuals, model.size, budget)
        cov_g = propagate(model.derived, fit)
        names = model.names
    m = budget.u_machine
    length = float(np.ptp(q[:, 2])) if len(q) else 0.0
    angle_machine = math.degrees(m / length) if length > 0.0 else 0.0
    u: dict[str, float] = {}
    for axis_name, i in zip("XYZ", range(3), strict=True):
        u[axis_name] = combine(math.sqrt(max(cov_g[i, i], 0.0)), m)
    offset = shape.centre - nominal_centre
    cov_c = cov_g[:3, :3]
    if nominal_axis is not None:
        proj = np.eye(3) - np.outer(nominal_axis, nominal_axis)
        offset, cov_c = proj @ offset, proj @ cov_c @ proj
        tilt = proj @ shape.axis
        u["TILT"] = combine(math.degrees(magnitude_u(tilt, proj @ cov_g[3:6, 3:6] @ proj)),
                            angle_machine)
    u["POS"] = position_factor * combine(magnitude_u(offset, cov_c), m)
    cone_factor = 1.0 / math.cos(shape.half_angle)
    for j, name in enumerate(names):
        fit_u = math.sqrt(max(cov_g[6 + j, 6 + j], 0.0))
        if name == "ANGLE":
            u[name] = combine(fit_u, angle_machine)
        elif name == "DMAJ":
            u[name] = combine(fit_u, m)
        else:  # a diameter from the ball centres: 2 r in it
            u[name] = combine(fit_u, 2.0 * cone_factor * budget.radius, m)
    if shape.kind in ("circle", "cylinder"):
        u.update(_section_u(q, sections, fit.sigma, budget))
    if "D" in u:
        u["P_STU"] = u["D"]
    if shape.kind == "sphere":  # the sphere test's effective radius: R_fit + constants
        u["R_EFF"] = combine(math.sqrt(max(cov_g[6, 6], 0.0)) / 2.0, m)
    for form in (c.name for c in chars):
        if form in FORM_NAMES or form.startswith("RON_S"):
            u[form] = form_u(fit.sigma, budget)
    # a degenerate fit (a singular or non-finite covariance) gives no u rather than NaN
    return tuple(replace(c, u=u[c.name]) if math.isfinite(u.get(c.name, math.nan)) else c
                 for c in chars)


def _section_u(q: Array, sections: IntArray, sigma: float, budget: Budget) -> dict[str, float]:
    """``u`` of each section's ``D_Sk`` (an LS circle with the pooled ``sigma``) and of
    ``TAPER`` (the LS slope of the section diameters over the axial extent)."""
    out: dict[str, float] = {}
    heights, us = [], []
    for j in sorted(set(sections.tolist())):
        local = q[sections == j]
        radius = float(np.mean(np.hypot(local[:, 0], local[:, 1])))

        def ring(p: Array, local: Array = local, radius: float = radius) -> Array:
            return np.hypot(local[:, 0] - p[0], local[:, 1] - p[1]) - (radius + p[2])

        cov = fit_covariance(ring, 3, budget, sigma=sigma).cov
        u_d = 2.0 * math.sqrt(max(cov[2, 2], 0.0))
        out[f"D_S{j + 1}"] = combine(u_d, 2.0 * budget.radius, budget.u_machine)
        heights.append(float(np.mean(local[:, 2])))
        us.append(u_d)
    h = np.asarray(heights)
    if len(h) > 1 and float(np.ptp(h)) > 0.0:
        w = (h - h.mean()) / float(np.sum((h - h.mean()) ** 2))
        out["TAPER"] = combine(float(np.ptp(h)) * float(np.sqrt(np.sum((w * us) ** 2))),
                               budget.u_machine)
    return out
