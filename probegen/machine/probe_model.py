"""The touch-trigger probe as the virtual machine sees it: ball, pre-travel, noise.

A kinematic touch-trigger probe seats its stylus holder on three radial rods 120° apart
(six contact points, three pairs).  The trigger fires when a contact opens, i.e. when
the stylus force reaches the seat's spring force times the ratio of two lever arms.  A
sideways push tips the holder about one seat pair or about the line between two, and
that pivot line turns with the push direction with a period of 120°: the force needed,
and so the pre-travel (how far the stylus bends before the trigger), repeats three times
per turn.  A push along the stylus lifts all three seats at once and needs the least
bending.  This is the 3-lobe pattern of probing-system tests (ISO 10360-5).

Probe frame: ``z`` along the stylus, from the ball towards the probe body (the spindle's
+Z for a spindle probe on a vertical machine); ``x`` along the reference direction of
the lobes (the spindle orientation of ``M19``).  A probing direction ``n`` (unit vector
of the ball centre's motion at the touch) has polar angle ``θ`` from ``−z`` (θ = 0:
moving down along the stylus, an axial touch) and azimuth ``φ`` in the x-y plane.

Default pre-travel model (:class:`Lobing`), smooth over the whole sphere of directions
(a polynomial in the components of ``n``)::

    δ(n) = lateral·sin²θ + axial·cos²θ + lobe·sin³θ·cos(3(φ − phase))

``sin³θ·cos 3φ = n_x³ − 3·n_x·n_y²`` is the lowest-order smooth 3-fold term; the
``sin θ`` of a plain ``a3·cos 3φ·sin θ`` would make the lobes a cone at the pole.  A
touch from below (pulling along the stylus) gets the axial value too.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from probegen.errors import ProbegenError

FloatArray = NDArray[np.float64]
Pretravel = Callable[[FloatArray], ArrayLike]
"""A pre-travel function: unit directions (n, 3) in the probe frame to mm (n,)."""


def tilted_probe_frame(directions: ArrayLike, b_degrees: float) -> FloatArray:
    """Machine-frame directions (n, 3) or (3,) in the probe frame of a head tilted by
    ``b_degrees`` about Y (its stylus axis turns with B)."""
    d = np.asanyarray(directions, dtype=np.float64)
    b = math.radians(b_degrees)
    c, s = math.cos(b), math.sin(b)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return np.asarray(np.stack([c * x - s * z, y, s * x + c * z], axis=-1))


@dataclass(frozen=True, slots=True)
class Lobing:
    """The 3-lobe pre-travel model of the module docstring.

    Attributes:
        lateral: mean pre-travel of a sideways touch (θ = 90°), mm.
        axial: pre-travel of a touch along the stylus (θ = 0°), mm.
        lobe: amplitude of the 3-fold variation of sideways touches, mm.
        phase: azimuth of the first lobe maximum, rad.
    """

    lateral: float = 0.0
    axial: float = 0.0
    lobe: float = 0.0
    phase: float = 0.0

    def __call__(self, directions: FloatArray) -> FloatArray:
        """Pre-travel (n,) mm for unit directions (n, 3) in the probe frame."""
        n = np.asanyarray(directions, dtype=np.float64)
        c, s = math.cos(self.phase), math.sin(self.phase)
        x = c * n[:, 0] + s * n[:, 1]  # azimuth measured from the phase
        y = -s * n[:, 0] + c * n[:, 1]
        side = x * x + y * y
        return np.asarray(self.lateral * side + self.axial * n[:, 2] ** 2
                          + self.lobe * (x**3 - 3.0 * x * y * y))


class ProbeModel:
    """A touch-trigger probe: ball radius, direction-dependent pre-travel and noise.

    Args:
        ball_radius: stylus ball radius, mm, positive.
        pretravel: a :class:`Lobing`, its coefficients ``(lateral, axial, lobe,
            phase)``, or any function of unit directions (n, 3) returning mm (n,).
        noise_sigma: standard deviation of the trigger repeatability, mm (Gaussian,
            along the probing direction).
        seed: seed of the noise stream; the same seed gives the same sequence.
    """

    def __init__(self, ball_radius: float, pretravel: Lobing | Sequence[float] | Pretravel
                 = Lobing(), noise_sigma: float = 0.0, seed: int = 0) -> None:
        if not (math.isfinite(ball_radius) and ball_radius > 0.0):
            raise ProbegenError(f"probe ball radius: expected a positive number, found "
                                f"{ball_radius!r}")
        if not (math.isfinite(noise_sigma) and noise_sigma >= 0.0):
            raise ProbegenError(f"probe noise sigma: expected a number >= 0, found "
                                f"{noise_sigma!r}")
        self.ball_radius = float(ball_radius)
        self.pretravel: Pretravel = (
            pretravel if callable(pretravel) else Lobing(*(float(v) for v in pretravel)))
        self.noise_sigma = float(noise_sigma)
        self.seed = seed
        self._rng = np.random.default_rng(seed)

    def trigger_offset(self, direction: ArrayLike) -> FloatArray | float:
        """How far the machine moves past the first touch before the trigger, mm.

        Args:
            direction: (3,) or (n, 3) float, the ball's motion in the probe frame (need
                not be unit length; not zero).

        Returns:
            A float for one direction, else (n,) float.  No noise (see :meth:`noisy_offset`).
        """
        d = np.asanyarray(direction, dtype=np.float64)
        n = np.atleast_2d(d)
        size = np.linalg.norm(n, axis=1)
        if n.shape[-1] != 3 or not np.all(np.isfinite(size)) or np.any(size == 0.0):
            raise ProbegenError(f"probing direction: expected non-zero 3-vectors, found "
                                f"{d.tolist()}")
        out = np.asarray(self.pretravel(n / size[:, None]), dtype=np.float64).reshape(-1)
        return float(out[0]) if d.ndim == 1 else out

    def noise(self, size: int | None = None) -> FloatArray | float:
        """The next draw(s) of the trigger noise, mm (0 when ``noise_sigma`` is 0)."""
        draw = self._rng.normal(0.0, 1.0, size) * self.noise_sigma
        return float(draw) if size is None else np.asarray(draw)

    def noisy_offset(self, direction: ArrayLike) -> FloatArray | float:
        """:meth:`trigger_offset` plus the next noise draw(s), mm."""
        offset = self.trigger_offset(direction)
        if isinstance(offset, float):
            return offset + float(self.noise())
        return offset + np.asarray(self.noise(len(offset)))

    def reset(self) -> None:
        """Restart the noise stream from the seed."""
        self._rng = np.random.default_rng(self.seed)
