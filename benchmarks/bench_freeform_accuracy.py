"""Benchmark: accuracy of the four free-form compensation methods (M3), and solver speed.

Run:  .venv/bin/python benchmarks/bench_freeform_accuracy.py [--grid 15] [--sigma 0.5]

For each slope (0-60°) a nominal bicubic B-spline height field over 40 × 40 mm: a plane
tilted about Y by the slope, plus a gentle bowl (radii of curvature 500 and 300 mm).  The
true part is the nominal one plus a planted form error (poles moved by
``A·sin(2πx/λ)·cos(2πy/λ')``).  A ``grid × grid`` set of guide points; every touch is
simulated exactly: the ball moves along its probing line until it touches the TRUE surface
(the offset-surface solver on the true surface), which gives the trigger position and the
true contact point.  Methods:

* naive: probing down, ``P = O − r·ẑ``;
* 2-D: probing down plus two touches ±0.5 mm along the nominal slope;
* micro-plane: probing down plus three touches on a circle of radius ρ (0.5 mm);
* vector: probing along the nominal normal, ``P = O − r·n_nominal``.

Errors, µm, max |·| and RMS over the grid:

* normal: ``(P_a − P_true)·n_true`` (distance of the found contact from the true surface
  to first order; what any fit sees; naive's is ``r·(1 − cos θ)``, θ the true slope: the
  ``pred`` columns print that prediction from the true normals);
* deviation: ``e_a − e_true``, ``e`` along the nominal normal from ``P_t``, ``e_true`` to
  the true surface on that line (what the report prints per point);
* 3-D: ``|P_a − P_true|``, including the along-surface shift ``r·δ`` of the location.

With ``--sigma`` > 0 every trigger position gets Gaussian noise of that σ (µm) along its
travel direction (fixed seed).  Last, the speed of the vectorised solver: 10,000 guide lines
on a B-spline face seeded as a mesh query would (up to 1 mm off).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from probegen.evaluate import compensate_freeform as cf  # noqa: E402
from probegen.geometry import freeform_offsets as fo  # noqa: E402
from probegen.geometry.bspline import (  # noqa: E402
    BSplineSurface,
    clamped_knots,
    greville,
    height_field,
)
from probegen.geometry.offset_surface import BallCentres, ball_centres  # noqa: E402

SLOPES = (0, 10, 20, 30, 40, 50, 60)
RADIUS = 3.0            # ball radius, mm (6 mm ruby, as in the seed)
SIZE = 40.0             # patch size, mm
POLES = 24              # poles per direction
ALLOWED = 1e-4          # error along the normal the vector method may leave, mm
METHODS = ("naive", "2d", "micro-plane", "vector")
DOWN = np.array(cf.DOWN)


@dataclass(frozen=True)
class Case:
    """One simulated part: its nominal and true surface."""

    slope_deg: float
    nominal: BSplineSurface
    true: BSplineSurface


def make_case(slope_deg: float, *, amplitude: float = 0.010,
              wavelength: float = 15.0) -> Case:
    """Nominal and true (form error planted) surfaces for one slope; lengths in mm."""
    x = greville(clamped_knots(POLES, 3, 0.0, SIZE), 3)  # the poles' x (and y)
    gx, gy = np.meshgrid(x, x, indexing="ij")
    bowl = (gx - SIZE / 2) ** 2 / 1000.0 + (gy - SIZE / 2) ** 2 / 600.0
    nominal_h = math.tan(math.radians(slope_deg)) * gx + bowl
    form = amplitude * np.sin(2 * np.pi * gx / wavelength) * np.cos(2 * np.pi * gy / 21.0)
    nominal = height_field(nominal_h, x=(0.0, SIZE), y=(0.0, SIZE))
    # the poles of a height field are not on the surface, but the planted error is a smooth
    # B-spline too and the truth is always read from the true surface itself
    true = height_field(nominal_h + form, x=(0.0, SIZE), y=(0.0, SIZE))
    return Case(float(slope_deg), nominal, true)


def touch(surface: BSplineSurface, origins: np.ndarray, direction: np.ndarray,
          seeds: np.ndarray) -> BallCentres:
    """Where the ball (radius RADIUS) moving along the lines first touches ``surface``."""
    return ball_centres(surface, origins, direction, RADIUS, seeds, strict=True)


def down_lines(xy: np.ndarray) -> np.ndarray:
    """Origins of vertical guide lines far above the patch."""
    return np.column_stack([xy, np.full(len(xy), 200.0)])


def noisy(centres: np.ndarray, travel: np.ndarray, sigma_mm: float,
          rng: np.random.Generator) -> np.ndarray:
    """Trigger positions with Gaussian noise along each travel direction."""
    if sigma_mm == 0.0:
        return centres
    return centres + sigma_mm * rng.standard_normal((len(centres), 1)) * travel


def simulate(case: Case, *, grid: int, sigma_um: float, rho: float = 0.5,
             count: int = 3, spacing: float = 0.5,
             seed: int = 6) -> dict[str, dict[str, np.ndarray]]:
    """Errors (mm) of every method at every guide point; see the module docstring."""
    rng = np.random.default_rng(seed)
    sigma = sigma_um / 1000.0
    g = np.linspace(5.0, SIZE - 5.0, grid)
    xy = np.array([(a, b) for a in g for b in g])
    nom = touch(case.nominal, down_lines(xy), DOWN, xy)
    n_nom = nom.normal
    # probing down at the guide points and at the extra touches
    down = touch(case.true, down_lines(xy), DOWN, xy)
    o_down = noisy(down.centre, DOWN, sigma, rng)
    pair_xy = xy[:, None, :] + fo.two_d_offsets(n_nom, spacing=spacing)[:, :, :2]
    pairs = _touch_many(case.true, pair_xy, sigma, rng)
    tri_xy = xy[:, None, :] + fo.micro_plane_offsets(radius=rho, count=count)[None, :, :2]
    triples = _touch_many(case.true, tri_xy, sigma, rng)
    # vector probing along the nominal normal, from 2 mm above the theoretical centre
    start = nom.centre + 2.0 * n_nom
    vec = ball_centres(case.true, start, -n_nom, RADIUS, nom.uv, strict=True)
    o_vec = noisy(vec.centre, -n_nom, sigma, rng)
    found = {
        "naive": (cf.naive(o_down, RADIUS), down),
        "2d": (cf.two_d(o_down, pairs, RADIUS), down),
        "micro-plane": (cf.micro_plane(o_down, triples, RADIUS), down),
        "vector": (cf.vector(o_vec, n_nom, RADIUS), vec),
    }
    # the true deviation along the nominal normal: that line meets the true surface
    e_true = -ball_centres(case.true, nom.contact, -n_nom, 0.0, nom.uv, strict=True).t
    out = {}
    for name, (comp, truth) in found.items():
        e = cf.deviation_map(comp, nom.contact, n_nom).deviation
        diff = comp.contacts - truth.contact
        out[name] = {"normal": np.einsum("ij,ij->i", diff, truth.normal),
                     "deviation": e - e_true, "3d": np.linalg.norm(diff, axis=1)}
    out["naive"]["pred"] = RADIUS * (1.0 - down.normal @ -DOWN)
    vector_map = cf.deviation_map(found["vector"][0], nom.contact, n_nom)
    out["vector"]["flag"] = cf.needs_micro_plane(vector_map, RADIUS, ALLOWED)
    return out


def _touch_many(surface: BSplineSurface, xy: np.ndarray, sigma: float,
                rng: np.random.Generator) -> np.ndarray:
    """Ball centres of vertical touches at ``(m, k, 2)`` positions → ``(m, k, 3)``."""
    m, k, _ = xy.shape
    flat = xy.reshape(-1, 2)
    centres = touch(surface, down_lines(flat), DOWN, flat).centre
    return noisy(centres, DOWN, sigma, rng).reshape(m, k, 3)


def stats(values: np.ndarray) -> tuple[float, float]:
    """(max |v|, RMS) in µm."""
    return float(np.max(np.abs(values))) * 1e3, float(np.sqrt(np.mean(values ** 2))) * 1e3


def table(results: dict[float, dict[str, dict[str, np.ndarray]]], kind: str) -> list[str]:
    """One text table: a row per slope, max/RMS per method (µm)."""
    head = f"{'slope':>5} " + " ".join(f"{m + ' max/rms':>22}" for m in METHODS)
    extra = kind == "normal"
    if extra:
        head += f" {'naive pred max':>15} {'r(1-cos)':>9}"
    lines = [head]
    for slope, res in results.items():
        cells = [f"{a:10.4f}/{b:<11.4f}" for a, b in (stats(res[m][kind]) for m in METHODS)]
        row = f"{slope:5.0f} " + " ".join(cells)
        if extra:
            planar = RADIUS * (1.0 - math.cos(math.radians(slope))) * 1e3
            row += f" {stats(res['naive']['pred'])[0]:15.4f} {planar:9.3f}"
        lines.append(row)
    return lines


def fallback_table(results: dict[float, dict[str, dict[str, np.ndarray]]]) -> list[str]:
    """Vector probing with the micro-plane fallback where the map's slope is too large."""
    lines = [f"{'slope':>5} {'flagged':>8} {'vector max':>11} {'vector kept max':>16} "
             f"{'combined max':>13}"]
    for slope, res in results.items():
        flag = res["vector"]["flag"]
        vec, micro = np.abs(res["vector"]["normal"]), np.abs(res["micro-plane"]["normal"])
        kept = float(vec[~flag].max()) * 1e3 if (~flag).any() else float("nan")
        combined = float(np.where(flag, micro, vec).max()) * 1e3
        lines.append(f"{slope:5.0f} {int(flag.sum()):4d}/{len(flag):<3d} "
                     f"{float(vec.max()) * 1e3:11.4f} {kept:16.4f} {combined:13.4f}")
    return lines


def rho_sweep(slope: float, sigma_um: float, grid: int) -> list[str]:
    """Micro-plane circle radius against curvature and noise (errors µm)."""
    lines = [f"{'rho mm':>6} {'3 touches: normal':>22} {'3d max/rms':>22} "
             f"{'4 touches: normal':>22} {'3d max/rms':>22}"]
    case = make_case(slope)
    for rho in (0.05, 0.1, 0.2, 0.5, 1.0):
        cells = []
        for count in (3, 4):
            res = simulate(case, grid=grid, sigma_um=sigma_um, rho=rho,
                           count=count)["micro-plane"]
            cells += [f"{a:10.4f}/{b:<11.4f}" for a, b in (stats(res["normal"]),
                                                          stats(res["3d"]))]
        lines.append(f"{rho:6.2f} " + " ".join(cells))
    return lines


def speed(count: int = 10_000, repeat: int = 3) -> str:
    """Lines per second of the vectorised solver on a bicubic B-spline face."""
    case = make_case(30.0)
    rng = np.random.default_rng(1)
    xy = rng.uniform(2.0, SIZE - 2.0, (count, 2))
    seeds = xy + rng.uniform(-1.0, 1.0, xy.shape)  # a mesh query's nearest vertex
    best, res = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = ball_centres(case.true, down_lines(xy), DOWN, RADIUS, seeds)
        best = min(best, time.perf_counter() - t0)
    assert res is not None
    return (f"solver: {count} guide lines on a {POLES}x{POLES} bicubic B-spline face, "
            f"seeds up to 1 mm off: {best:.3f} s, {count / best:,.0f} lines/s; "
            f"converged {int(res.ok.sum())}/{count}, iterations mean "
            f"{res.iterations.mean():.2f} max {int(res.iterations.max())}, "
            f"largest residual {res.residual.max():.1e} mm")


def main(argv: list[str] | None = None) -> None:
    """Print the accuracy tables (noise-free and noisy) and the speed figure."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--grid", type=int, default=15, help="guide points per side")
    parser.add_argument("--sigma", type=float, default=0.5, help="trigger noise σ, µm")
    parser.add_argument("--slopes", type=float, nargs="*", default=SLOPES)
    parser.add_argument("--amplitude", type=float, default=10.0,
                        help="planted form error amplitude, µm")
    parser.add_argument("--no-speed", action="store_true")
    args = parser.parse_args(argv)
    print(f"ball radius {RADIUS} mm; form error {args.amplitude} um, wavelengths 15 x 21 mm; "
          f"{args.grid}x{args.grid} guide points per slope; errors in um")
    amplitude = args.amplitude / 1000.0
    for sigma in (0.0, args.sigma):
        results = {s: simulate(make_case(s, amplitude=amplitude), grid=args.grid,
                               sigma_um=sigma) for s in args.slopes}
        kinds = ("normal", "deviation", "3d") if sigma == 0.0 else ("normal", "deviation")
        for kind in kinds:
            print(f"\n[{kind} error, sigma = {sigma} um]")
            print("\n".join(table(results, kind)))
        if sigma == 0.0:
            print(f"\n[vector probing, micro-plane where the map's slope allows more than "
                  f"{ALLOWED * 1e3} um; normal error, sigma = 0]")
            print("\n".join(fallback_table(results)))
    for sigma in (0.0, args.sigma):
        print(f"\n[micro-plane circle radius, slope 30 deg, sigma = {sigma} um]")
        print("\n".join(rho_sweep(30.0, sigma, args.grid)))
    if not args.no_speed:
        print("\n" + speed())


if __name__ == "__main__":
    main()
