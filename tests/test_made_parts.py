"""The parts of our own making (samples/parts, issue 17 item 6).

Each committed STEP file is what ``samples/parts/make_parts.py`` writes, byte for byte;
revolved recognition finds exactly the features the README lists (kind, side, nominal
diameter, axis and where the feature sits); ``probegen init`` on each part gives a spec
that compiles unchanged to Fanuc and DMIS.  The expected figures are written out here
from the README, not taken from the generator's constants.
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from conftest import REPO
from test_init import _compiles, _init

from probegen import cad
from probegen.cad.revolved import revolved_features
from probegen.cli.app import main
from probegen.errors import ExitCode

PARTS = REPO / "samples/parts"
NAMES = ("five_face_block", "small_holes", "counterbores", "flange", "odd_angle")
X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)


def _slope_axis(deg: float) -> tuple[float, float, float]:
    """The outward normal of a face sloping ``deg`` from Z towards +X (negative: -X)."""
    t = math.radians(deg)
    return (math.sin(t), 0.0, math.cos(t))


def _into(at: tuple[float, ...], axis: tuple[float, float, float], depth: float
          ) -> tuple[float, float, float]:
    """The middle of a hole ``depth`` deep from ``at`` against ``axis``."""
    return tuple(float(a - depth / 2.0 * n) for a, n in zip(at, axis, strict=True))  # type: ignore[return-value]


BOLTS = [(37.5 * math.cos(math.radians(a)), 37.5 * math.sin(math.radians(a)), 6.0)
         for a in range(0, 360, 60)]
S30, S37 = _slope_axis(30.0), _slope_axis(-37.3)
EXPECTED: dict[str, list[tuple[str, bool, float, tuple[float, float, float],
                               tuple[float, float, float]]]] = {
    # (type, inner, diameter (cone: at its narrow end; torus: major), axis, middle point)
    "five_face_block": [
        *[("cylinder", False, 4.0, Z, (x, y, 20.0)) for x in (2.0, 78.0) for y in (2.0, 58.0)],
        ("cylinder", True, 20.0, Z, (25.0, 30.0, 20.0)),
        ("cylinder", True, 8.0, Z, (60.0, 40.0, 34.0)),
        ("cylinder", True, 12.0, Y, (60.0, 30.0, 14.0)),
        ("cylinder", True, 6.0, Y, (25.0, 5.0, 20.0)),
        ("cylinder", True, 16.0, X, (74.0, 30.0, 20.0)),
        ("cylinder", True, 10.0, X, (5.0, 30.0, 20.0)),
    ],
    "small_holes": [("cylinder", True, d, Z, (x, 15.0, 5.0))
                    for x, d in ((10.0, 1.5), (25.0, 2.5), (42.0, 4.0), (58.0, 5.0))],
    "counterbores": [
        ("cylinder", True, 18.0, Z, (15.0, 20.0, 14.5)),
        ("cylinder", True, 11.0, Z, (15.0, 20.0, 4.5)),
        ("cylinder", True, 11.0, Z, (40.0, 20.0, 16.75)),
        ("cylinder", True, 6.6, Z, (40.0, 20.0, 6.75)),
        ("cone", True, 6.6, Z, (62.0, 20.0, 18.4)),
        ("cylinder", True, 6.6, Z, (62.0, 20.0, 8.4)),
        ("cone", True, 9.0, Z, (80.0, 20.0, 18.0)),
        ("cylinder", True, 9.0, Z, (80.0, 20.0, 8.0)),
    ],
    "flange": [
        ("cylinder", False, 100.0, Z, (0.0, 0.0, 6.0)),
        ("cylinder", False, 50.0, Z, (0.0, 0.0, 18.0)),
        ("cylinder", True, 25.0, Z, (0.0, 0.0, 11.0)),
        *[("cylinder", True, 9.0, Z, b) for b in BOLTS],
        ("torus", False, 54.0, Z, (0.0, 0.0, 13.0)),
    ],
    "odd_angle": [
        ("cylinder", True, 10.0, S30, _into((100.0 - 10.0 * math.sqrt(3.0), 25.0, 30.0),
                                            S30, 10.0)),
        ("cylinder", True, 8.0, S37, _into((10.0 / math.tan(math.radians(37.3)), 25.0, 30.0),
                                           S37, 8.0)),
        ("cylinder", True, 12.0, Z, (50.0, 25.0, 7.5)),
    ],
}
"""Per part, every revolved feature it has."""
CLOSE = 1e-6


def make_parts() -> ModuleType:
    """``samples/parts/make_parts.py``, loaded as a module."""
    spec = importlib.util.spec_from_file_location("make_parts", PARTS / "make_parts.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_committed_steps_are_what_the_script_writes(tmp_path: Path) -> None:
    fresh = make_parts().main(tmp_path)
    assert sorted(p.name for p in fresh) == sorted(f"{n}.step" for n in NAMES)
    for path in fresh:
        assert path.read_bytes() == (PARTS / path.name).read_bytes(), path.name


def _middle(f: object) -> np.ndarray:
    low, high = f.extent  # type: ignore[attr-defined]
    return np.asarray(f.centre_at((low + high) / 2.0))  # type: ignore[attr-defined]


@pytest.mark.parametrize("name", NAMES)
def test_recognition_finds_every_feature_with_its_size(name: str) -> None:
    features = revolved_features(cad.load_part(PARTS / f"{name}.step"))
    assert len(features) == len(EXPECTED[name])
    left = list(features)
    for kind, inner, diameter, axis, middle in EXPECTED[name]:
        found = [f for f in left if f.type == kind and f.inner == inner
                 and abs(2.0 * f.radius - diameter) < CLOSE
                 and np.allclose(f.axis, axis, atol=CLOSE)
                 and np.allclose(_middle(f), middle, atol=CLOSE)]
        assert len(found) == 1, (kind, inner, diameter, axis, middle)
        left.remove(found[0])
    assert not left


def test_counterbore_and_countersink_sizes() -> None:
    """The countersinks' 90 deg cones reach D13 and D17 at the top face; the flange's
    fillet is a quarter of a 2 mm tube."""
    cones = [f for f in revolved_features(cad.load_part(PARTS / "counterbores.step"))
             if f.type == "cone"]
    assert [round(2.0 * f.radius_at(f.extent[1]), 9) for f in cones] == [13.0, 17.0]
    assert all(abs(math.degrees(f.half_angle) - 45.0) < 1e-6 for f in cones)
    assert all(abs(f.centre_at(f.extent[1])[2] - 20.0) < CLOSE for f in cones)
    torus = next(f for f in revolved_features(cad.load_part(PARTS / "flange.step"))
                 if f.type == "torus")
    assert torus.minor_radius == pytest.approx(2.0) and torus.length == pytest.approx(2.0)


def test_what_a_vertical_probe_cannot_reach() -> None:
    """The side holes, the sloping ones and the face-down one are refused by a vertical
    probe with the reason; the top ones are reachable."""
    block = revolved_features(cad.load_part(PARTS / "five_face_block.step"))
    assert sorted(f.accessible for f in block if f.inner) == [False] * 4 + [True] * 2
    odd = {round(2.0 * f.radius): f for f in
           revolved_features(cad.load_part(PARTS / "odd_angle.step"))}
    assert math.degrees(math.acos(odd[8].axis[2])) == pytest.approx(37.3)
    assert math.degrees(math.acos(odd[10].axis[2])) == pytest.approx(30.0)
    assert all("not parallel to Z" in odd[d].reason for d in (8, 10))
    assert odd[12].reason.startswith("closed above")


@pytest.mark.parametrize("name", NAMES)
def test_init_skeleton_compiles_unchanged(name: str, tmp_path: Path) -> None:
    spec = tmp_path / f"{name}.toml"
    text = _init(PARTS / f"{name}.step", spec)
    assert "\n[[feature]]\n" in text
    _compiles(spec, tmp_path / "out")


ISSUE17_PROFILES = {"cmm": "dmis", "vmc-5axis-fanuc": "fanuc"}
"""The issue's sample profiles and the dialect each writes; tested where they exist."""
WITH_PROFILES = [(n, p) for p in sorted(ISSUE17_PROFILES)
                 if (REPO / f"samples/machines/{p}.toml").exists() for n in NAMES]


@pytest.mark.parametrize(("name", "profile"), WITH_PROFILES)
def test_init_with_the_issue_profiles_compiles(name: str, profile: str,
                                               tmp_path: Path) -> None:
    """``probegen init`` with the CMM (to DMIS) and the five-axis (to Fanuc) profiles."""
    machine = REPO / f"samples/machines/{profile}.toml"
    spec = tmp_path / f"{name}.toml"
    assert main(["-q", "init", str(PARTS / f"{name}.step"), "--machine", str(machine),
                 "-o", str(spec)]) == ExitCode.OK
    dialect = ISSUE17_PROFILES[profile]
    assert main(["-q", "compile", str(spec), "-d", dialect, "-o",
                 str(tmp_path / "out")]) == ExitCode.OK
    assert (tmp_path / "out" / f"{name}.{'dmi' if dialect == 'dmis' else 'nc'}").is_file()


def test_benchmark_counts_fillets_narrow_bores_and_reasons(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """benchmarks/bench_real_parts.py on our parts with its stand-in CMM (a rack of 3, 1,
    2 and 6 mm balls, margin 0.3: the smallest bore 2.4 mm): the block's four rounded
    edges and the flange's foot are fillets, the 1.5 mm hole is narrow; a left-out line
    is classed by its first reason."""
    from dataclasses import replace

    monkeypatch.syspath_prepend(str(REPO / "benchmarks"))
    import bench_real_parts as bench

    case = replace(bench.CASES["cmm"], sample=tmp_path / "absent.toml")
    machine, _path, where = bench.load_case(case, tmp_path)
    assert where.startswith("stand-in")
    assert [s.ball_diameter for s in machine.styli()] == [3.0, 1.0, 2.0, 6.0]
    assert bench.least_bore(machine) == pytest.approx(2.4)
    counts = {}
    for name in NAMES:
        fillets, narrow, eligible = bench.eligibility(
            cad.load_part(PARTS / f"{name}.step"), machine)
        counts[name] = (len(fillets), len(narrow), len(eligible))
    assert counts == {"five_face_block": (4, 0, 6), "small_holes": (0, 1, 3),
                      "counterbores": (0, 0, 8), "flange": (1, 0, 9), "odd_angle": (0, 0, 3)}
    lines = {
        "R1 bore D8.000 (cylinder, faces 9): axis (-0.6060, 0.0000, 0.7955) is 37.3 deg "
        "from Z, not along the probe: needs an orientation or a setup; bore D8.000: the "
        "stylus ball D6.000 needs D8.000 or more: a smaller stylus": "orientation",
        "R2 bore D12.000 (cylinder, faces 10): closed above: material at z = 15.0000 over "
        "the centre: reach it from below: needs a setup": "setup",
        "R4 bore D4.000 (cylinder, faces 9): bore D4.000: the stylus ball D6.000 needs "
        "D8.000 or more: a smaller stylus": "stylus too large",
        "R6 torus D54.000 tube D4.000 (torus, faces 7): no touch can be reached safely: no "
        "room: the stylus ball meets face 1 (a smaller or longer stylus, or another "
        "orientation) [no touch]": "collision",
        "R9 bore D3.000 (cylinder, faces 2): blind, depth 0.400 mm: the ball reaches no "
        "section (it needs 3.500 mm below one: radius 3.000 + margin 0.500): a smaller "
        "stylus [x]": "blind depth",
        "R221 bore D36.000 (cylinder, faces 439): the section's centre lies in material":
            "not accessible",
        "R3 boss D4.000 (cylinder, faces 3): arc too short: the longest arc on the faces "
        "is 3.142 mm, the ball D6.000 needs 7.000 mm: a smaller stylus": "arc too short",
        "R69 boss D50.000 (cylinder, faces 141): axis at A 2.8 B -135.0: not on the head's "
        "7.5 deg grid: needs a setup": "head grid",
        "R74 bore D50.000 (cylinder, faces 159): axis at A 177.2 B -45.0: beyond the head's A "
        "range 0..105: no orientation reaches this face: needs a setup": "orientation",
        "R2 bore D12.000 (cylinder, faces 10): tilt 180.0 deg: beyond the A axis's range "
        "-110..110: needs a setup": "orientation",
        "R67 boss D50.000 (cylinder, faces 139): no open end to approach it from":
            "not accessible",
        "R2 outer cone D8.000 (cone, faces 4): cone: 5 points in one section: a free "
        "cone fit needs two sections (one circle lies on many cones): a CMM fits it "
        "freely from the touches; where ...": "free fit",
        "R5 thing": "other",
        # after the setups were tried: what stops it in the setup, where that is not an
        # orientation itself (planning.setups.all_revolved_setups)
        "R24 torus D24.000 tube D4.000 (torus, faces 61): faces down: every touch goes up, "
        "under material: needs an orientation or a setup: add a [[setup]] to the machine "
        "profile (none of its setups FLIPPED reaches it) [x]; in setup FLIPPED: no touch "
        "can be reached safely: no room: the stylus shank meets face 49": "collision",
        "R21 bore D4.000 (cylinder, faces 58): tilt 150.0 deg: beyond the A axis's range "
        "-110..110: needs a setup: add a [[setup]] to the machine profile (none of its "
        "setups FLIPPED reaches it); in setup FLIPPED: axis at A 30.0 B 0.0: beyond the "
        "A axis's range": "orientation",
        "R16 boss D4.000 (cylinder, faces 53): arc too short: the longest arc on the faces "
        "is 1.297 mm; in setup FLIPPED: no room": "arc too short",
    }
    assert {line: bench.reason_of(line) for line in lines} == lines
