"""Point layouts on a sphere for the probing test (method M1) and their figures.

Conventions (``docs/methods.md`` M1): unit vectors in the sphere's frame; the pole is the
probe-shank direction (+Z); the x axis runs along the first equator vertex; spherical
``(θ polar from the pole, φ azimuth)`` maps to ``(sinθ cosφ, sinθ sinφ, cosθ)``.

Layouts:
    ``iso``: the ISO 10360-5 recommendation (1 + 4 + 8 + 4 + 8 points).
    ``octahedral``: the seed's quasi-uniform layout: the upper half of an octahedron, each
        edge cut in three equal arcs and each face centroid added.
    ``cap``: ``n`` points on the cap ``θ ≤ θ_max`` by Riesz-energy minimisation seeded from a
        spiral; deterministic (fixed seed layout, fixed optimiser settings).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize

from probegen.constants import tol

LAYOUTS = ("iso", "octahedral", "cap")

Array = NDArray[np.float64]
TIE = 1e-9
"""Distances (of unit vectors) closer than this are equal in :func:`zigzag_order`."""


def from_angles(theta_deg: Array, phi_deg: Array) -> Array:
    """Return unit vectors for polar angles and azimuths in degrees.

    Args:
        theta_deg: (n,) polar angles from the pole, degrees.
        phi_deg: (n,) azimuths, degrees.

    Returns:
        (n, 3) float unit vectors.
    """
    t = np.radians(np.asanyarray(theta_deg, dtype=np.float64))
    p = np.radians(np.asanyarray(phi_deg, dtype=np.float64))
    return np.column_stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


def _rings(spec: list[tuple[float, float, float, int]]) -> Array:
    """Build a layout from rings ``(theta, phi0, dphi, count)`` in degrees."""
    thetas: list[float] = []
    phis: list[float] = []
    for theta, phi0, dphi, count in spec:
        thetas += [theta] * count
        phis += [phi0 + k * dphi for k in range(count)]
    return from_angles(np.array(thetas), np.array(phis))


def iso_layout() -> Array:
    """The 25 points ISO 10360-5 recommends; (25, 3) unit vectors."""
    return _rings(
        [
            (0.0, 0.0, 0.0, 1),
            (22.5, 0.0, 90.0, 4),
            (45.0, 22.5, 45.0, 8),
            (67.5, 45.0, 90.0, 4),
            (90.0, 22.5, 45.0, 8),
        ]
    )


def octahedral_layout() -> Array:
    """The seed's 25-point quasi-uniform layout; (25, 3) unit vectors."""
    centroid = math.degrees(math.acos(1.0 / math.sqrt(3.0)))
    pts = _rings(
        [
            (0.0, 0.0, 0.0, 1),
            (90.0, 0.0, 90.0, 4),
            (30.0, 0.0, 90.0, 4),
            (60.0, 0.0, 90.0, 4),
            (90.0, 30.0, 90.0, 4),
            (90.0, 60.0, 90.0, 4),
            (centroid, 45.0, 90.0, 4),
        ]
    )
    return pts


def _spiral_cap(n: int, theta_max: float) -> Array:
    """Deterministic seed: a golden-angle spiral with equal areas on the cap."""
    k = np.arange(n, dtype=np.float64)
    cos_max = math.cos(theta_max)
    cos_t = 1.0 - (k + 0.5) / n * (1.0 - cos_max)
    theta = np.arccos(cos_t)
    phi = k * math.pi * (3.0 - math.sqrt(5.0))
    return np.column_stack([theta, phi])


def _angles_to_xyz(ang: Array) -> Array:
    t, p = ang[:, 0], ang[:, 1]
    return np.column_stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


def _energy(x: Array, n: int, s: float) -> tuple[float, Array]:
    """Riesz s-energy of points given as flat (θ, φ) pairs, with its gradient."""
    ang = x.reshape(n, 2)
    t, p = ang[:, 0], ang[:, 1]
    xyz = _angles_to_xyz(ang)
    diff = xyz[:, None, :] - xyz[None, :, :]
    d2 = np.einsum("ijk,ijk->ij", diff, diff) + np.eye(n)
    inv = d2 ** (-s / 2.0)
    np.fill_diagonal(inv, 0.0)
    energy = float(inv.sum() / 2.0)
    coef = -s * d2 ** (-s / 2.0 - 1.0)
    np.fill_diagonal(coef, 0.0)
    gxyz = np.einsum("ij,ijk->ik", coef, diff)
    dt = np.column_stack([np.cos(t) * np.cos(p), np.cos(t) * np.sin(p), -np.sin(t)])
    dp = np.column_stack([-np.sin(t) * np.sin(p), np.sin(t) * np.cos(p), np.zeros(n)])
    grad = np.column_stack([(gxyz * dt).sum(1), (gxyz * dp).sum(1)])
    return energy, grad.ravel()


def cap_layout(n: int, theta_max_deg: float = 90.0, *, energy_exponent: float = 6.0) -> Array:
    """``n`` quasi-uniform points on the cap ``θ ≤ θ_max`` (pole included as a point).

    The first point is fixed at the pole (the standard's first touch); the others minimise
    the Riesz ``s``-energy (``s = energy_exponent``) with ``θ`` bounded to the cap.

    Args:
        n: number of points, at least 3.
        theta_max_deg: largest polar angle in degrees, in (0, 180).
        energy_exponent: Riesz exponent; larger values favour the minimum distance.

    Returns:
        (n, 3) float unit vectors, pole first.
    """
    theta_max = math.radians(theta_max_deg)
    seed = _spiral_cap(n - 1, theta_max)
    pole = np.zeros(2)

    def fun(x: Array) -> tuple[float, Array]:
        full = np.concatenate([pole, x])
        e, g = _energy(full, n, energy_exponent)
        return e, g[2:]

    bounds = [(min(1e-6, theta_max / 2.0), theta_max), (None, None)] * (n - 1)
    res = minimize(
        fun, seed.ravel(), jac=True, method="L-BFGS-B", bounds=bounds,
        options={"maxiter": 3000, "ftol": 1e-15, "gtol": 1e-12},
    )
    ang = np.vstack([pole, res.x.reshape(n - 1, 2)])
    return _angles_to_xyz(ang)


def layout(name: str, n: int = 25, theta_max_deg: float = 90.0) -> Array:
    """Return the named layout as (n, 3) unit vectors (``iso``/``octahedral`` have 25)."""
    if name == "iso":
        return iso_layout()
    if name == "octahedral":
        return octahedral_layout()
    return cap_layout(n, theta_max_deg)


@dataclass(frozen=True, slots=True)
class Uniformity:
    """Nearest-neighbour figures of a layout on the unit sphere.

    Attributes:
        min_distance: smallest nearest-neighbour chord distance (units of R).
        max_distance: largest nearest-neighbour chord distance (units of R).
        ratio: ``min_distance / max_distance`` (1 = perfectly even).
    """

    min_distance: float
    max_distance: float
    ratio: float


def uniformity(points: Array) -> Uniformity:
    """Nearest-neighbour chord distances of unit vectors ``points : (n, 3)``."""
    p = np.asanyarray(points, dtype=np.float64)
    d = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=2)
    np.fill_diagonal(d, np.inf)
    nn = d.min(axis=1)
    return Uniformity(float(nn.min()), float(nn.max()), float(nn.min() / nn.max()))


def _ring_groups(theta: Array, band: float | None, jump: float) -> list[list[int]]:
    """Group point indices into rings by polar angle.

    With ``band`` the rings are the bands ``round(θ / band)``; without it a new ring starts
    wherever the sorted polar angles jump by more than ``jump``.
    """
    order = np.argsort(theta, kind="stable")
    groups: list[list[int]] = [[int(order[0])]]
    for prev, cur in zip(order[:-1], order[1:], strict=True):
        if band is not None:
            new_ring = round(theta[cur] / band) != round(theta[prev] / band)
        else:
            new_ring = theta[cur] - theta[prev] > jump
        if new_ring:
            groups.append([])
        groups[-1].append(int(cur))
    return groups


def zigzag_order(points: Array, *, band: float | None = None) -> list[int]:
    """Order the points ring by ring in a serpentine, starting at the pole.

    Rings are the points of (nearly) equal polar angle, from the pole outward: without
    ``band``, polar angles closer than half the smallest nearest-neighbour angle share a
    ring (so the octahedral layout's 54.7° and 60° points form one ring of 8); with
    ``band`` (rad), the rings are bands of that width (for layouts without exact rings).
    Each ring starts at its point nearest the previous point and runs alternately with
    increasing and decreasing azimuth, so consecutive points are neighbours.

    Args:
        points: (n, 3) unit vectors.
        band: ring width in radians, or None for the layout's own rings.

    Returns:
        Indices into ``points`` in measuring order.
    """
    p = np.asanyarray(points, dtype=np.float64)
    theta = np.arccos(np.clip(p[:, 2], -1.0, 1.0))
    phi = np.mod(np.arctan2(p[:, 1], p[:, 0]), 2.0 * math.pi)
    jump = max(tol.ring, math.asin(min(uniformity(p).min_distance / 2.0, 1.0)))
    out: list[int] = []
    for k, ring in enumerate(_ring_groups(theta, band, jump)):
        ring = sorted(ring, key=lambda i: (round(float(phi[i]), 12), i))
        if k % 2 == 0:
            ring = ring[::-1]
        if out:
            last = p[out[-1]]
            gaps = [float(np.linalg.norm(p[i] - last)) for i in ring]
            # the first of the nearest, distances within TIE of each other being equal
            # (a ring about the pole: all equal but for the last digits, which differ
            # between numpy builds)
            start = next(j for j, g in enumerate(gaps) if g <= min(gaps) + TIE)
            ring = ring[start:] + ring[:start]
        out += ring
    return out


def max_step_angle(points: Array, order: list[int]) -> float:
    """Largest central angle (rad) between consecutive points of ``order``."""
    p = np.asanyarray(points, dtype=np.float64)[order]
    cosines = np.clip(np.einsum("ij,ij->i", p[:-1], p[1:]), -1.0, 1.0)
    return float(np.arccos(cosines).max()) if len(p) > 1 else 0.0


def safe_retract(offset_radius: float, alpha: float) -> float:
    """Smallest retract distance whose chords clear the offset sphere (M1).

    A chord between two points at distance ``R' + d`` from the centre, ``α`` apart, comes
    closest to the centre at ``(R' + d)·cos(α/2)``; it clears the offset sphere ``R'`` iff
    ``d ≥ R'·(1/cos(α/2) − 1)``.

    Args:
        offset_radius: ``R' = R + r`` (sphere radius plus ball radius), mm.
        alpha: largest central angle between consecutive points, rad.

    Returns:
        The minimum retract distance in mm (``inf`` when ``α ≥ π``).
    """
    half = alpha / 2.0
    if half >= math.pi / 2.0:
        return math.inf
    return offset_radius * (1.0 / math.cos(half) - 1.0)
