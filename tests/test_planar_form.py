"""Form of lines and planes: flatness and straightness by the ISO 1101 minimum zone (least
squares on request), the method named in results.json, and the ``form`` tolerance.

The zones are checked on constructed points whose minimum zone is known exactly; the
tolerance on a virtual-machine run of the lines-and-planes spec of
``test_no_false_ok`` with a planted form error (one touch of each face moved).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import REPO
from test_no_false_ok import FACES, faces_log  # noqa: F401  (the module-scoped fixture)

from probegen.cli.app import ExitCode, main
from probegen.errors import SpecError
from probegen.evaluate.planar import planar_form
from probegen.geometry.fits import fit_line_2d, fit_plane
from probegen.spec.model import load_spec

H = 0.013
"""The constructed zones' width, mm."""
BUMP = {"PT TOP 4 ": ("Z", 0.05), "PT EDGE 2 ": ("Y", 0.015)}
"""The planted form errors: the fourth touch of TOP 50 µm high, the middle touch of
EDGE 15 µm into the material (its outward normal is -Y)."""


def tilted_square(rng: np.random.Generator) -> np.ndarray:
    """A 5 × 5 grid on a tilted plane with heights in [0, H] above it (along Z): the
    four corners at 0, the centre at H (the mean of the corners), so no further tilt
    makes the zone narrower and the plane's own is H measured along Z: the minimum zone
    is exactly H times the cosine of the plane's tilt."""
    u, v = np.meshgrid(np.linspace(-40, 40, 5), np.linspace(-30, 30, 5))
    u, v = u.ravel(), v.ravel()
    e = rng.uniform(0.0, H, u.size)
    corners = (np.abs(u) == 40) & (np.abs(v) == 30)
    e[corners], e[(u == 0) & (v == 0)] = 0.0, H
    return np.column_stack([u, v, 5.0 + 0.02 * u - 0.01 * v + e])


def test_flatness_minimum_zone_of_a_known_zone() -> None:
    rng = np.random.default_rng(7)
    for _ in range(5):
        pts = tilted_square(rng)
        zone, method = planar_form("plane", pts, "minimum_zone")
        ls, ls_method = planar_form("plane", pts, "least_squares")
        assert (method, ls_method) == ("minimum zone", "least squares")
        assert zone == pytest.approx(H / np.linalg.norm([0.02, -0.01, 1.0]), abs=1e-9)
        assert ls == pytest.approx(fit_plane(pts).form, abs=1e-12)
        assert ls > zone + 1e-4  # the noisy interior tilts the least-squares plane


def test_straightness_minimum_zone_of_a_known_zone() -> None:
    """Ends at 0, the middle at H, the rest in [0, H] about a slanted line in XY."""
    rng = np.random.default_rng(8)
    for _ in range(5):
        s = np.linspace(0.0, 60.0, 9)
        e = rng.uniform(0.0, H, s.size)
        e[0], e[-1], e[4] = 0.0, 0.0, H
        d, n = np.array([0.8, 0.6]), np.array([-0.6, 0.8])
        xy = np.outer(s, d) + np.outer(e, n) + [3.0, -2.0]
        pts = np.column_stack([xy, np.full(s.size, 25.0)])
        zone, _ = planar_form("line", pts, "minimum_zone")
        ls, _ = planar_form("line", pts, "least_squares")
        assert zone == pytest.approx(H, abs=1e-9)
        assert ls == pytest.approx(fit_line_2d(xy).form, abs=1e-12) and ls >= zone


def faces_spec(tmp: Path, form: str, low: float = -0.5) -> Path:
    """The lines-and-planes spec with ``form`` TOML added to both tolerance tables
    (TOP's position ``[low, 0.5]``)."""
    text = FACES.format(repo=REPO, low=low).replace(
        "angle = 1.0 }", f"angle = 1.0, {form} }}").replace(
        ", 0.5] }", f", 0.5], {form} }}")
    path = tmp / "faces.toml"
    path.write_text(text)
    return path


def bumped(log: Path, tmp: Path) -> Path:
    out = []
    for line in log.read_text().splitlines():
        for start, (axis, by) in BUMP.items():
            if line.startswith(start):
                words = line.split()
                k = next(i for i, w in enumerate(words) if w.startswith(axis))
                words[k] = f"{axis}{float(words[k][1:]) + by:.4f}"
                line = " ".join(words)
        out.append(line)
    path = tmp / "bumped.log"
    path.write_text("\n".join(out) + "\n")
    return path


def ingest(log: Path, spec: Path, tmp: Path) -> tuple[int, dict[str, dict[str, Any]]]:
    code = main(["ingest", str(log), "--spec", str(spec), "-o", str(tmp / "out"), "-q"])
    doc = json.loads((tmp / "out/results.json").read_text())
    return code, {f"{f['id']} {c['name']}": c for f in doc["features"]
                  for c in f.get("characteristics", [])}


def test_form_tolerance_and_method_in_results(faces_log: Path, tmp_path: Path) -> None:  # noqa: F811
    log = bumped(faces_log, tmp_path)
    code, chars = ingest(log, faces_spec(tmp_path, "form = 0.02"), tmp_path)
    top, edge = chars["TOP FORM"], chars["EDGE FORM"]
    assert (top["method"], edge["method"]) == ("minimum zone", "minimum zone")
    assert (top["lower"], top["upper"], edge["upper"]) == (None, 0.02, 0.02)
    # three touches, the middle one 15 µm in: the zone is 15 µm (to the log's 4
    # decimals; the ball's cosine error is the same at every touch).  TOP: 4 touches
    # p1..p4 with sum(l_k p_k) = 0, sum(l_k) = 0 for l = (-5/6, 2/3, -5/6, 1): the
    # minimum zone of heights e is 2|sum(l_k e_k)| / sum|l_k| = 0.6 e4 = 30 µm
    assert edge["measured"] == pytest.approx(0.015, abs=1e-4) and edge["status"] == "OK"
    assert top["measured"] == pytest.approx(0.03, abs=1e-4) and top["status"] == "NOT OK"
    assert code == ExitCode.NOT_OK
    code, ls = ingest(log, faces_spec(tmp_path, 'form = 0.02, form_method = "least_squares"'),
                      tmp_path)
    assert ls["TOP FORM"]["method"] == "least squares"
    # least squares: the residuals are l (l·e) / |l|², their range 11/6 · e4 / (17/6)
    assert ls["TOP FORM"]["measured"] == pytest.approx(0.05 * 11 / 17, abs=1e-4)
    code, ok = ingest(log, faces_spec(tmp_path, "form = 0.035"), tmp_path)
    assert code == ExitCode.OK and ok["TOP FORM"]["status"] == "OK"
    # without a form tolerance the form is still evaluated, by the minimum zone, not checked
    plain = tmp_path / "plain.toml"
    plain.write_text(FACES.format(repo=REPO, low=-0.5))
    code, free = ingest(log, plain, tmp_path)
    assert free["TOP FORM"]["method"] == "minimum zone" and free["TOP FORM"]["upper"] is None


def test_evaluation_form_method_is_the_default(tmp_path: Path) -> None:
    spec = faces_spec(tmp_path, "form = 0.02")
    spec.write_text(spec.read_text().replace(
        "[program]", '[evaluation]\nform_method = "least_squares"\n\n[program]'))
    tops = {f.id: f for f in load_spec(spec).features}
    assert tops["TOP"].tolerance.form_method == "least_squares"  # type: ignore[union-attr]


def test_form_tolerance_needs_enough_contacts(tmp_path: Path) -> None:
    spec = faces_spec(tmp_path, "form = 0.02")
    spec.write_text(spec.read_text().replace(
        "[30.0, 30.0, 50.0]]", "]").replace("[20.0, 80.0, 50.0], ]", "[20.0, 80.0, 50.0]]"))
    with pytest.raises(SpecError, match=r"contacts: a form tolerance needs at least 4 "
                                        r"contacts on a plane, found 3"):
        load_spec(spec)


def test_a_toleranced_form_cut_short_is_not_evaluated(faces_log: Path,  # noqa: F811
                                                      tmp_path: Path) -> None:
    """TOP's fourth touch missing: its toleranced FORM is listed NOT EVALUATED (never
    dropped because three touches have no form)."""
    kept = [line for line in faces_log.read_text().splitlines()
            if not line.startswith(("PT TOP 4", "PGEND"))]
    log = tmp_path / "cut.log"
    log.write_text("\n".join(kept) + "\n")
    code, chars = ingest(log, faces_spec(tmp_path, "form = 0.02"), tmp_path)
    assert code == ExitCode.INCOMPLETE
    assert (chars["TOP FORM"]["status"], chars["TOP FORM"]["upper"]) == ("NOT EVALUATED", 0.02)
    assert chars["EDGE FORM"]["status"] == "OK"
