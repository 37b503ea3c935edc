"""What each section of the page shows, as plain values for the template.

The template (``templates/report/report.html.j2``) only loops and calls filters; the
plots are finished SVG text made here, the 3-D scenes finished JSON.
"""

from __future__ import annotations

from dataclasses import dataclass

from probegen.report import palette, plots
from probegen.report.deviation_plot import deviation_map_svg
from probegen.report.model import (
    Decision,
    Feature,
    Function,
    ProbeRadii,
    Results,
    sphere_test_radii,
)
from probegen.report.numbers import fixed, signed
from probegen.report.scene import STYLES, Scene, ball_scene, path_scene, scene_json

UM = 1000.0
"""Micrometres per millimetre: residuals and radius errors are plotted in µm."""


@dataclass(frozen=True, slots=True)
class LegendItem:
    """A swatch under a 3-D view: ``shape`` is ``line``, ``dash``, ``dot`` or ``ball``."""

    label: str
    colour: str
    shape: str


@dataclass(frozen=True, slots=True)
class View:
    """One 3-D view: the id and JSON of its scene, its caption and legend."""

    id: str
    title: str
    json: str
    legend: tuple[LegendItem, ...]


@dataclass(frozen=True, slots=True)
class FormPlots:
    """The form plots of one feature (empty ``plots`` with a ``message`` if none)."""

    feature: str
    plots: tuple[str, ...]
    message: str = ""


@dataclass(frozen=True, slots=True)
class RadiiPlots:
    """Effective radius per direction: a polar map, a bar chart and a summary line."""

    label: str
    summary: str
    plots: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class Calibration:
    """The calibration section: probe radii, identified functions, what is missing."""

    radii: tuple[RadiiPlots, ...]
    functions: tuple[str, ...]
    messages: tuple[str, ...]


DECISION_KEYS = {
    "X": ("centre X", "mm"), "Y": ("centre Y", "mm"), "D": ("diameter", "mm"),
    "F": ("roundness", "mm"), "P": ("face position", "mm"),
    "A": ("angle from nominal", "\u00b0"), "E": ("excess material", "mm"),
    "NG": ("limit exceeded", ""), "C": ("tool wear correction", "mm"),
}
"""What each decision key is (``probegen.ir.actions``) and its unit."""
STOPPED = "the program stopped: ERR "
"""How ``probegen ingest`` starts the note of an alarm (``ERR <code> <feature> ..``)."""


@dataclass(frozen=True, slots=True)
class DecisionRow:
    """One value of a decision as the table prints it (texts; ``agreement`` a status)."""

    key: str
    meaning: str
    offline: str
    machine: str
    difference: str
    limit: str
    agrees: bool | None
    exceeded: bool


@dataclass(frozen=True, slots=True)
class DecisionTable:
    """A feature's decision values, whether they all agree and the alarms it raised."""

    feature: str
    rows: tuple[DecisionRow, ...]
    agrees: bool | None
    alarms: tuple[str, ...]


def decisions(results: Results) -> list[DecisionTable]:
    """The in-process decisions by feature (in results order), offline next to machine."""
    features = list(dict.fromkeys(d.feature for d in results.decisions))
    out = []
    for feature in features:
        rows = tuple(_decision_row(d) for d in results.decisions if d.feature == feature)
        known = [r.agrees for r in rows if r.agrees is not None]
        alarms = tuple(n for n in results.notes
                       if n.startswith(STOPPED) and f" {feature} " in n[len(STOPPED):])
        out.append(DecisionTable(feature, rows, all(known) if known else None, alarms))
    return out


def _decision_row(d: Decision) -> DecisionRow:
    """Lengths 4 decimals (the log's), the angle 6 (as printed); corrections (``A E C``)
    signed; the flag ``NG`` as yes / no, compared exactly."""
    meaning, unit = DECISION_KEYS.get(d.key, (d.key, ""))
    decimals = 6 if d.key == "A" else 4
    flag = d.key == "NG"
    both = d.offline is not None and d.machine is not None

    def text(v: float | None) -> str:
        if v is None:
            return "\u2013"
        if flag:
            return "yes" if v else "no"
        return signed(v, decimals) if d.key in ("A", "E", "C") else fixed(v, decimals)

    return DecisionRow(
        key=d.key, meaning=f"{meaning} ({unit})" if unit else meaning,
        offline=text(d.offline), machine=text(d.machine),
        difference=signed((d.offline or 0.0) - (d.machine or 0.0), decimals)
        if both and not flag else "\u2013",
        limit="\u2013" if d.limit is None or flag else f"\u2264 {fixed(d.limit, decimals)}",
        agrees=d.agrees, exceeded=flag and bool(d.offline or d.machine))


def views(results: Results) -> list[View]:
    """The stylus-path view (if there is a path or points) and one error-ball view per
    sphere test."""
    out = []
    scene = path_scene(results)
    if scene.segments or scene.points:
        out.append(_view(scene))
    for k, f in enumerate(results.features):
        if f.kind == "sphere_test" and f.residuals:
            out.append(_view(ball_scene(f, k)))
    return out


def _view(scene: Scene) -> View:
    used = {style for _, _, style in scene.segments}
    legend = [LegendItem(name, str(STYLES[name]["colour"]),
                         "dash" if STYLES[name]["dash"] else "line")
              for name in STYLES if name in used]
    if scene.points:
        legend.append(LegendItem("measured point", palette.POINT, "dot"))
    if scene.balls:
        legend += [LegendItem("\u03b5 > 0 (material outside)", palette.LIGHT, "ball"),
                   LegendItem("\u03b5 < 0 (material inside)", palette.DARK, "ball")]
    return View(scene.id, scene.title, scene_json(scene), tuple(legend))


def form_plots(feature: Feature) -> FormPlots:
    """Residual per point (bars) and residual against polar angle (scatter)."""
    if not feature.residuals:
        return FormPlots(feature.id, (), "no residuals in the results")
    eps = [e * UM for e in feature.residuals]
    if feature.kind == "freeform":
        return _deviation_plots(feature, eps)
    bars = plots.bar_chart(eps, title=f"{feature.id}: residual per point (+ material outside)",
                           y_label="\u03b5 (\u00b5m)", decimals=3)
    if len(feature.directions) != len(eps):
        return FormPlots(feature.id, (bars,))
    theta = plots.polar_angles(feature.directions)
    phi = plots.azimuths(feature.directions)
    tips = [f"point {i}: \u03b8 {plots.fmt_angle(t)}, \u03c6 {plots.fmt_angle(p)}, "
            f"\u03b5 {signed(e, 3)} \u00b5m"
            for i, (t, p, e) in enumerate(zip(theta, phi, eps, strict=True), start=1)]
    scatter = plots.scatter_plot(
        theta, eps, title=f"{feature.id}: residual against polar angle (+ material outside)",
        x_label="polar angle \u03b8 from +Z (\u00b0)", y_label="\u03b5 (\u00b5m)",
        x_ticks=plots.angle_ticks(theta), labels=tips)
    return FormPlots(feature.id, (bars, scatter))


def _deviation_plots(feature: Feature, eps: list[float]) -> FormPlots:
    """A free-form feature (M3): the deviation map over the face and the deviation per
    guide point (along the nominal normal, + = material added)."""
    bars = plots.bar_chart(eps, title=f"{feature.id}: deviation along the nominal normal "
                           "per point", y_label="e (\u00b5m)", decimals=3)
    if len(feature.points) != len(eps):
        return FormPlots(feature.id, (bars,))
    dmap = deviation_map_svg(feature.points, eps, title=f"{feature.id}: deviation map",
                             normals=feature.directions or ((0.0, 0.0, 1.0),), decimals=3,
                             labels=[f"point {k}" for k in range(1, len(eps) + 1)])
    return FormPlots(feature.id, (dmap, bars))


def calibration(results: Results) -> Calibration:
    """The calibration section's content, and a sentence for each thing absent."""
    sources = [results.probe] if results.probe else \
        [r for r in map(sphere_test_radii, results.features) if r is not None]
    messages = []
    if not sources:
        messages.append("No probe calibration (effective radius per direction) in these "
                        "results.")
    if not results.functions:
        messages.append("No rotary-axis (method M4) or geometric-error (method M5) "
                        "calibration in these results.")
    return Calibration(tuple(_radii_plots(r) for r in sources),
                       tuple(_function_plot(f) for f in results.functions), tuple(messages))


def _radii_plots(radii: ProbeRadii) -> RadiiPlots:
    dev = [(r - radii.ball_radius) * UM for r in radii.radii]
    mean = sum(radii.radii) / len(radii.radii) if radii.radii else radii.ball_radius
    summary = (f"nominal ball radius {fixed(radii.ball_radius, 4)} mm; effective radius "
               f"mean {fixed(mean, 4)} mm, min {fixed(min(radii.radii, default=mean), 4)} "
               f"mm, max {fixed(max(radii.radii, default=mean), 4)} mm "
               f"({len(radii.radii)} directions)")
    if not radii.radii:
        return RadiiPlots(radii.label, summary, ())
    title = "effective radius \u2212 nominal (\u00b5m)"
    return RadiiPlots(radii.label, summary, (
        plots.polar_map(radii.directions, dev, title=title),
        plots.bar_chart(dev, title=title, y_label="r_eff \u2212 r (\u00b5m)",
                        x_label="direction", decimals=3),
    ))


def _function_plot(function: Function) -> str:
    unit = f" ({function.unit})" if function.unit else ""
    return plots.line_plot(function.positions, function.values, title=function.name,
                           x_label="position", y_label=f"value{unit}")
