"""Evaluate a posted program's DPRNT log: the DMIS program's features and tolerances.

The DMIS program (as posted, from the feature map) runs again through the DMIS
interpreter, this time against a *replaying* machine: its n-th probing move returns the
ball centre the log holds for the map's n-th touch (matched by the printed id and
index, not by log order).  So every measured feature is fitted, compensated, constructed,
aligned, toleranced and written to a DMIS output file by the same code as on the
virtual CMM (:mod:`probegen.sim.cmm`): features of the DMIS kinds, with the CMM's
fits (feature compensation, the cylinder fit started from the nominal axis).

With a probe calibration (``post-ingest --calibration``) each replayed ball centre is
first moved by ``r(n) − r`` along its normal (``compensate.calibrated_centres``, ``n`` the
reverse of the probing direction, ``r`` the posted ball radius the DMIS program
compensates with), so the CMM code's one-radius compensation gives the calibrated
contact point.

Checks: the log is first checked against the map (:mod:`probegen.results.logcheck`: the run
used, the program number and identity of the posted program, unknown and duplicate point
ids); every touch of the map must be in the log (the last one read after a restart),
in the log's units, and lie on its probing line (:data:`ON_LINE`) within its reach; a
log that fails is refused with the touch, its log line and its DMIS line named.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from probegen.constants import MM_PER_INCH
from probegen.dmis.reader import parse_dmis
from probegen.errors import IncompleteRunError, ResultsParseError
from probegen.ir.identity import PlannedTouch, map_identity
from probegen.machine.calibration import ProbeCalibration, calibrated_centres, for_stylus
from probegen.post.featuremap import FeatureMap, read_feature_map
from probegen.post.posted import PostTouch
from probegen.results.dprnt import DprntLog, read_dprnt
from probegen.results.logcheck import check_log
from probegen.sim.cmm.features import DmisFeature, arr, vec3
from probegen.sim.cmm.interpreter import DmisRunResult, run_dmis

Vec3 = tuple[float, float, float]

ON_LINE = 0.01
"""Largest distance (mm) of a logged ball centre from its probing line: the control
reports the commanded position, on the line up to the printed rounding (and the
machine's positioning errors, which stay far below this)."""


class _Replay:
    """A ``Cmm`` whose probing moves return the logged ball centres in map order."""

    def __init__(self, fmap: FeatureMap, points: dict[tuple[str, int], Vec3],
                 source: str, cut: dict[tuple[str, int], str] | None = None,
                 lines: dict[tuple[str, int], int] | None = None,
                 calibration: ProbeCalibration | None = None) -> None:
        self.fmap, self.points, self.source = fmap, points, source
        self.cut = cut or {}
        self.lines = lines or {}
        self.calibration = calibration
        self.used = 0

    @property
    def ball_radius(self) -> float:
        """The posted stylus ball radius, mm."""
        return self.fmap.ball_diameter / 2.0

    def move(self, start: Vec3, end: Vec3) -> None:
        """Positioning: nothing to replay."""

    def probe(self, start: Vec3, direction: Vec3, distance: float) -> Vec3:
        """The logged ball centre of the next touch of the map."""
        if self.used >= len(self.fmap.touches):
            raise ResultsParseError(f"{self.source}: the DMIS program probes more points "
                                    f"than the feature map lists ({len(self.fmap.touches)})")
        touch = self.fmap.touches[self.used]
        self.used += 1
        found = self._checked(touch)
        if self.calibration is None:
            return found
        moved = calibrated_centres([found], [-arr(touch.direction)], self.calibration,
                                   self.ball_radius)
        return vec3(moved[0])

    def _checked(self, t: PostTouch) -> Vec3:
        key = (t.id, t.index)
        if key not in self.points:
            where = (f"{self.source}: no PT {t.id} {t.index} in the log (feature "
                     f"{t.feature}, DMIS line {t.line})")
            why = self.cut.get(key) or self.cut.get(("", 0))
            if why:
                raise IncompleteRunError(f"{where}: NOT EVALUATED, {why}")
            raise ResultsParseError(f"{where}: did the program run to its end?")
        p = arr(self.points[key])
        rel = p - arr(t.start)
        along = float(rel @ arr(t.direction))
        off = float(np.linalg.norm(rel - along * arr(t.direction)))
        if off > ON_LINE or not -ON_LINE <= along <= t.reach + ON_LINE:
            where = f"{self.source}:{self.lines[key]}" if key in self.lines else self.source
            raise ResultsParseError(
                f"{where}: PT {t.id} {t.index} (DMIS line {t.line}) at "
                f"{', '.join(f'{v:.4f}' for v in p)} is {off:.4f} mm off its probing line "
                f"and {along:.4f} mm along it (reach {t.reach:g}): was the log written by "
                "this program?")
        return vec3(p)


def evaluate_log(log: DprntLog, fmap: FeatureMap,
                 calibration: ProbeCalibration | None = None) -> DmisRunResult:
    """Run the map's DMIS program on the logged touches (see the module docstring),
    with the probe calibration's radii when one is given.

    Returns:
        The DMIS run: output file text, actual and nominal features (work coordinates,
        mm), evaluated tolerances, the statements skipped.

    Raises:
        ResultsParseError: a touch missing or off its probing line, or extra probing
            (``IncompleteRunError`` for a touch missing from a run cut short or without
            contact).
        DmisProgramError: the map's DMIS program is wrong (a changed map).
    """
    scale = MM_PER_INCH if fmap.units == "inch" else 1.0
    latest = [t for t in log.latest_touches() if t.kind == "PT"]
    points = {(t.feature, t.index): (t.xyz[0] * scale, t.xyz[1] * scale, t.xyz[2] * scale)
              for t in latest}
    for_stylus(calibration, fmap.ball_diameter / 2.0, "--calibration")
    replay = _Replay(fmap, points, log.source, _cut(log),
                     {(t.feature, t.index): t.line for t in latest}, calibration)
    result = run_dmis(fmap.text, replay, source=fmap.source, skip_unsupported=True,
                      answers=dict(fmap.answers))
    if replay.used != len(fmap.touches):
        raise ResultsParseError(f"{log.source}: the DMIS program probed {replay.used} points, "
                                f"the feature map lists {len(fmap.touches)}")
    return result


def _cut(log: DprntLog) -> dict[tuple[str, int], str]:
    """Why touches may be missing: ``ERR NOTOUCH`` points not measured again, and
    (key ``("", 0)``) a log without ``PGEND``."""
    out = {key: f"no contact (ERR NOTOUCH, line {line})"
           for key, line in log.no_contact().items()}
    if not log.complete:
        out[("", 0)] = "the log has no PGEND line: the program did not finish"
    return out


def run_status(log: DprntLog, result: DmisRunResult) -> str:
    """The run's status (:func:`probegen.evaluate.characteristics.run_status`): its tolerances'
    verdicts; NOT EVALUATED when the log did not finish or a touch had no contact."""
    from probegen.evaluate.characteristics import run_status as status

    cut = _cut(log)
    return status((t.in_tolerance for t in result.tolerances.values()),
                  not_evaluated=bool(cut), complete=log.complete)


def ingest_file(log: str | Path, features: str | Path,
                calibration: ProbeCalibration | None = None, *, run: int | None = None,
                ignore_identity: bool = False
                ) -> tuple[DprntLog, DmisRunResult, tuple[str, ...]]:
    """Evaluate a captured DPRNT ``log`` with the feature map ``features`` (and the probe
    calibration's radii when one is given); returns the
    run of the log used, the DMIS run and the notes of the log's checks (``run``,
    ``ignore_identity``: see :func:`probegen.results.logcheck.check_log`).

    Raises:
        ProbegenError: the log belongs to another program, or names points the map
            does not have.
        ResultsParseError: the log or the map cannot be used (see ``evaluate_log``);
            ``IncompleteRunError`` when a touch is missing from a run cut short.
    """
    fmap = read_feature_map(features)
    parse_dmis(fmap.text, source=fmap.source)  # a damaged map fails here, located
    planned = [PlannedTouch("PT", t.id, t.index, t.start, t.start, 0.0) for t in fmap.touches]
    checked = check_log(read_dprnt(log), program=fmap.number,
                        identity=map_identity(fmap.text, fmap.touches), touches=planned,
                        run=run, ignore_identity=ignore_identity, plausibility=False)
    return checked.log, evaluate_log(checked.log, fmap, calibration), checked.notes


def results_table(result: DmisRunResult) -> str:
    """One line per actual feature (deviation from nominal, form) and per tolerance."""
    lines = [f"{'feature':<12} {'kind':<7} {'d location':>11} {'d size':>9} {'form':>9}"]
    for name, actual in result.features.items():
        lines.append(_feature_line(name, actual, result.nominals[name]))
    for name, t in result.tolerances.items():
        verdict = "INTOL" if t.in_tolerance else "OUTOL"
        lines.append(f"T({name}) {t.tolerance.kind} on {t.feature}: {t.deviation:.4f} "
                     f"[{t.tolerance.lower:g}, {t.tolerance.upper:g}] {verdict}")
    for s in result.skipped:
        lines.append(f"skipped line {s.line}: {s.text} ({s.reason})")
    return "\n".join(lines) + "\n"


def _feature_line(name: str, actual: DmisFeature, nominal: DmisFeature) -> str:
    loc = sum((a - n) ** 2 for a, n in zip(actual.location, nominal.location,
                                             strict=True)) ** 0.5
    size = "" if actual.size is None or nominal.size is None else \
        f"{actual.size - nominal.size:+.4f}"
    form = "" if actual.form is None else f"{actual.form:.4f}"
    return f"{name:<12} {actual.kind:<7} {loc:11.4f} {size:>9} {form:>9}"
