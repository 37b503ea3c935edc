"""benchmarks/points_on_model.py, the DMIS points check: a touch where a cross hole's rim
meets a bore's section (NIST FTC 10 R137, the Prusa heatsink R20) is on the model with
its outward vector; the same point with the vector turned into the material is not."""

from __future__ import annotations

import pytest
from build123d import Align, Box, Cylinder, Pos, Rot, export_step
from conftest import REPO

from probegen import cad

C = Align.CENTER


@pytest.fixture(scope="module")
def part(tmp_path_factory: pytest.TempPathFactory) -> cad.Part:
    """A block with a D5.5 bore along X on z = 0 and a D2.5 hole down Z whose rim touches
    the bore's section x = 22.25 at its top (x = 21 + 1.25)."""
    block = Box(40, 20, 20, align=(Align.MIN, C, C))
    block -= Rot(0, 90, 0) * Cylinder(2.75, 40, align=(C, C, Align.MIN))
    block -= Pos(21, 0, 0) * Cylinder(1.25, 10, align=(C, C, Align.MIN))
    path = tmp_path_factory.mktemp("rim") / "rim.step"
    export_step(block, path)
    return cad.load_part(path)


def check(text: str, part: cad.Part, monkeypatch: pytest.MonkeyPatch) -> str:
    monkeypatch.syspath_prepend(str(REPO / "benchmarks"))
    from points_on_model import check_points

    return str(check_points(text, part).text())


def test_a_touch_on_a_cross_holes_rim_is_outward(part: cad.Part,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """Along the vector (down, towards the bore's axis) and against it (up, into the
    cross hole) there is air at the rim itself; beside it the bore's wall is there."""
    rim = "PTMEAS/CART,22.2500,0.0000,2.7500,0.000000,0.000000,-1.000000\n"
    plain = "PTMEAS/CART,30.0000,0.0000,2.7500,0.000000,0.000000,-1.000000\n"
    assert check(rim + plain, part, monkeypatch) == \
        "2 points: all on the model, outward (worst 0.00 um)"


def test_a_vector_into_the_material_is_inward_at_the_rim_too(
        part: cad.Part, monkeypatch: pytest.MonkeyPatch) -> None:
    rim = "PTMEAS/CART,22.2500,0.0000,2.7500,0.000000,0.000000,1.000000\n"
    plain = "PTMEAS/CART,30.0000,0.0000,2.7500,0.000000,0.000000,1.000000\n"
    side = "PTMEAS/CART,30.0000,0.0000,2.7500,1.000000,0.000000,0.000000\n"  # tangent
    assert check(rim + plain + side, part, monkeypatch) == \
        "3 points: 3 inward (worst 0.00 um)"


def test_the_rim_was_what_failed_before(part: cad.Part,
                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """At the rim itself the sides say air both ways (what the check reported inward)."""
    import numpy as np

    monkeypatch.syspath_prepend(str(REPO / "benchmarks"))
    from points_on_model import _sides

    p, v = np.array([22.25, 0.0, 2.75]), np.array([0.0, 0.0, -1.0])
    assert _sides(part.exact, p, v) == "inward"
    assert _sides(part.exact, p + [0.02, 0.0, 0.0], v) == "outward"
