"""The features of a spec skeleton (``probegen init``): everything recognised on a part
that compiles as it stands, and everything else with the reason it was left out.

Three sources, each feature checked by planning it alone with the machine's stylus and
the collision check (the same code ``compile`` runs):

- revolved features (:func:`probegen.planning.revolved_spec.all_revolved`: bores,
  bosses, cones, spheres, tori with their nominal sizes), ids ``R<n>`` as
  ``features --revolved`` numbers them;
- planar faces not facing down, as ``plane`` features touched at up to
  :data:`PLANE_CONTACTS` points spread over the face, each ``r + margin`` from every
  edge (``r`` the ball radius), ids ``P<face>``;
- free-form faces (B-spline, Bézier, offset, extrusion and revolution surfaces) whose
  normal lies within 60 deg of +Z, as ``freeform`` features on a 3 x 3 ``uv`` grid, ids
  ``F<face>``.

Ids are upper-case letters and digits of at most 12 characters, unique (each prefix
numbers a different thing), valid in every dialect.  The text of the skeleton is written
by :mod:`probegen.cli.init`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from probegen.errors import ProbegenError
from probegen.machine.profile import MachineProfile
from probegen.spec.actions import PlanarSpec
from probegen.spec.model import Feature, FreeformSpec, RevolvedSpec, Spec

if TYPE_CHECKING:
    from probegen.cad import Part

PLANE_CONTACTS = 4
"""Contacts a plane gets (the fewest its flatness is evaluated from), when it has room."""
PLANE_GRID = 16
"""Grid lines per direction over a planar face's box when looking for contact points."""
FREEFORM_GRID = (3, 3)
"""Guide points of a free-form feature, per parameter direction."""
FREEFORM_TYPES = ("bspline", "bezier", "offset", "extrusion", "revolution", "other")
"""Face types measured as free-form features."""
MAX_TILT = 60.0
"""Largest angle of a free-form face's normal from +Z the spec accepts, degrees."""


@dataclass(frozen=True, slots=True)
class Entry:
    """One feature of the skeleton, compiled alone without error.

    Attributes:
        feature: the spec feature (its id, kind, face and keys).
        title: what it is, with its nominal size (``bore D10.000``, ``plane at z = 5``).
        source: where it came from (face ids, the recognised feature).
        tolerance: a tolerance table for the commented line (TOML inline table).
    """

    feature: Feature
    title: str
    source: str
    tolerance: str


@dataclass(frozen=True, slots=True)
class Skeleton:
    """The skeleton of a part: its features, the clearance plane (mm) and one line per
    feature left out (``id what (faces): reason``)."""

    clearance_z: float
    features: tuple[Entry, ...]
    left_out: tuple[str, ...]


def skeleton(part: Part, machine: MachineProfile) -> Skeleton:
    """Every recognised feature of ``part`` that compiles alone on ``machine``, and the
    ones left out with their reasons (revolved, then planes, then free-form faces).  The
    revolved features are those every dialect can evaluate
    (:func:`probegen.planning.well_posed.for_every_dialect`): the skeleton compiles
    unchanged with any ``-d``."""
    from probegen.planning.revolved_spec import CLEARANCE_ABOVE_MODEL, all_revolved
    from probegen.planning.well_posed import for_every_dialect

    clearance = max(machine.clearance_z, part.bbox_max[2] + CLEARANCE_ABOVE_MODEL)
    revolved, notes = all_revolved(part, for_every_dialect(machine), clearance)
    entries = [_revolved_entry(part, f) for f in revolved]
    left = list(notes)
    for face in part.faces:
        if face.type == "plane":
            found = _plane(part, machine, clearance, face)
        elif face.type in FREEFORM_TYPES:
            found = _freeform(part, machine, clearance, face)
        else:
            continue
        if isinstance(found, Entry):
            entries.append(found)
        else:
            left.append(found)
    return Skeleton(clearance, tuple(entries), tuple(left))


# ------------------------------------------------------------------------- revolved


def _revolved_entry(part: Part, spec: RevolvedSpec) -> Entry:
    """The entry of a revolved feature ``all_revolved`` kept."""
    from probegen.cad.revolved import revolved_features

    number = int(spec.id[1:])
    f = next(r for r in revolved_features(part) if r.id == number)
    title, tolerance = revolved_title(f)
    faces = ",".join(map(str, f.faces))
    low, high = (f.centre_at(h)[2] for h in f.extent)
    return Entry(spec, title, f"revolved feature {f.id}, faces {faces}, z "
                              f"{_mm(min(low, high))} to {_mm(max(low, high))}", tolerance)


def revolved_title(f: Any) -> tuple[str, str]:
    """What a recognised revolved feature is, with its nominal size
    (:func:`probegen.planning.left_out.describe`, a cylinder's length, a cone's half
    angle), and a tolerance table for it (``diameter`` ±0.05 mm: the tube's of a torus)."""
    from probegen.planning.left_out import describe

    title = describe(f)
    if f.type == "cylinder":
        return (f"{title}, length {f.length:.3f}",
                "{ diameter = [-0.05, 0.05], position = 0.1, form = 0.05 }")
    if f.type == "cone":
        return (f"{title} at its origin, half angle {math.degrees(f.half_angle or 0.0):.3f} "
                "deg", "{ position = 0.1, angle = [-0.5, 0.5] }")
    if f.type == "sphere":
        return title, "{ diameter = [-0.05, 0.05], position = 0.1, form = 0.05 }"
    return title, "{ diameter = [-0.05, 0.05], position = 0.1 }"


# --------------------------------------------------------------------------- planes


def _plane(part: Part, machine: MachineProfile, clearance: float, face: Any) -> Entry | str:
    """A plane feature on a planar ``face``, or why there is none."""
    fid, n = f"P{face.id}", face.axis
    what = f"{fid} plane (face {face.id}, normal {_vec(n)})"
    if n[2] < -1e-6:
        return (f"{what}: faces down: the probe (along Z) cannot reach it: needs an "
                "orientation or a setup")
    edge = machine.probe.ball_radius + machine.margin
    contacts = plane_contacts(part, face.id, n, edge)
    if not contacts:
        return (f"{what}: no point {edge:.3f} mm (ball radius + margin) from every edge: "
                "narrower than the stylus ball: a smaller stylus")
    why = ""
    for tried in (contacts, *((c,) for c in contacts)):  # a boss between them: touch one
        spec = PlanarSpec(fid, f"{part.path}: face {face.id}", "plane", face.id, None,
                          tried, None)
        why = _compiles(part, machine, clearance, spec)
        if not why:
            contacts = tried
            break
    if why:
        return f"{what}: {why}"
    offset = sum(a * b for a, b in zip(face.origin, n, strict=True))
    form = ", form = 0.05" if len(contacts) >= PLANE_CONTACTS else ""
    return Entry(spec, f"plane, {len(contacts)} contact{'s' if len(contacts) > 1 else ''}, "
                       f"normal {_vec(n)}, {_mm(offset)} mm from the origin",
                 f"face {face.id}, area {face.area:.1f} mm2",
                 f"{{ position = [-0.05, 0.05]{form} }}")


def plane_contacts(part: Part, face: int, normal: tuple[float, float, float],
                   edge: float) -> tuple[tuple[float, float, float], ...]:
    """Up to :data:`PLANE_CONTACTS` points of planar face ``face`` at least ``edge`` mm
    from its boundary (holes included), spread by farthest-point sampling from the
    point farthest from the boundary; from the face's triangles in the part's mesh."""
    mesh = part.mesh()
    ids = np.asarray(mesh.metadata["face_ids"])
    tris = np.asarray(mesh.faces)[ids == face]
    if len(tris) == 0:
        return ()
    n = np.asarray(normal, dtype=float)
    e1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    xyz = np.asarray(mesh.vertices)
    flat = np.stack([xyz @ e1, xyz @ e2], axis=1)
    grid = _grid(flat[tris.ravel()])
    inside = _in_triangles(grid, flat[tris])
    points = grid[inside]
    if len(points) == 0:
        return ()
    room = _edge_distance(points, flat, tris)
    keep = points[room >= edge]
    if len(keep) == 0:
        return ()
    chosen = [int(np.argmax(room[room >= edge]))]
    while len(chosen) < min(PLANE_CONTACTS, len(keep)):
        far = np.min(np.linalg.norm(keep[:, None, :] - keep[chosen][None, :, :], axis=2), axis=1)
        if far.max() < edge:
            break
        chosen.append(int(np.argmax(far)))
    height = float(np.mean(xyz[tris.ravel()] @ n))
    return tuple(_vec3(p[0] * e1 + p[1] * e2 + height * n) for p in keep[chosen])


def _grid(flat: np.ndarray) -> np.ndarray:
    """A :data:`PLANE_GRID` square grid over the box of 2-D points (cell centres)."""
    lo, hi = flat.min(axis=0), flat.max(axis=0)
    t = (np.arange(PLANE_GRID) + 0.5) / PLANE_GRID
    u, v = np.meshgrid(lo[0] + t * (hi[0] - lo[0]), lo[1] + t * (hi[1] - lo[1]))
    return np.stack([u.ravel(), v.ravel()], axis=1)


def _in_triangles(points: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Which 2-D ``points`` lie in one of the 2-D triangles ``tris`` (m, 3, 2)."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]

    def side(p: np.ndarray, q: np.ndarray, x: np.ndarray) -> np.ndarray:
        return ((q[None, :, 0] - p[None, :, 0]) * (x[:, None, 1] - p[None, :, 1])
                - (q[None, :, 1] - p[None, :, 1]) * (x[:, None, 0] - p[None, :, 0]))

    s1, s2, s3 = side(a, b, points), side(b, c, points), side(c, a, points)
    same = ((s1 >= 0) & (s2 >= 0) & (s3 >= 0)) | ((s1 <= 0) & (s2 <= 0) & (s3 <= 0))
    return np.asarray(same.any(axis=1))


def _edge_distance(points: np.ndarray, flat: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Distance of each 2-D point to the boundary of the triangle set (its edges used by
    one triangle only)."""
    edges = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    border = unique[count == 1]
    p, q = flat[border[:, 0]], flat[border[:, 1]]
    d = q - p
    length = np.maximum(np.sum(d * d, axis=1), 1e-18)
    t = np.clip(np.einsum("mk,nmk->nm", d, points[:, None, :] - p[None]) / length, 0.0, 1.0)
    foot = p[None] + t[:, :, None] * d[None]
    return np.asarray(np.min(np.linalg.norm(points[:, None, :] - foot, axis=2), axis=1))


# ------------------------------------------------------------------------ free-form


def _freeform(part: Part, machine: MachineProfile, clearance: float,
              face: Any) -> Entry | str:
    """A free-form feature on ``face``, or why there is none."""
    fid, n = f"F{face.id}", face.axis
    what = f"{fid} free-form {face.type} face (face {face.id}, normal {_vec(n)})"
    tilt = math.degrees(math.acos(max(-1.0, min(1.0, n[2]))))
    if tilt > MAX_TILT:
        return (f"{what}: normal {tilt:.1f} deg from +Z, more than the {MAX_TILT:g} deg a probe "
                "along Z measures: needs an orientation or a setup")
    spec = FreeformSpec(fid, f"{part.path}: face {face.id}", face.id, None, "uv",
                        FREEFORM_GRID, None, machine.probe.ball_radius, n, "vector", 0.5, None)
    why = _compiles(part, machine, clearance, spec)
    if why:
        return f"{what}: {why}"
    return Entry(spec, f"free-form {face.type} face, normal {_vec(n)} ({tilt:.1f} deg from +Z)",
                 f"face {face.id}, area {face.area:.1f} mm2", "{ deviation = [-0.1, 0.1] }")


# ------------------------------------------------------------------------ shared


def _compiles(part: Part, machine: MachineProfile, clearance: float, feature: Feature) -> str:
    """Why ``feature`` alone does not plan with its collision check ("" when it does)."""
    from probegen.planning import plan_program

    spec = Spec(source=part.path, model=Path(part.path), machine=machine,
                dialect=machine.dialect, clearance_z=clearance, program_number=1001,
                program_name="INIT", features=(feature,), raised=part.raised)
    try:
        plan_program(spec, runtime_variables=True, part=part)
    except ProbegenError as exc:
        from probegen.planning.left_out import collision_reason

        text = str(exc)
        return collision_reason(text.split(": ", 2)[-1] if text.startswith(part.path)
                                else text)
    return ""


def _mm(x: float) -> str:
    """``x`` with 3 decimals, never ``-0.000``."""
    text = f"{x:.3f}"
    return "0.000" if text == "-0.000" else text


def _vec(v: tuple[float, float, float]) -> str:
    return "(" + ", ".join(_mm(x) for x in v) + ")"


def _vec3(v: np.ndarray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))
