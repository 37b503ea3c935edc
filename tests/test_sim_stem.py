"""The virtual machine checks the whole probe, not only its ball (``sim/stem.py``): a
move whose ball stays clear but whose shank or probe body cuts into the part is a
collision (alarm 9100) naming the element and the face; the same move with the probe
turned away, or with a body that fits, is clear.  The part is the bore_block sample (a
100 x 100 x 50 block with a D50 through-bore at X50 Y50, a boss on top)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from conftest import REPO

from probegen import cad
from probegen.machine.probe_model import ProbeModel
from probegen.machine.profile import Stylus
from probegen.sim.alarms import SimAlarm
from probegen.sim.contact import PlacedPart
from probegen.sim.stem import SIDES, prism, probe_cylinders
from probegen.sim.vm import COLLISION_ALARM, VirtualMachine

D3 = Stylus("D3", 3.0, 2.0, 40.0, 0)
SHORT = Stylus("S10", 3.0, 2.0, 10.0, 0)


@pytest.fixture(scope="module")
def placed() -> PlacedPart:
    return PlacedPart.from_model(cad.load_part(REPO / "samples/bore_block/bore_block.step"))


def vm(placed: PlacedPart, start: Stylus | None, body: tuple[float, float] = (0.0, 0.0),
       axis: tuple[float, float, float] = (0.0, 0.0, 1.0)) -> VirtualMachine:
    return VirtualMachine(placed, ProbeModel(1.5), start=start, body=body, stylus_axis=axis)


def test_a_shank_that_cuts_into_the_part_is_a_collision(placed: PlacedPart) -> None:
    """The ball 0.5 mm off the block's X0 face, the head turned so that the stylus
    points back through the block: the ball is clear, the shank is not."""
    a, b = (-2.0, 40.0, 25.0), (-2.0, 60.0, 25.0)
    vm(placed, D3, axis=(-1.0, 0.0, 0.0)).move(a, b)  # the stylus away from the block
    vm(placed, None, axis=(1.0, 0.0, 0.0)).move(a, b)  # no stylus given: the ball alone
    with pytest.raises(SimAlarm) as exc:
        vm(placed, D3, axis=(1.0, 0.0, 0.0)).move(a, b)
    assert exc.value.number == COLLISION_ALARM
    assert re.match(r"SHANK COLLISION \(GOTO\) WITH FACE [1-9]", exc.value.message)
    assert "(THE BALL FROM X-2.0000 Y40.0000 Z25.0000)" in exc.value.message


def test_a_body_wider_than_the_bore_is_a_collision(placed: PlacedPart) -> None:
    """The ball on the bore's axis 25 mm down, a 10 mm stylus: its body starts 15 mm
    below the bore's top; a 40 mm body fits the D50 bore, a 60 mm one does not.  A long
    stylus keeps even the wide body above the part (the boss stands elsewhere)."""
    down = (50.0, 50.0, 80.0), (50.0, 50.0, 25.0)
    vm(placed, SHORT, body=(40.0, 50.0)).rapid(*down)
    vm(placed, SHORT, body=(0.0, 50.0)).rapid(*down)  # no body stated: the shank alone
    with pytest.raises(SimAlarm) as exc:
        vm(placed, SHORT, body=(60.0, 50.0)).rapid(*down)
    assert re.match(r"BODY COLLISION \(G0\) WITH FACE [1-9]", exc.value.message)


def test_a_probing_move_checks_the_stem_up_to_the_touch(placed: PlacedPart) -> None:
    """A skip move towards the bore's wall with the stylus through the block: alarm
    before the touch; with the stylus up, the touch."""
    start, end = (50.0, 50.0, 25.0), (80.0, 50.0, 25.0)
    hit = vm(placed, D3).skip(start, end, 100.0)
    assert hit is not None and hit[0] == pytest.approx(75.0 - 1.5, abs=1e-3)
    with pytest.raises(SimAlarm, match=r"^alarm 9100: SHANK COLLISION \(PROBING\) WITH FACE "
                                       r"[1-9]"):
        vm(placed, D3, axis=(0.0, 1.0, 0.0)).skip(start, end, 100.0)


def test_the_prism_is_inscribed_in_the_cylinder() -> None:
    """The checked prism's corners lie on the cylinder; its faces at most
    r·(1 - cos(π/SIDES)) inside it: the check never alarms on a move the true cylinder
    clears."""
    (shank,) = probe_cylinders(1.5, 2.0, 40.0, 0.0, 0.0)
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    corners = prism(np.zeros(3), axis, shank)
    along = corners @ axis
    across = np.linalg.norm(corners - np.outer(along, axis), axis=1)
    assert across == pytest.approx(1.0, abs=1e-12)
    assert sorted(set(np.round(along, 9))) == pytest.approx([1.5, 40.0])
    assert 1.0 - math.cos(math.pi / SIDES) < 0.0022


LONG = Stylus("D3L", 3.0, 2.5, 100.0, 0)
SENSORS = """DMISMN/'STEM',05.3
UNITS/MM,ANGDEC
S(D3)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,-1,40,3
S(D3L)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,-1,100,3
SNSLCT/S({label})
GOTO/50,50,120
GOTO/50,50,5
GOTO/50,50,120
ENDFIL
"""


@pytest.mark.parametrize(("label", "alarm"), [("D3L", False), ("D3", True)])
def test_the_cmm_takes_the_stylus_of_the_sensor_s_length(placed: PlacedPart, label: str,
                                                         alarm: bool) -> None:
    """Two styli of one ball (D3 40 mm, D3L 100 mm): SNSLCT takes the one whose length
    the sensor's SNSDEF gives.  The ball 5 mm above the bore's bottom end: D3's 60 mm
    body starts 45 mm up, inside the D50 bore (alarm); D3L's 105 mm up, above the part."""
    from probegen.sim.vm import run_text

    machine = VirtualMachine(placed, ProbeModel(1.5), rack=(D3, LONG), start=D3,
                             body=(60.0, 50.0))
    result = run_text(SENSORS.format(label=label), machine, kind="dmis")
    assert machine.stylus is not None and machine.stylus.label == label
    assert (result.alarm is not None) is alarm
    assert not alarm or re.search(r"^9100 BODY COLLISION \(GOTO\) WITH FACE [1-9]",
                                  result.alarm or "")
