"""The in-process decisions computed again offline, next to what the machine printed.

The program's ``Check`` arithmetic (``dialects/fanuc_actions.py``) is repeated here in
numpy on the ball centres of the log's ``PT`` lines: the algebraic (Kasa) circle
(:func:`probegen.geometry.fits_initial.algebraic_circle`), the principal direction of a
line (:func:`probegen.geometry.fits.fit_line_2d`), positions along a face's normal, the
limits and the tool correction.  Each value is paired with the one the machine printed
in its ``RES`` line; they agree to the log's precision (the machine computes from
unrounded skip positions, the log prints 4 decimals).  Two independent paths check
each other: a wrong sign or formula in either shows as a disagreement.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from probegen.errors import ProbegenError
from probegen.geometry.fits import fit_line_2d
from probegen.geometry.fits_initial import algebraic_circle
from probegen.ir.actions import Check, Limit, point_index
from probegen.machine.calibration import ProbeCalibration
from probegen.results import DprntLog
from probegen.spec.actions import PlanarSpec, ToolAction
from probegen.spec.model import RevolvedSpec, Spec

if TYPE_CHECKING:
    from probegen.cad import Part

Vec3 = tuple[float, float, float]

LENGTH_AGREEMENT = 2e-4
"""Largest offline-machine difference of a length (mm) that counts as agreeing: the log
rounds each point and each printed value to 1e-4."""
LOG_ROUNDING = 5e-5
"""Half the last printed digit of a coordinate, mm."""


@dataclass(frozen=True, slots=True)
class Decision:
    """One value of a feature's decision, computed offline and printed by the machine.

    Attributes:
        feature: feature id.
        key: ``X Y D F P A E NG C`` (``ir_actions``; ``C`` the tool correction made).
        offline: the value computed from the log's points (None: too few points).
        machine: the value the machine printed (None: not printed, e.g. after an alarm).
        limit: the largest difference that counts as agreeing.
    """

    feature: str
    key: str
    offline: float | None
    machine: float | None
    limit: float

    @property
    def agrees(self) -> bool | None:
        """Whether both are known and within ``limit``; None when one is missing."""
        if self.offline is None or self.machine is None:
            return None
        return abs(self.offline - self.machine) <= self.limit


def evaluate_check(check: Check, balls: dict[int, Vec3]) -> dict[str, float]:
    """The values of ``check`` from ball centres by touch index (mm, degrees).

    Raises:
        ProbegenError: a touch is missing or the points fit nothing.
    """
    names = [next(n for n in p if n is not None) for p in check.points]
    missing = [point_index(n) for n in names if point_index(n) not in balls]
    if missing:
        raise ProbegenError(f"feature {check.feature}: no touch for points "
                            f"{', '.join(map(str, missing))}")
    pts = np.array([balls[point_index(n)] for n in names], dtype=np.float64)
    if check.corrections:  # the calibration, as the program applies it
        pts = pts + np.asarray(check.corrections, dtype=np.float64)
    out = _circle(check, pts) if check.fit == "circle" else _planar(check, pts)
    out["NG"] = float(any(_exceeds(check, out, lim) for lim in check.limits))
    return out


def _exceeds(check: Check, values: dict[str, float], lim: Limit) -> bool:
    """Whether a limit is exceeded (the program's comparisons: a zone has no lower
    limit)."""
    value = _deviation(check, values, lim.key)
    two_sided = lim.key == "diameter" or (lim.key == "position" and check.fit != "circle")
    return value > lim.upper or (two_sided and value < lim.lower)


def _circle(check: Check, pts: np.ndarray) -> dict[str, float]:
    xy = pts[:, :2]
    mean = xy.mean(axis=0)
    found = algebraic_circle(xy - mean)
    if found is None:
        raise ProbegenError(f"feature {check.feature}: the touches fit no circle")
    centre = found[0] + mean
    sign = 1.0 if check.inner else -1.0
    d = 2.0 * (found[1] + sign * check.ball_radius)
    radial = np.linalg.norm(xy - centre, axis=1)
    return {"X": float(centre[0]), "Y": float(centre[1]), "D": d,
            "F": float(radial.max() - radial.min()),
            "E": -sign * (d - check.diameter) / 2.0}


def _planar(check: Check, pts: np.ndarray) -> dict[str, float]:
    axis = int(np.argmax(np.abs(check.normal)))
    s = 1.0 if check.normal[axis] > 0 else -1.0
    p = float(pts[:, axis].mean()) - s * check.ball_radius
    # E along the whole normal (the program's s·(P − nominal) for a face square to an
    # axis, the only kind with run-time actions; ingest evaluates every face with it)
    e = float(np.mean((pts - np.asarray(check.nominal)) @ np.asarray(check.normal)))
    out = {"P": p, "E": e - check.ball_radius}
    if check.fit == "line":
        direction = fit_line_2d(pts[:, :2]).direction
        phi = math.degrees(math.atan2(direction[1], direction[0])) % 180.0
        a = phi - check.direction
        out["A"] = a - 180.0 * round(a / 180.0)
    return out


def _deviation(check: Check, v: dict[str, float], key: str) -> float:
    if key == "diameter":
        return v["D"] - check.diameter
    if key == "form":
        return v["F"]
    if key == "angle":
        return abs(v["A"])
    if check.fit != "circle":
        return v["E"]
    return 2.0 * math.hypot(v["X"] - check.nominal[0], v["Y"] - check.nominal[1])


def tool_correction(tool: ToolAction, excess: float) -> float:
    """The wear correction the program makes (0 in the dead band; beyond the maximum
    the program stops instead), mm."""
    c = -tool.feedback * excess
    return 0.0 if abs(c) < tool.dead_band else c


def decisions(spec: Spec, log: DprntLog, calibration: ProbeCalibration | None = None,
              part: Part | None = None) -> tuple[Decision, ...]:
    """Every decision value of ``spec``'s features with actions: offline and printed
    (offline with ``calibration`` as a program compiled with it computes them).
    ``part`` is the spec's model, loaded; loaded here when needed and not given."""
    from probegen.planning.actions import planar_check, revolved_check
    from probegen.planning.planar import plan_planar
    from probegen.planning.revolved_spec import plan_revolved, revolved_nodes
    from probegen.planning.setup import part_of

    balls: dict[str, dict[int, Vec3]] = {}
    for t in log.latest_touches():
        if t.kind == "PT":
            balls.setdefault(t.feature, {})[t.index] = t.xyz
    printed: dict[str, dict[str, float]] = {}
    for r in log.results:
        printed.setdefault(r.feature, {}).update(r.values)
    out: list[Decision] = []
    m = dataclasses.replace(spec.machine, calibration=calibration)
    for f in spec.features:
        if not isinstance(f, RevolvedSpec | PlanarSpec) or not f.actions.any:
            continue
        if part is None:
            part = part_of(spec)
        if isinstance(f, RevolvedSpec):
            p = plan_revolved(f, part, m, spec.clearance_z)
            nodes = revolved_check(revolved_nodes(p, m, spec.clearance_z), f, p.definition, m)
            check = next(n for n in nodes if isinstance(n, Check))
        else:
            found = planar_check(plan_planar(f, part, m), m)[1]
            assert found is not None
            check = found
        out += _pair(f, check, balls.get(f.id, {}), printed.get(f.id, {}))
    return tuple(out)


def _pair(f: RevolvedSpec | PlanarSpec, check: Check, balls: dict[int, Vec3],
          printed: dict[str, float]) -> list[Decision]:
    try:
        values: dict[str, float | None] = dict(evaluate_check(check, balls))
    except ProbegenError:
        values = {}
    keys: list[str] = [k for k in ("X", "Y", "D", "F", "P", "A", "NG")
                       if k in values or k in printed]
    tool = f.actions.tool
    if tool is not None:
        excess = values.get("E")
        values["C"] = None if excess is None else tool_correction(tool, excess)
        keys.append("C")
    return [Decision(f.id, k, values.get(k), printed.get(k), _limit(k, balls))
            for k in keys]


def _limit(key: str, balls: dict[int, Vec3]) -> float:
    """How far offline and machine may differ: the log's rounding, carried through (an
    angle: 4 roundings across the points' extent in XY, plus the printed 1e-6 deg)."""
    if key == "NG":
        return 0.0
    if key != "A":
        return LENGTH_AGREEMENT
    xy = np.array([p[:2] for p in balls.values()]) if balls else np.zeros((1, 2))
    span = float(np.max(np.linalg.norm(xy[:, None] - xy[None], axis=2)))
    return math.degrees(4.0 * LOG_ROUNDING / max(span, 1.0)) + 1e-6
