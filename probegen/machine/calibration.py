"""Ball centre → contact point, along the nominal surface normal.

A touch-trigger probe reports the ball centre ``O`` at the trigger; the contact point is
``P = O − r·n`` with ``n`` the outward unit normal of the surface and ``r`` the ball's
effective radius.  Compensating along the move axis instead of the normal is the classic
error of open probing macros (tens of micrometres on a slope); here it is always the
normal.

The effective radius is either one number (the nominal ball radius, or the mean effective
radius of a probe calibration) or a ``ProbeCalibration``: effective radii measured in a set
of directions by the sphere test (method M1), and between them a smooth least-squares map
(harmonic polynomials up to degree 3: the axial/lateral and 3-lobe parts of a kinematic
probe's pre-travel) plus the inverse-distance weighted misfit (exact at the measured
directions).  Inverse-distance weighting alone is off by a third of the lobe amplitude
half-way between two measured directions 30° apart; the smooth map follows the lobes.

The sphere test cannot tell a pre-travel term linear in the direction (``v·n``) from a
shift of the sphere's centre: its map holds no such term.  Sizes (diameters, widths) are
blind to it; a position found from one side (a plane touched from above) carries it.  A
probe whose axial and lateral pre-travel differ has such a term on a test of the upper
hemisphere (``docs/results.md``, calibration).

Every caller that turns ball centres into contact points or sizes goes through one
function, :func:`calibrated_centres`: it moves each ball centre by ``(r(n) − r_ref)``
along its normal, so that offsetting the moved centre by the single reference radius
``r_ref`` gives the calibrated contact point.  Fits on ball centres (the revolved kinds,
the on-control fits of the in-process actions) then keep their one-radius offset
arithmetic; :func:`compensate` is the same function with ``r_ref = 0``.

A calibration is identified by its :attr:`ProbeCalibration.fingerprint` (a short hash of
its file text), printed in the ``PGCAL`` line of a program compiled with it and in every
output of ``ingest``.

Calibration file (TOML, written by ``probegen ingest --write-calibration``)::

    [calibration]
    ball_radius = 3.0            # nominal, mm
    effective_radius = 2.9981    # mean effective radius, mm
    source = "run.log"
    date = "2026-11-26"          # when the sphere test ran (--calibration-date); optional
    directions = [[0.0, 0.0, 1.0], ...]    # unit vectors, probe frame
    radii = [2.9979, ...]                  # effective radius in each direction, mm
    u_radius = 0.0002            # standard uncertainty of the effective radius, mm
                                 # (optional, 0 when absent: files before it)
    stylus = "D2"                # optional: the rack's stylus it was measured with
    orientation = "A0B0"         # optional: the head or tilt orientation (default: vertical)

A probe of several styli, or a CMM head used in several orientations, has one entry per
stylus and orientation: ``[[calibration]]`` tables (an array), each with the keys above and
``stylus`` required, no two of the same stylus and orientation.  The radius map of every
entry is in the probe's own frame (``directions``: from the ball's centre, the stylus
along -Z), so a stylus calibrated at A0B0 is, to first order, calibrated at any
orientation: :meth:`ProbeCalibration.entry_for` takes the entry of the stylus and
orientation asked for, else the stylus's vertical entry (``A0B0``, ``TILT0`` or no
orientation), else the one entry of a file that names no stylus (every file written
before issue 17), and refuses otherwise (``docs/results.md``, "Probe calibration").
"""

from __future__ import annotations

import datetime
import hashlib
import math
import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from probegen.errors import SpecError
from probegen.files import Table, load_toml

VERTICAL_NAMES = ("", "A0B0", "TILT0", "VERTICAL")
"""Names of the vertical probe's orientation (no name, a CMM head's, a five-axis
machine's, probegen's own): all the same orientation."""
ORIENTATION = re.compile(r"[A-Z0-9_]{1,16}\Z")
"""An orientation name (``ir.Orient.name``)."""
STYLUS_LABEL = re.compile(r"[A-Z0-9_]{1,8}\Z")
"""A stylus label (``machine.rack.LABEL``)."""
IDW_POWER = 4.0
"""Power of the inverse-distance weights: high enough that a direction's own radius
dominates near it, low enough to blend smoothly between the measured directions."""
UNCALIBRATED = "uncalibrated, nominal ball radius"
"""What every output says when no calibration was used."""


@dataclass(frozen=True, slots=True)
class ProbeCalibration:
    """Effective stylus radii by direction (from the sphere test).

    Attributes:
        ball_radius: nominal ball radius, mm.
        effective_radius: mean effective radius, mm.
        directions: unit vectors where the radius was measured.
        radii: the effective radius in each direction, mm.
        source: where the calibration came from.
        u_radius: standard uncertainty of the effective radius, mm (from the sphere
            test's fit; 0 when the file does not state it).
        date: when the sphere test ran (ISO 8601, from ``--calibration-date``), or "".
        stylus: the label of the stylus it was measured with, or "" (not stated).
        orientation: the orientation it was measured in, or "" (the vertical probe;
            ``A0B0`` and ``TILT0`` are the same).
        others: the other entries of the same file (a file of several styli or
            orientations); the fields above are the entry in use
            (:meth:`entry_for` picks another).
    """

    ball_radius: float
    effective_radius: float
    directions: tuple[tuple[float, float, float], ...]
    radii: tuple[float, ...]
    source: str = ""
    u_radius: float = 0.0
    date: str = ""
    stylus: str = ""
    orientation: str = ""
    others: tuple[ProbeCalibration, ...] = ()

    @property
    def fingerprint(self) -> str:
        """A short identity: ``C`` and 8 hex digits of the SHA-256 of the file text
        (a letter first, so it prints and reads as one DPRNT word); the same for every
        entry of one file."""
        digest = hashlib.sha256(calibration_toml(self).encode("utf-8")).hexdigest()
        return "C" + digest[:8].upper()

    def describe(self) -> str:
        """One line for every output: source, date and fingerprint (and the stylus and
        orientation of an entry that names them)."""
        pair = f"stylus {self.stylus} {self.orientation or 'vertical'}, " \
            if self.stylus else ""
        return (f"calibrated: {pair}{self.source or 'unknown source'}, "
                f"{self.date or 'undated'}, fingerprint {self.fingerprint}, "
                f"effective radius {self.effective_radius:.4f} mm")

    @property
    def entries(self) -> tuple[ProbeCalibration, ...]:
        """Every entry of the file, each without ``others``, sorted by stylus and
        orientation (one: a file of one entry)."""
        every = (replace(self, others=()), *self.others)
        return tuple(sorted(every, key=lambda e: (e.stylus, e.orientation)))

    def entry_for(self, stylus: str, orientation: str = "", where: str = ""
                  ) -> ProbeCalibration:
        """The entry of ``stylus`` (a rack label) in ``orientation`` (a head or tilt
        orientation name; "", ``A0B0``, ``TILT0``: the vertical probe), with the file's
        other entries kept in ``others`` (the fingerprint is the file's).

        Falls back to the stylus's vertical entry (the map is in the probe frame), then
        to the one entry of a file that names no stylus.

        Raises:
            SpecError: no entry fits; names ``where``, the pair and the entries held.
        """
        every = self.entries
        vertical = _vertical(orientation)
        for fits in (lambda e: e.stylus == stylus and _same(e.orientation, orientation),
                     lambda e: e.stylus == stylus and _vertical(e.orientation),
                     lambda e: not e.stylus and len(every) == 1):
            found = [e for e in every if fits(e)]
            if found:
                chosen = found[0]
                return replace(chosen, others=tuple(e for e in every if e is not chosen))
        held = ", ".join(f"{e.stylus or 'unnamed'} {e.orientation or 'vertical'}"
                         for e in every)
        asked = f"stylus {stylus}" + ("" if vertical else f" in orientation {orientation}")
        raise SpecError(f"{where or self.source}: expected a probe calibration of {asked} "
                        f"(or of its vertical orientation), found entries for {held} only; "
                        "run the sphere test with that stylus and add its entry "
                        "([[calibration]] with stylus and orientation), or measure without "
                        "a calibration (nominal ball radius)")

    def radius(self, normals: ArrayLike) -> NDArray[np.float64]:
        """Effective radius for each approach normal ``normals : (n, 3)``; returns (n,).

        A smooth map (least-squares polynomial in the direction's components, see
        :func:`_basis`) plus the inverse-distance weighted misfit at the measured
        directions: exact at each measured direction, smooth between them."""
        n = np.asanyarray(normals, dtype=np.float64).reshape(-1, 3)
        if not self.directions:
            return np.full(len(n), self.effective_radius)
        d = np.asarray(self.directions)
        r = np.asarray(self.radii)
        k, coef = _smooth_map(d, r)
        misfit = r - _basis(d)[:, :k] @ coef
        dist = np.linalg.norm(n[:, None, :] - d[None, :, :], axis=2)
        exact = dist < 1e-12
        w = 1.0 / np.maximum(dist, 1e-12) ** IDW_POWER
        w = np.where(exact.any(axis=1, keepdims=True), exact.astype(float), w)
        return np.asarray(_basis(n)[:, :k] @ coef + (w @ misfit) / w.sum(axis=1))


def _basis(n: NDArray[np.float64]) -> NDArray[np.float64]:
    """The smooth map's terms at unit directions (n, 3): the harmonic polynomials of
    degree 0 (1 term), 1 (3), 2 (5) and 3 (7), in that order.  A kinematic probe's
    pre-travel is the sum of an axial/lateral part (degree 0 and 2) and its 3-lobe part
    (degree 3, ``x³ − 3xy²``), so 16 terms hold it whole."""
    x, y, z = n[:, 0], n[:, 1], n[:, 2]
    return np.stack([np.ones(len(n)), x, y, z,
                     x * x - y * y, x * y, x * z, y * z, 3.0 * z * z - 1.0,
                     x**3 - 3.0 * x * y * y, 3.0 * x * x * y - y**3, z * (x * x - y * y),
                     x * y * z, x * (5.0 * z * z - 1.0), y * (5.0 * z * z - 1.0),
                     z * (5.0 * z * z - 3.0)], axis=1)


MAP_TERMS = (16, 9, 4, 1)
"""Terms of the smooth map tried in turn (degree 3, 2, 1, 0): the first with at least
as many directions as terms and a condition number below :data:`MAP_CONDITION`."""
MAP_CONDITION = 1e4
"""Largest condition number of the smooth map's design matrix (the directions of a
sphere test on one hemisphere keep the degree-3 map near 150)."""


def _smooth_map(d: NDArray[np.float64], r: NDArray[np.float64]
                ) -> tuple[int, NDArray[np.float64]]:
    """The number of terms and the least-squares coefficients of the smooth map."""
    basis = _basis(d)
    for k in MAP_TERMS:
        if len(d) >= k and np.linalg.cond(basis[:, :k]) < MAP_CONDITION:
            coef = np.linalg.lstsq(basis[:, :k], r, rcond=None)[0]
            return k, np.asarray(coef)
    return 1, np.array([float(np.mean(r))])


def calibrated_centres(centres: ArrayLike, normals: ArrayLike, calibration: ProbeCalibration,
                       reference: float, *, probe_normals: ArrayLike | None = None
                       ) -> NDArray[np.float64]:
    """Ball centres moved so that one radius ``reference`` compensates them as the
    calibration would: ``O' = O − (r(n) − reference)·n``.

    The one place a calibration meets ball centres (every feature kind, the actions,
    free-form, the rotary and post paths call it, directly or through
    :func:`compensate`).

    Args:
        centres: (n, 3) ball centres, mm.
        normals: (n, 3) outward surface normals (from the surface towards the ball),
            need not be unit.
        calibration: the probe calibration.
        reference: the radius the caller offsets the moved centres by, mm.
        probe_normals: the same normals in the probe frame, where the calibration's
            map is (a head tilted by a rotary axis); default ``normals``.

    Returns:
        (n, 3) moved ball centres, mm.
    """
    o = np.asanyarray(centres, dtype=np.float64).reshape(-1, 3)
    n = np.asanyarray(normals, dtype=np.float64).reshape(-1, 3)
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    look = n if probe_normals is None else \
        np.asanyarray(probe_normals, dtype=np.float64).reshape(-1, 3)
    return np.asarray(o - (calibration.radius(look) - reference)[:, None] * n)


STYLUS_MATCH = 1e-6
"""Largest difference (mm) between a calibration's nominal ball radius and the stylus
it is used with."""


def for_stylus(calibration: ProbeCalibration | None, ball_radius: float,
               where: str) -> ProbeCalibration | None:
    """``calibration`` when it was measured with a ball of ``ball_radius`` (mm);
    a ``SpecError`` naming ``where`` otherwise (a calibration of another stylus)."""
    if calibration is not None and abs(calibration.ball_radius - ball_radius) > STYLUS_MATCH:
        raise SpecError(f"{where}: expected a probe calibration of a {2 * ball_radius:g} mm "
                        f"ball (the stylus used), found one of a "
                        f"{2 * calibration.ball_radius:g} mm ball "
                        f"({calibration.source or 'unknown source'})")
    return calibration


def stylus_calibration(calibration: ProbeCalibration | None, stylus: str, ball_radius: float,
                       orientation: str, where: str) -> ProbeCalibration | None:
    """The entry of ``calibration`` for ``stylus`` (a label, ball of ``ball_radius`` mm)
    in ``orientation`` (:meth:`ProbeCalibration.entry_for`, checked by :func:`for_stylus`),
    or None without a calibration (the nominal radius).

    Raises:
        SpecError: no entry fits, or the entry is of another ball.
    """
    if calibration is None:
        return None
    return for_stylus(calibration.entry_for(stylus, orientation, where), ball_radius, where)


def _vertical(name: str) -> bool:
    return name in VERTICAL_NAMES


def _same(a: str, b: str) -> bool:
    """Whether orientation names ``a`` and ``b`` are the same orientation."""
    return a == b or _vertical(a) and _vertical(b)


def calibration_state(calibration: ProbeCalibration | None) -> dict[str, object]:
    """The calibration as every output records it (``results.json`` ``calibration``)."""
    if calibration is None:
        return {"state": UNCALIBRATED}
    return {"state": calibration.describe(), "source": calibration.source,
            "date": calibration.date, "fingerprint": calibration.fingerprint,
            "effective_radius": float(f"{calibration.effective_radius:.7f}")}


def check_date(text: str, where: str) -> str:
    """An ISO 8601 date or date-time, as given; a ``ProbegenError`` otherwise."""
    try:
        datetime.datetime.fromisoformat(text)
    except ValueError:
        raise SpecError(f"{where}: expected an ISO 8601 date (2026-11-26 or "
                        f"2026-11-26T10:30), found {text!r}") from None
    return text


def compensate(centres: ArrayLike, normals: ArrayLike,
               radius: float | ProbeCalibration) -> NDArray[np.float64]:
    """Contact points ``P = O − r(n)·n``.

    Args:
        centres: (n, 3) ball centres reported at the trigger.
        normals: (n, 3) outward unit surface normals (nominal, or estimated).
        radius: effective ball radius, or a calibration giving it by direction.

    Returns:
        (n, 3) float contact points.
    """
    if isinstance(radius, ProbeCalibration):
        return calibrated_centres(centres, normals, radius, 0.0)
    o = np.asanyarray(centres, dtype=np.float64).reshape(-1, 3)
    n = np.asanyarray(normals, dtype=np.float64).reshape(-1, 3)
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    return np.asarray(o - radius * n)


def load_calibration(path: str | Path) -> ProbeCalibration:
    """Read a calibration file (see the module docstring); errors name file and key.

    A file of several entries (``[[calibration]]``) gives its first entry in file order
    with the others in ``others``."""
    file = str(path)
    root = Table(load_toml(path), file, "")
    several = isinstance(root.get_any("calibration"), list)
    tables = root.tables("calibration") if several else \
        [root.table("calibration", required=True)]
    if not tables:
        raise root.fail("calibration", "at least one [[calibration]] entry")
    entries = [_entry(t, several) for t in tables]
    seen: dict[tuple[str, bool | str], str] = {}
    for t, e in zip(tables, entries, strict=True):
        key = (e.stylus, True if _vertical(e.orientation) else e.orientation)
        if key in seen:
            raise SpecError(f"{t.where('orientation')}: expected one entry per stylus and "
                            f"orientation, found stylus {e.stylus} "
                            f"{e.orientation or 'vertical'} again (first at "
                            f"{seen[key]})")
        seen[key] = t.path
    root.done()
    return replace(entries[0], others=tuple(entries[1:]))


def _entry(t: Table, several: bool) -> ProbeCalibration:
    """One entry; ``several``: of a file of several, where ``stylus`` is required."""
    directions = t.get_any("directions", [])
    radii = t.get_any("radii", [])
    cal = ProbeCalibration(
        ball_radius=t.get_float("ball_radius", required=True, positive=True) or 0.0,
        effective_radius=t.get_float("effective_radius", required=True, positive=True) or 0.0,
        directions=_directions(t, directions),
        radii=_radii(t, radii),
        source=t.get_str("source", "") or "",
        u_radius=t.get_float("u_radius", 0.0, minimum=0.0, maximum=1.0) or 0.0,
        date=_date(t),
        stylus=_name(t, "stylus", STYLUS_LABEL, several, "1-8 of A-Z 0-9 _ (a stylus label "
                                                       "of the machine's rack)"),
        orientation=_name(t, "orientation", ORIENTATION, False, "1-16 of A-Z 0-9 _ (an "
                                                               "orientation name: A90B90)"),
    )
    if len(cal.directions) != len(cal.radii):
        raise SpecError(f"{t.where('radii')}: expected one radius per direction "
                        f"({len(cal.directions)}), found {len(cal.radii)}")
    t.done()
    return cal


def _name(t: Table, key: str, pattern: re.Pattern[str], required: bool, what: str) -> str:
    text = t.get_str(key, "", required=required) or ""
    if text and not pattern.match(text):
        raise t.fail(key, what)
    return text


def _date(t: Table) -> str:
    text = t.get_str("date", "") or ""
    return check_date(text, t.where("date")) if text else ""


def _directions(t: Table, value: object) -> tuple[tuple[float, float, float], ...]:
    out = []
    if not isinstance(value, list):
        raise t.fail("directions", "an array of [x, y, z] unit vectors")
    for v in value:
        ok = isinstance(v, list) and len(v) == 3 and all(
            isinstance(c, int | float) and not isinstance(c, bool) for c in v)
        if not ok or abs(math.hypot(*v) - 1.0) > 1e-6:
            raise t.fail("directions", "an array of [x, y, z] unit vectors")
        out.append((float(v[0]), float(v[1]), float(v[2])))
    return tuple(out)


def _radii(t: Table, value: object) -> tuple[float, ...]:
    ok = isinstance(value, list) and all(
        isinstance(c, int | float) and not isinstance(c, bool) and c > 0 for c in value)
    if not ok:
        raise t.fail("radii", "an array of positive numbers")
    assert isinstance(value, list)
    return tuple(float(c) for c in value)


def combined(new: tuple[ProbeCalibration, ...], old: ProbeCalibration | None = None,
             where: str = "") -> tuple[ProbeCalibration, tuple[ProbeCalibration, ...]]:
    """The calibration of the entries ``new`` (one per sphere test of a run) written over
    the file ``old`` (None: no file yet), and the entries of ``old`` it keeps.

    An entry of a stylus (and orientation) replaces the old one of the same pair; the
    old file's other entries are kept when every one of them names its stylus (a file
    of the rack, written by this function or by hand).  A file of one unnamed entry (a
    probe without a rack), or one new unnamed entry, is replaced whole, as it always was.

    Raises:
        SpecError: ``new`` is empty, holds two entries of one stylus and orientation, or
            several of which one names no stylus; names ``where``.
    """
    if not new:
        raise SpecError(f"{where}: expected at least one sphere test's calibration, found none")
    keys = [(e.stylus, True if _vertical(e.orientation) else e.orientation) for e in new]
    if len(new) > 1 and not all(e.stylus for e in new):
        raise SpecError(f"{where}: expected every sphere test of a run that calibrates "
                        "several styli to name its stylus (stylus = \"D2\"), found one "
                        "without")
    if len(set(keys)) < len(keys):
        twice = sorted({k[0] or "unnamed" for k in keys if keys.count(k) > 1})
        raise SpecError(f"{where}: expected one sphere test per stylus and orientation, "
                        f"found several of stylus {', '.join(twice)}")
    kept: tuple[ProbeCalibration, ...] = ()
    if old is not None and all(e.stylus for e in new) and all(e.stylus for e in old.entries):
        kept = tuple(e for e in old.entries
                     if (e.stylus, True if _vertical(e.orientation) else e.orientation)
                     not in keys)
    every = sorted((*new, *kept), key=lambda e: (e.stylus, e.orientation))
    first = replace(every[0], others=tuple(replace(e, others=()) for e in every[1:]))
    return first, kept


def calibration_toml(cal: ProbeCalibration) -> str:
    """The calibration as TOML text (fixed decimals, repeatable): ``[calibration]`` for a
    file of one entry, ``[[calibration]]`` entries sorted by stylus and orientation for
    several."""
    entries = cal.entries
    head = "[[calibration]]" if len(entries) > 1 else "[calibration]"
    return ("# Probe calibration written by probegen (sphere test, method M1).\n"
            + "\n".join(_entry_toml(e, head) for e in entries))


def _entry_toml(cal: ProbeCalibration, head: str) -> str:
    dirs = ",\n    ".join(f"[{x:.9f}, {y:.9f}, {z:.9f}]" for x, y, z in cal.directions)
    radii = ", ".join(f"{r:.7f}" for r in cal.radii)
    return (
        f"{head}\n"
        + (f"stylus = {_quote(cal.stylus)}\n" if cal.stylus else "")
        + (f"orientation = {_quote(cal.orientation)}\n" if cal.orientation else "")
        + f"ball_radius = {cal.ball_radius:.7f}\n"
        f"effective_radius = {cal.effective_radius:.7f}\n"
        f"source = {_quote(cal.source)}\n"
        + (f"date = {_quote(cal.date)}\n" if cal.date else "")
        + f"directions = [\n    {dirs},\n]\n"
        f"radii = [{radii}]\n"
        f"u_radius = {cal.u_radius:.7f}\n"
    )


def _quote(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'
