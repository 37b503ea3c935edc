"""The least-squares fits against the NIST reference pairs (``.ds`` points, ``.fit``
reference results computed by NIST at 60 digits).

The pairs are read in place from ``shared/ref/nist-ls-fits`` beside the checkout (see
SOURCES.md there for their origin and format).  NIST reports the point on an axis as the
projection of the data centroid, the same convention as ours, so points are compared
directly; directions are compared up to sign except the cone's, which NIST and we both
point towards increasing radius.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import ArrayLike

from probegen.geometry import fits

REF = Path(__file__).parents[2] / "shared" / "ref" / "nist-ls-fits"
PAIRS = sorted(REF.glob("*/*.ds"))
#: Required agreement: positions and sizes (mm), directions (rad).
LENGTH_TOL = 1e-7
ANGLE_TOL = 1e-7


def _angle(u: ArrayLike, v: ArrayLike, *, signed: bool = False) -> float:
    """Angle between two 3-D directions (up to sign unless ``signed``)."""
    a, b = np.asarray(u, dtype=float), np.asarray(v, dtype=float)
    cos = float(a @ b) if signed else abs(float(a @ b))
    return math.atan2(float(np.linalg.norm(np.cross(a, b))), cos)


def _distance(p: ArrayLike, q: ArrayLike) -> float:
    return float(np.linalg.norm(np.subtract(p, q)))


def _sphere(pts: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    f = fits.fit_sphere(pts)
    return {"centre": _distance(f.centre, ref[:3]), "diameter": abs(f.diameter - ref[3])}


def _plane(pts: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    f = fits.fit_plane(pts)
    return {"point": _distance(f.point, ref[:3]), "normal@": _angle(f.normal, ref[3:6])}


def _line3d(pts: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    f = fits.fit_line_3d(pts)
    return {"point": _distance(f.point, ref[:3]), "direction@": _angle(f.direction, ref[3:6])}


def _line2d(pts: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    keep = np.ptp(pts, axis=0) > 0.0  # NIST 2-D sets hold one coordinate constant
    assert keep.sum() == 2
    f = fits.fit_line_2d(pts[:, keep])
    direction = np.zeros(3)
    direction[keep] = f.direction
    return {"point": _distance(f.point, ref[:3][keep]), "direction@": _angle(direction, ref[3:6])}


def _circle3d(pts: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    f = fits.fit_circle_3d(pts)
    return {"centre": _distance(f.centre, ref[:3]), "normal@": _angle(f.normal, ref[3:6]),
            "diameter": abs(f.diameter - ref[6])}


def _cylinder(pts: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    f = fits.fit_cylinder(pts)
    return {"point": _distance(f.point, ref[:3]), "axis@": _angle(f.axis, ref[3:6]),
            "diameter": abs(f.diameter - ref[6])}


def _cone(pts: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    f = fits.fit_cone(pts)
    return {"point": _distance(f.point, ref[:3]),
            "axis@": _angle(f.axis, ref[3:6], signed=True),
            "distance": abs(f.distance - ref[6]),
            "apex angle@": abs(f.apex_angle - math.radians(ref[7]))}


COMPARE: dict[str, Callable[[np.ndarray, np.ndarray], dict[str, float]]] = {
    "Sphere": _sphere, "Plane": _plane, "Line3d": _line3d, "Line2d": _line2d,
    "Circle3d": _circle3d, "Cylinder": _cylinder, "Cone": _cone,
}


def deviations(ds: Path) -> dict[str, float]:
    """Deviations of our fit of ``ds`` from its NIST ``.fit``; keys ending in ``@`` are
    angles (rad), the others lengths (mm)."""
    with ds.open() as handle:
        count = int(handle.readline())
        pts = np.loadtxt(handle, ndmin=2)
    assert pts.shape == (count, 3), ds
    ref = np.loadtxt(ds.with_suffix(".fit"))
    return COMPARE[ds.parent.name](pts, ref)


def test_all_pairs_present() -> None:
    assert len(PAIRS) == 27, f"expected 27 NIST pairs in {REF}, found {len(PAIRS)}"
    assert all(p.with_suffix(".fit").is_file() for p in PAIRS)


@pytest.mark.parametrize("ds", PAIRS, ids=[f"{p.parent.name}/{p.stem}" for p in PAIRS])
def test_nist_pair(ds: Path) -> None:
    for name, dev in deviations(ds).items():
        limit = ANGLE_TOL if name.endswith("@") else LENGTH_TOL
        assert dev <= limit, f"{ds.name} {name}: deviation {dev:.3e} > {limit:.0e}"
