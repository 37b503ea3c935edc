"""Probe orientations (``ir.Orient``): the frame of a feature whose axis is not along Z.

One convention for the whole project, pure Python (the IR holds no numpy):

* A frame is a rotation ``R`` (rows; its columns are the frame's X, Y, Z in work
  coordinates) and an origin: ``p_work = origin + R·p_frame``.
* Frame +Z is the tool axis, from the part towards the head (the probe hangs along -Z),
  as in Fanuc's feature coordinate system (G68.2).  :func:`frame_for` gives the frame of
  an approach direction ``a`` (the unit vector from the feature towards where the probe
  comes from): ``Z = a``, ``X = ẑ × a / |ẑ × a|`` (horizontal), ``Y = Z × X`` (the
  frame's Y leans up); ``a = +Z`` is the identity and ``a = -Z`` the half turn about X.
* :func:`euler_zxz` gives the G68.2 ``I J K`` angles: ``R = Rz(I)·Rx(J)·Rz(K)``, deg.
* :func:`in_work` maps a program's nodes back to work coordinates (the DMIS dialect, the
  program identity and ingest, which all speak work coordinates).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TypeVar

from probegen import ir
from probegen.errors import UnsupportedError

Rotation = tuple[ir.Vec3, ir.Vec3, ir.Vec3]
IDENTITY: Rotation = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
FLIP_X: Rotation = ((1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, -1.0))
VERTICAL = 1e-9
"""``|a_x|, |a_y|`` below this: the direction is along Z."""

N = TypeVar("N")


def _unit(v: ir.Vec3) -> ir.Vec3:
    n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if not n > 0.0:
        raise ValueError(f"no direction: {v}")
    return (v[0] / n, v[1] / n, v[2] / n)


def _cross(a: ir.Vec3, b: ir.Vec3) -> ir.Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _clean(x: float) -> float:
    """``x`` with values within 1e-15 of 0 or ±1 snapped (repeatable text, no ``-0``)."""
    for v in (0.0, 1.0, -1.0):
        if abs(x - v) < 1e-15:
            return v + 0.0
    return x


def frame_for(axis: ir.Vec3) -> Rotation:
    """The rotation of the frame whose +Z is the approach direction ``axis`` (not
    necessarily unit), see the module docstring."""
    z = _unit(axis)
    if abs(z[0]) < VERTICAL and abs(z[1]) < VERTICAL:
        return IDENTITY if z[2] > 0.0 else FLIP_X
    x = _unit(_cross((0.0, 0.0, 1.0), z))
    y = _cross(z, x)
    cols = (x, y, z)
    return tuple(tuple(_clean(cols[j][i]) for j in range(3))  # type: ignore[return-value]
                 for i in range(3))


def head_approach(a: float, b: float) -> ir.Vec3:
    """The approach direction (from the ball towards the head: an ``Orient``'s frame +Z)
    of a CMM head at angles ``A``, ``B`` (deg): ``A`` tilts the stylus from straight down,
    ``B`` turns it counter-clockwise seen from above, ``B = 0`` pointing the stylus to -Y:
    ``(-sin A·sin B, sin A·cos B, cos A)``.  The stylus direction (head to ball) is its
    negative.  The one convention of the planner, the DMIS dialect and the virtual CMM."""
    sa, ca = math.sin(math.radians(a)), math.cos(math.radians(a))
    sb, cb = math.sin(math.radians(b)), math.cos(math.radians(b))
    return (-sa * sb, sa * cb, ca)


def is_identity(rotation: Rotation, tol: float = 1e-12) -> bool:
    """Whether ``rotation`` is the vertical probe's."""
    return all(abs(rotation[i][j] - IDENTITY[i][j]) <= tol for i in range(3) for j in range(3))


def apply(rotation: Rotation, v: ir.Vec3) -> ir.Vec3:
    """``R·v``."""
    return tuple(sum(rotation[i][j] * v[j] for j in range(3))  # type: ignore[return-value]
                 for i in range(3))


def apply_t(rotation: Rotation, v: ir.Vec3) -> ir.Vec3:
    """``Rᵀ·v``."""
    return tuple(sum(rotation[j][i] * v[j] for j in range(3))  # type: ignore[return-value]
                 for i in range(3))


def product_t(a: Rotation, b: Rotation) -> Rotation:
    """``aᵀ·b``: the rotation ``b`` seen from the frame of ``a`` (frame ``b`` in ``a``'s
    coordinates)."""
    return tuple(tuple(sum(a[k][i] * b[k][j] for k in range(3))  # type: ignore[return-value]
                       for j in range(3)) for i in range(3))


def to_work(orient: ir.Orient | None, p: ir.Vec3) -> ir.Vec3:
    """Point ``p`` of ``orient``'s frame in work coordinates (``None``: unchanged)."""
    if orient is None:
        return p
    q = apply(orient.rotation, p)
    return (q[0] + orient.origin[0], q[1] + orient.origin[1], q[2] + orient.origin[2])


def to_frame(orient: ir.Orient | None, p: ir.Vec3) -> ir.Vec3:
    """Work point ``p`` in ``orient``'s frame (``None``: unchanged)."""
    if orient is None:
        return p
    o = orient.origin
    return apply_t(orient.rotation, (p[0] - o[0], p[1] - o[1], p[2] - o[2]))


def direction_to_work(orient: ir.Orient | None, v: ir.Vec3) -> ir.Vec3:
    """Direction ``v`` of ``orient``'s frame in work coordinates."""
    return v if orient is None else apply(orient.rotation, v)


def euler_zxz(rotation: Rotation) -> tuple[float, float, float]:
    """The Euler angles ``(I, J, K)`` (deg) with ``R = Rz(I)·Rx(J)·Rz(K)`` (Fanuc G68.2
    ``I J K``); for ``J = 0`` (or 180) the turn is all in ``I`` and ``K = 0``."""
    r = rotation
    j = math.degrees(math.acos(max(-1.0, min(1.0, r[2][2]))))
    if math.hypot(r[0][2], r[1][2]) < 1e-12:
        i = math.degrees(math.atan2(r[1][0], r[0][0])) if r[2][2] > 0 else \
            math.degrees(math.atan2(-r[1][0], r[0][0]))
        return (_clean(i), _clean(j), 0.0)
    i = math.degrees(math.atan2(r[0][2], -r[1][2]))
    k = math.degrees(math.atan2(r[2][0], r[2][1]))
    return (_clean(i), _clean(j), _clean(k))


def from_euler_zxz(i: float, j: float, k: float) -> Rotation:
    """The rotation ``Rz(i)·Rx(j)·Rz(k)`` (deg): the inverse of :func:`euler_zxz`."""
    def rz(a: float) -> Rotation:
        c, s = math.cos(math.radians(a)), math.sin(math.radians(a))
        return ((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0))

    def rx(a: float) -> Rotation:
        c, s = math.cos(math.radians(a)), math.sin(math.radians(a))
        return ((1.0, 0.0, 0.0), (0.0, c, -s), (0.0, s, c))

    def mul(a: Rotation, b: Rotation) -> Rotation:
        return tuple(tuple(sum(a[r][m] * b[m][c] for m in range(3))
                           for c in range(3)) for r in range(3))  # type: ignore[return-value]

    return mul(mul(rz(i), rx(j)), rz(k))


def _point(orient: ir.Orient | None, p: ir.Point, what: str) -> ir.Point:
    if orient is None:
        return p
    if any(isinstance(c, ir.Var) for c in p):
        raise UnsupportedError(f"{what}: a run-time coordinate in the tilted frame "
                               f"{orient.name} cannot be turned into work coordinates")
    return to_work(orient, (float(p[0]), float(p[1]), float(p[2])))  # type: ignore[arg-type]


def node_in_work(orient: ir.Orient | None, node: N) -> N:
    """``node`` (a move, a touch or a feature block) with its coordinates in work
    coordinates; other nodes unchanged."""
    if orient is None or is_identity(orient.rotation) and orient.origin == (0.0, 0.0, 0.0):
        return node
    if isinstance(node, ir.Move):
        return replace(node, target=_point(orient, node.target, "move"))
    if isinstance(node, ir.Touch):
        surface = None if node.surface is None else direction_to_work(orient, node.surface)
        return replace(node, contact=_point(orient, node.contact, f"touch {node.feature}"),
                       normal=direction_to_work(orient, node.normal), surface=surface)
    if isinstance(node, ir.FeatureBlock):
        return replace(node, feature=definition_in_work(orient, node.feature),
                       body=tuple(node_in_work(orient, n) for n in node.body))
    return node


_POINTS = ("centre", "apex", "point", "start", "end")
_DIRECTIONS = ("axis", "normal")


def definition_in_work(orient: ir.Orient | None, feature: ir.FeatureDef) -> ir.FeatureDef:
    """A feature definition with its points and directions in work coordinates."""
    if orient is None:
        return feature
    changes: dict[str, ir.Vec3] = {}
    for name in _POINTS:
        if hasattr(feature, name):
            changes[name] = to_work(orient, getattr(feature, name))
    for name in _DIRECTIONS:
        if hasattr(feature, name):
            changes[name] = direction_to_work(orient, getattr(feature, name))
    return replace(feature, **changes)  # type: ignore[arg-type]


def in_work(nodes: tuple[ir.Node, ...]) -> list[tuple[ir.Node, ir.Orient | None]]:
    """Every top-level node of ``nodes`` in work coordinates, with the orientation in force
    where it stands (None before the first ``Orient``; the ``Orient`` nodes themselves are
    kept, paired with themselves)."""
    out: list[tuple[ir.Node, ir.Orient | None]] = []
    orient: ir.Orient | None = None
    for node in nodes:
        if isinstance(node, ir.Orient):
            orient = node
            out.append((node, node))
            continue
        out.append((node_in_work(orient, node), orient))
    return out
