"""Free-form features (method M3) from their touches: contact points and normal deviations.

Each guide point ``g`` of a planned free-form feature has its own touch (index ``10·g``,
the ball centre ``O_a``) and, for the 2-D and micro-plane methods, two or three extra
touches (``10·g + 1 ...``).  The ball centres are compensated by
:mod:`probegen.evaluate.compensate_freeform` (``vertical``: naive ``O − r·ẑ``; ``vertical2d``:
the 2-D profile normal; ``microplane``: the plane through the extra touches;
``vector``: the nominal normal along which the ball travelled), and each contact point
``P_a`` is compared with its theoretical contact point ``P_t`` along the nominal normal:
``e = (P_a − P_t)·n`` (+ = material added).

Characteristics: ``E<g>`` for each guide point ``g`` (measured = nominal + ``e``, with
the nominal ``0``), checked against ``tolerance.deviation``.  numpy only.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from probegen.errors import ProbegenError
from probegen.evaluate import compensate_freeform as cf
from probegen.evaluate.characteristics import Characteristic, accepted
from probegen.geometry.uncertainty import Budget, combine
from probegen.machine.calibration import ProbeCalibration
from probegen.spec.model import FREEFORM_EXTRA as EXTRA
from probegen.spec.model import FREEFORM_STRIDE as STRIDE

Vec3 = tuple[float, float, float]
Touches = Mapping[tuple[str, int], Vec3]
"""Ball centres by (feature id, touch index), mm."""

@dataclass(frozen=True, slots=True)
class NominalPoint:
    """What the plan says about one guide point: its number, the theoretical contact
    point ``P_t`` of its own touch and the outward normal there (mm, unit)."""

    guide: int
    contact: Vec3
    normal: Vec3


@dataclass(frozen=True, slots=True)
class FreeformResult:
    """An evaluated free-form feature.

    Attributes:
        feature: feature id.
        method: the M3 method.
        guides: the guide points evaluated (1-based).
        nominal: their theoretical contact points ``P_t``, mm.
        points: the compensated contact points ``P_a``, mm.
        directions: the nominal outward normals at ``P_t``.
        residuals: the deviations ``e`` along the nominal normals, mm.
        normals_used: the normals the compensation used (estimated or nominal).
        characteristics: ``E<g>`` per guide point.
    """

    feature: str
    method: str
    guides: tuple[int, ...]
    nominal: tuple[Vec3, ...]
    points: tuple[Vec3, ...]
    directions: tuple[Vec3, ...]
    residuals: tuple[float, ...]
    normals_used: tuple[Vec3, ...]
    characteristics: tuple[Characteristic, ...]
    kind: str = "freeform"

    @property
    def ok(self) -> bool | None:
        """All toleranced characteristics within limits (None if none is toleranced)."""
        return accepted(self.characteristics)

    @property
    def summary(self) -> cf.DeviationSummary:
        """Count, min, max, mean and RMS of the deviations, mm."""
        return cf.summarise(self.residuals)


def complete_guides(feature: str, method: str, nominal: Sequence[NominalPoint],
                    touches: Touches) -> tuple[list[NominalPoint], list[int]]:
    """The guide points with every touch their method needs, and those missing some."""
    roles = range(1 + EXTRA[method])
    full = [p for p in nominal
            if all((feature, STRIDE * p.guide + j) in touches for j in roles)]
    done = {p.guide for p in full}
    return full, [p.guide for p in nominal if p.guide not in done]


def evaluate_freeform(feature: str, method: str, nominal: Sequence[NominalPoint],
                      touches: Touches, *, direction: Vec3,
                      radius: float | ProbeCalibration,
                      deviation: tuple[float, float] | None = None,
                      budget: Budget | None = None) -> FreeformResult:
    """Compensate the touches of every complete guide point and evaluate the deviations.

    Args:
        feature: feature id (as in the touches' keys).
        method: ``vertical``, ``vertical2d``, ``microplane`` or ``vector``.
        nominal: the planned guide points, each with every touch in ``touches``
            (see :func:`complete_guides`).
        touches: ball centres by (feature, touch index), mm.
        direction: unit guide direction, out of the material (the vertical methods
            travel along its opposite).
        radius: ball radius, mm, or the probe calibration.
        deviation: allowed ``[lower, upper]`` deviation along the normal, mm.
        budget: the stated uncertainty contributions: each deviation is one touch, so
            its ``u`` combines the probe's, the machine's and the radius's (no fit).

    Raises:
        ProbegenError: no guide point, or touches from which no normal follows.
    """
    if not nominal:
        raise ProbegenError(f"feature {feature}: no guide point with all its touches")
    base = [STRIDE * p.guide for p in nominal]
    centres = np.array([touches[(feature, k)] for k in base])
    extra = EXTRA[method]
    others = np.array([[touches[(feature, k + j)] for j in range(1, extra + 1)]
                       for k in base]).reshape(len(base), extra, 3)
    travel = -np.asarray(direction, dtype=np.float64)
    p_t = np.array([p.contact for p in nominal])
    n_t = np.array([p.normal for p in nominal])
    if method == "vector":
        comp = cf.vector(centres, n_t, radius)
    elif method == "vertical2d":
        comp = cf.two_d(centres, others, radius, probe_direction=travel)
    elif method == "microplane":
        comp = cf.micro_plane(centres, others, radius, probe_direction=travel)
    else:
        comp = cf.naive(centres, radius, probe_direction=travel)
    dmap = cf.deviation_map(comp, p_t, n_t)
    lo, hi = deviation if deviation is not None else (None, None)
    b = budget or Budget()
    u = combine(b.u_probe, b.u_machine, b.radius)
    chars = tuple(Characteristic(f"E{p.guide}", float(e), 0.0, float(e), lo, hi, u)
                  for p, e in zip(nominal, dmap.deviation, strict=True))
    return FreeformResult(
        feature, method, tuple(p.guide for p in nominal), _rows(p_t), _rows(comp.contacts),
        _rows(dmap.normals), tuple(float(e) for e in dmap.deviation), _rows(comp.normals),
        chars)


def _rows(a: np.ndarray) -> tuple[Vec3, ...]:
    return tuple((float(x), float(y), float(z)) for x, y, z in np.asarray(a).tolist())
