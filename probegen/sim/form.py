"""Planted form errors of the part: a radial deviation ``δ(θ, h)`` on a revolved face.

The virtual machine places the nominal model; a :class:`FormError` perturbs one of its
cylinder, cone, sphere or torus faces so the closed loop can check that taper,
roundness and other form errors come back out of the evaluation.

Deviation (mm)::

    δ(θ, h) = offset + taper·h + Σ a_k·cos(k·θ + φ_k) + custom(θ, h)

* The face's frame: ``k`` is the face's axis (``FaceRecord.axis``; a sphere's points
  from its centre towards the face's centre of mass) pointed up (``+Z``; a horizontal
  axis ``+Y``, then ``+X``); ``θ`` (rad) is the polar angle about ``k`` in the frame
  ``geometry.frames.rotation_to_z(k)`` (for a vertical face: from ``+X`` towards
  ``+Y``); ``h`` (mm) is the axial position along ``k``, from the foot of the part
  origin on the axis for cylinders and cones (a vertical face: ``h`` is the part's
  ``Z``) and from the centre for spheres and tori.
* Meaning: the face's radius parameter becomes ``radius + δ`` where the surface is
  touched: a cylinder's or sphere's radius, a cone's radius at every height (its
  section radius at ``h`` is ``ρ(h) + δ``), a torus's tube radius.  ``δ > 0`` moves the
  surface away from the axis (a larger bore, a larger boss; a thicker tube).

Contact model (``local radius``): the ball touches the perturbed face where it would
touch the analytic face of radius ``radius + δ*``, ``δ*`` taken at that contact's own
foot point.  :func:`form_roots` solves it by a fixed-point iteration: contact on the
face with the current ``δ``, ``δ`` again at the new foot, until ``δ`` changes by less
than :data:`DELTA_TOLERANCE` (the contact then moves by less than that over the cosine
of the approach angle, about 1e-10 mm on a square approach).  It is exact for
``offset`` (a uniform size error).  Against the ball truly rolling on the perturbed
surface it neglects the tilt of the perturbed surface: the error is at most about
``r·g²/2`` with ``g`` the slope of ``δ`` along the surface (``|∂δ/∂h|``,
``|∂δ/∂θ|/ρ``): a taper of 2e-4 and a 3 mm ball give 6e-8 mm, a 3-lobe form of
5 µm on a 25 mm radius 3e-10 mm.  The feature's boundary edges and every other face
stay nominal (a step of ``δ`` where the face ends), so plan the touches away from the
edges by more than ``|δ|``.

Form file (``probegen sim --form FILE``)::

    [[form]]
    face = 10                  # model face id (``probegen features MODEL`` lists them)
    offset = 0.0               # mm
    taper = 0.0002             # mm of radius per mm of h
    lobes = [[3, 0.004, 30.0]] # [k, amplitude mm, phase degrees], any number
    limit = 0.1                # largest |δ| the face may take, mm (default 0.1)
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from probegen.cad import FaceRecord
from probegen.cad.exact import FloatArray, Root, face_roots, nearest_on_surface
from probegen.errors import ProbegenError, SpecError
from probegen.files import Table, load_toml
from probegen.geometry.frames import rotation_to_z

FORM_TYPES = ("cylinder", "cone", "sphere", "torus")
"""Face types a form error can perturb."""
DELTA_TOLERANCE = 1e-10
"""The fixed-point iteration stops when ``δ`` changes by less than this, mm."""
MAX_ITERATIONS = 50
"""Iteration limit of the fixed point (a smooth, small ``δ`` converges in 2-4)."""
SIDE_STEP = 1e-6
"""Radius step (mm) that tells on which side of the perturbed face a point lies."""
MAX_LIMIT = 0.4
"""Largest allowed ``limit``, mm: the contact search's mesh tracing stops 0.5 mm before
the mesh, so a face may move at most less than that."""


@dataclass(frozen=True, slots=True)
class Lobe:
    """One roundness harmonic ``amplitude·cos(k·θ + phase)``: ``k`` >= 1 lobes,
    amplitude (mm), phase (rad)."""

    k: int
    amplitude: float
    phase: float = 0.0


@dataclass(frozen=True, slots=True)
class FormError:
    """A radial deviation of one model face (see the module doc for ``δ``, ``θ``, ``h``).

    Attributes:
        face: the model face id (1-based).
        offset: constant part of ``δ``, mm.
        taper: slope of ``δ`` along the axis, mm per mm.
        lobes: roundness harmonics.
        custom: any further term ``(θ rad, h mm) -> mm`` (smooth and small), or None.
        limit: the largest ``|δ|`` the face may take, mm; a larger value at a touch
            is an error (the contact search allows for this much).
    """

    face: int
    offset: float = 0.0
    taper: float = 0.0
    lobes: tuple[Lobe, ...] = ()
    custom: Callable[[float, float], float] | None = None
    limit: float = 0.1

    def delta(self, theta: float, h: float) -> float:
        """``δ(θ, h)``, mm."""
        d = self.offset + self.taper * h
        d += sum(lobe.amplitude * math.cos(lobe.k * theta + lobe.phase)
                 for lobe in self.lobes)
        if self.custom is not None:
            d += float(self.custom(theta, h))
        return d


class BoundForm:
    """A form error on its face: ``δ`` at part-frame points, perturbed face records."""

    def __init__(self, form: FormError, record: FaceRecord) -> None:
        if record.type not in FORM_TYPES:
            raise ProbegenError(f"form error on face {form.face}: expected a face of type "
                                f"{', '.join(FORM_TYPES)}, found {record.type}")
        if not 0.0 < form.limit <= MAX_LIMIT:
            raise ProbegenError(f"form error on face {form.face}: expected a limit in "
                                f"(0, {MAX_LIMIT}] mm, found {form.limit}")
        self.form = form
        self.record = record
        k = np.asarray(record.axis, dtype=np.float64)
        self.axis = k if tuple(k[::-1]) > (0.0, 0.0, 0.0) else -k
        o = np.asarray(record.origin, dtype=np.float64)
        if record.type in ("cylinder", "cone"):
            o = o - float(o @ self.axis) * self.axis  # foot of the part origin
        self.origin = o
        self.frame = rotation_to_z(self.axis)

    def delta_at(self, point: FloatArray) -> float:
        """``δ`` at a part-frame point (its ``θ`` and ``h``), mm."""
        q = self.frame @ (point - self.origin)
        return self.form.delta(math.atan2(q[1], q[0]), float(q[2]))

    def check(self, foot: FloatArray) -> None:
        """Raise unless ``|δ|`` at a touched point is within the form's limit."""
        d = self.delta_at(foot)
        if not (math.isfinite(d) and abs(d) <= self.form.limit):
            raise ProbegenError(f"form error on face {self.form.face}: expected |δ| <= "
                                f"{self.form.limit} mm (its limit), found {d} at "
                                f"{np.round(foot, 4).tolist()}")

    def inside(self, c: FloatArray, foot: FloatArray) -> bool:
        """Whether ``c`` lies in the material, judged at its nearest point ``foot`` of
        the perturbed face: the material is on the side of the larger radius parameter
        for a concave (``inner``) face, of the smaller one for a convex face."""
        grown = nearest_on_surface(self.with_delta(self.delta_at(foot) + SIDE_STEP), c)
        if grown is None:
            return False
        closer = float(np.linalg.norm(c - grown)) < float(np.linalg.norm(c - foot))
        return closer == bool(self.record.inner)

    def with_delta(self, delta: float) -> FaceRecord:
        """The face record with its radius parameter changed by ``delta``."""
        r = self.record
        if r.type == "torus":
            return dataclasses.replace(r, minor_radius=(r.minor_radius or 0.0) + delta)
        return dataclasses.replace(r, radius=(r.radius or 0.0) + delta)

    def roots(self, a: FloatArray, u: FloatArray, r: float) -> list[Root]:
        """Entering roots of the move ``a + s·u`` (part frame) against the perturbed
        face offset by the ball radius ``r``: each nominal root moved to its fixed
        point (see the module doc), sorted along the move."""
        out = []
        for s0, _ in face_roots(self.record, a, u, r):
            root = self._fixed_point(a, u, r, s0)
            if root is not None:
                out.append(root)
        return sorted(out, key=lambda root: root[0])

    def _fixed_point(self, a: FloatArray, u: FloatArray, r: float,
                     s: float) -> Root | None:
        delta, n = 0.0, None
        for _ in range(MAX_ITERATIONS):
            roots = face_roots(self.with_delta(delta), a, u, r)
            if not roots:
                return None
            s, n = min(roots, key=lambda root: abs(root[0] - s))
            new = self.delta_at(a + s * u - r * n)
            if not math.isfinite(new):
                raise ProbegenError(f"form error on face {self.form.face}: expected a "
                                    f"finite δ, found {new}")
            if abs(new - delta) <= DELTA_TOLERANCE:
                return s, n
            delta = new
        raise ProbegenError(f"form error on face {self.form.face}: the contact did not "
                            f"converge in {MAX_ITERATIONS} steps (is δ small and smooth?)")

    def nearest(self, c: FloatArray) -> FloatArray | None:
        """The nearest point to ``c`` of the perturbed untrimmed surface (local radius
        model), or None where it is not unique."""
        foot = nearest_on_surface(self.record, c)
        for _ in range(MAX_ITERATIONS):
            if foot is None:
                return None
            delta = self.delta_at(foot)
            new = nearest_on_surface(self.with_delta(delta), c)
            if new is None or float(np.linalg.norm(new - foot)) <= DELTA_TOLERANCE:
                return new
            foot = new
        raise ProbegenError(f"form error on face {self.form.face}: the nearest point did "
                            f"not converge in {MAX_ITERATIONS} steps")


def load_forms(path: str | Path) -> tuple[FormError, ...]:
    """Read a form file (see the module doc); errors name the file and key."""
    root = Table(load_toml(path), str(path), "")
    forms = [_form(t) for t in root.tables("form")]
    root.done()
    if not forms:
        raise SpecError(f"{path}: expected at least one [[form]] table, found none")
    faces = [f.face for f in forms]
    if len(set(faces)) != len(faces):
        raise SpecError(f"{path}: expected each face once, found faces {faces}")
    return tuple(forms)


def _form(t: Table) -> FormError:
    face = t.get_int("face", required=True, minimum=1) or 1
    lobes = t.get_any("lobes", [])
    ok = isinstance(lobes, list) and all(
        isinstance(v, list) and len(v) == 3 and isinstance(v[0], int)
        and not isinstance(v[0], bool) and v[0] >= 1
        and all(isinstance(x, int | float) and not isinstance(x, bool)
                and math.isfinite(x) for x in v[1:]) for v in lobes)
    if not ok:
        raise t.fail("lobes", "an array of [k >= 1, amplitude mm, phase degrees]")
    form = FormError(
        face=face, offset=t.get_float("offset", 0.0) or 0.0,
        taper=t.get_float("taper", 0.0) or 0.0,
        lobes=tuple(Lobe(int(v[0]), float(v[1]), math.radians(v[2])) for v in lobes),
        limit=t.get_float("limit", 0.1, positive=True, maximum=MAX_LIMIT) or 0.1)
    t.done()
    return form
