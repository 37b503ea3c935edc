"""Which stylus of the rack plans a feature (``planning/styli.py``): the largest ball
first, then the shorter stylus; a forced label; the smallest stylus's error with what
each said when none plans.  ``plan_with`` is a fake that plans with any ball up to a
given size (a bore of that diameter) and a length at least a given depth."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import pytest
from conftest import REPO

from probegen.errors import CollisionError, ModelError, PlanningError, SpecError
from probegen.machine.profile import MachineProfile, Stylus, load_profile
from probegen.planning import styli
from probegen.planning.styli import pick_stylus, rack_order, smallest_stylus

CMM = load_profile(REPO / "samples" / "machines" / "cmm.toml")
FIVE = load_profile(REPO / "samples" / "machines" / "vmc-5axis-fanuc.toml")
VMC = load_profile(REPO / "samples" / "machines" / "vmc-fanuc.toml")


def bore(diameter: float, depth: float = 0.0, tried: list[float] | None = None
         ) -> Callable[[MachineProfile], str]:
    """A fake planner: a bore of ``diameter`` and ``depth`` (mm) plans with a ball at most
    ``diameter - 1`` and a stylus at least ``depth`` long; records the balls tried."""
    def plan(m: MachineProfile) -> str:
        p = m.probe
        if tried is not None:
            tried.append(p.ball_diameter)
        if p.ball_diameter > diameter - 1.0:
            raise PlanningError(f"spec.toml: feature[0]: bore {diameter:g}: expected a "
                                f"ball under {diameter - 1.0:g} mm, found {p.ball_diameter:g}")
        if p.length < depth:
            raise CollisionError(f"spec.toml: feature[0]: the probe body hits the part at "
                                 f"depth {p.length:g} of {depth:g} mm")
        return f"plan T{p.tool_number} ball {p.ball_diameter:g}"
    return plan


def test_the_largest_ball_that_fits_wins() -> None:
    tried: list[float] = []
    s, plan = pick_stylus(FIVE, bore(4.5, tried=tried))
    assert (s.label, plan) == ("D3", "plan T21 ball 3")
    assert tried == [6.0, 6.0, 3.0]   # D6, then D6L (the same ball, longer), then D3
    s, plan = pick_stylus(FIVE, bore(20.0))
    assert (s.label, plan) == ("D6", "plan T20 ball 6")


def test_the_cmm_rack_order_and_its_smallest() -> None:
    assert [s.label for s in rack_order(CMM)] == ["D6", "D3", "D3L", "D2", "D1"]
    assert smallest_stylus(CMM).label == "D1"
    assert smallest_stylus(FIVE).label == "D1"
    assert smallest_stylus(VMC).label == "PRB20"
    s, _ = pick_stylus(CMM, bore(2.5))
    assert s.label == "D1"


def test_equal_balls_shorter_first_longer_for_depth() -> None:
    long3 = Stylus("L3", 3.0, 2.0, 80.0, 25)
    machine = replace(FIVE, rack=(*FIVE.rack, long3))
    assert [s.label for s in rack_order(machine)] == ["D6", "D6L", "D3", "L3", "D2", "D1"]
    assert smallest_stylus(machine).label == "D1"
    s, plan = pick_stylus(machine, bore(5.0, depth=60.0))
    assert (s.label, plan) == ("L3", "plan T25 ball 3")
    s, _ = pick_stylus(machine, bore(5.0, depth=30.0))
    assert s.label == "D3"


def test_force_plans_that_stylus_only() -> None:
    tried: list[float] = []
    s, plan = pick_stylus(FIVE, bore(20.0, tried=tried), force="D2")
    assert (s.label, plan, tried) == ("D2", "plan T22 ball 2", [2.0])
    with pytest.raises(PlanningError, match="expected a ball under 1 mm, found 2"):
        pick_stylus(FIVE, bore(2.0), force="D2")


def test_a_forced_label_not_in_the_rack() -> None:
    with pytest.raises(SpecError, match=r"stylus: expected a stylus of the machine's rack "
                                        r"\(D6, D6L, D3, D2, D1; .*vmc-5axis-fanuc.toml: "
                                        r"\[\[probe.stylus\]\]\), found 'D5'"):
        pick_stylus(FIVE, bore(20.0), force="D5")


def test_none_plans_raises_the_smallest_error_with_what_each_said() -> None:
    with pytest.raises(PlanningError) as info:
        pick_stylus(FIVE, bore(1.5))
    text = str(info.value)
    assert text.startswith("spec.toml: feature[0]: bore 1.5: expected a ball under 0.5 mm, "
                           "found 1 (with D1, the smallest stylus; no stylus of the rack "
                           "plans it, largest first: ")
    # what all the messages share (the feature's "where") is said once, at the start
    assert text.endswith("D6 (ball 6 mm): expected a ball under 0.5 mm, found 6; "
                         "D6L (ball 6 mm): expected a ball under 0.5 mm, found 6; "
                         "D3 (ball 3 mm): expected a ball under 0.5 mm, found 3; "
                         "D2 (ball 2 mm): expected a ball under 0.5 mm, found 2; "
                         "D1 (ball 1 mm): expected a ball under 0.5 mm, found 1)")


def test_the_error_keeps_the_smallest_styluss_class() -> None:
    with pytest.raises(CollisionError, match=r"the probe body hits the part at depth 20 of "
                                             r"120 mm \(with D1, the smallest stylus; "
                                             r"no stylus"):
        pick_stylus(FIVE, bore(20.0, depth=120.0))


def test_one_stylus_error_unchanged() -> None:
    with pytest.raises(PlanningError) as info:
        pick_stylus(VMC, bore(5.0))
    assert str(info.value) == ("spec.toml: feature[0]: bore 5: expected a ball under 4 mm, "
                               "found 6")


def test_long_messages_are_cut_at_a_word() -> None:
    def plan(m: MachineProfile) -> str:
        raise PlanningError(f"feature B1: ball {m.probe.ball_diameter:g}: " + "word " * 40)
    with pytest.raises(PlanningError) as info:
        pick_stylus(FIVE, plan)
    said = str(info.value).split("largest first: ", 1)[1]
    assert "D6 (ball 6 mm): ball 6: word word" in said
    assert all(len(part) < 130 for part in said.split("; "))
    assert " ...; D3" in said


def test_other_errors_go_through_at_once() -> None:
    tried: list[float] = []

    def plan(m: MachineProfile) -> str:
        tried.append(m.probe.ball_diameter)
        raise ModelError("part.step: expected a STEP model")
    with pytest.raises(ModelError):
        pick_stylus(FIVE, plan)
    assert tried == [6.0]


def test_the_probe_stylus_plans_with_the_profile_itself() -> None:
    seen: list[MachineProfile] = []

    def plan(m: MachineProfile) -> str:
        seen.append(m)
        return "ok"
    pick_stylus(FIVE, plan)
    assert seen[0] is FIVE


def test_the_message_of_none_plans_is_made_when_read(monkeypatch: pytest.MonkeyPatch
                                                     ) -> None:
    read: list[str] = []

    class Counted:  # a stylus's error whose text costs a measurement to make
        def __init__(self, ball: float) -> None:
            self.ball = ball

        def __str__(self) -> str:
            read.append(f"{self.ball:g}")
            return f"feature B1: ball {self.ball:g} collides"

    def plan(m: MachineProfile) -> str:
        raise PlanningError(Counted(m.probe.ball_diameter))

    with pytest.raises(PlanningError) as info:
        pick_stylus(FIVE, plan)
    assert read == []  # dropped unread (another orientation plans it): nothing made
    lazy = str(info.value)
    assert read == ["6", "6", "3", "2", "1"] and str(info.value) == lazy  # made once
    monkeypatch.setattr(styli, "LAZY", False)
    with pytest.raises(PlanningError) as eager:
        pick_stylus(FIVE, plan)
    assert str(eager.value) == lazy
