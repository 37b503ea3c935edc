"""Feature order: nearest neighbour improved by 2-opt and Or-opt (probegen.planning.order)."""

from __future__ import annotations

import math

import pytest
from fuzzing import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from probegen.planning.order import (
    Stop,
    cost_matrix,
    nearest_neighbour,
    or_opt_pass,
    order_stops,
    tour_length,
    travel_length,
    travel_path,
    two_opt_pass,
)

ORIGIN = (0.0, 0.0, 0.0)


def _always(a: object, b: object) -> bool:
    return True


def _flat(points: list[tuple[float, float]]) -> list[Stop]:
    return [Stop((x, y, 0.0), (x, y, 0.0)) for x, y in points]


# A(4,6) B(6,4) C(7,5) D(8,1) E(1,9) from the origin: nearest neighbour runs A B C D E
# (sqrt 52 + sqrt 8 + sqrt 2 + sqrt 17 + sqrt 113); one 2-opt move gives D C B A E
# (sqrt 65 + sqrt 17 + sqrt 2 + sqrt 8 + sqrt 18).
CRAFTED = [(4.0, 6.0), (6.0, 4.0), (7.0, 5.0), (8.0, 1.0), (1.0, 9.0)]
NN_LENGTH = math.sqrt(52) + math.sqrt(8) + math.sqrt(2) + math.sqrt(17) + math.sqrt(113)
TWO_OPT_LENGTH = math.sqrt(65) + math.sqrt(17) + math.sqrt(2) + math.sqrt(8) + math.sqrt(18)


def test_two_opt_improves_nearest_neighbour_on_a_crafted_instance() -> None:
    costs = cost_matrix(_flat(CRAFTED), clearance_z=0.0, direct=_always, start=ORIGIN)
    nearest = nearest_neighbour(costs)
    assert nearest == [0, 1, 2, 3, 4, 5]
    assert tour_length(nearest, costs) == pytest.approx(NN_LENGTH, abs=1e-12)
    better = two_opt_pass(nearest, costs)
    assert better == [0, 4, 3, 2, 1, 5]
    assert tour_length(better, costs) == pytest.approx(TWO_OPT_LENGTH, abs=1e-12)
    tour = order_stops(_flat(CRAFTED), clearance_z=0.0, direct=_always, start=ORIGIN)
    assert tour.nearest == (0, 1, 2, 3, 4)
    assert tour.nearest_length == pytest.approx(NN_LENGTH, abs=1e-12)
    assert tour.length <= TWO_OPT_LENGTH + 1e-12


def test_or_opt_moves_a_stop_where_two_opt_cannot() -> None:
    # On a line from 0: nearest neighbour visits 1, 3, -1.5 (1 + 2 + 4.5); no reversal
    # helps, moving -1.5 to the front does (1.5 + 2.5 + 2).
    stops = [Stop((x, 0.0, 0.0), (x, 0.0, 0.0)) for x in (1.0, -1.5, 3.0)]
    costs = cost_matrix(stops, clearance_z=0.0, direct=_always, start=ORIGIN)
    nearest = nearest_neighbour(costs)
    assert nearest == [0, 1, 3, 2] and tour_length(nearest, costs) == pytest.approx(7.5)
    assert two_opt_pass(nearest, costs) is None
    assert or_opt_pass(nearest, costs) == [0, 2, 1, 3]
    assert order_stops(stops, clearance_z=0.0, direct=_always, start=ORIGIN).length == (
        pytest.approx(6.0))


def test_travel_by_the_clearance_plane() -> None:
    a, b = (0.0, 0.0, 10.0), (30.0, 40.0, 20.0)
    assert travel_path(a, b, clearance_z=50.0) == (a, (0.0, 0.0, 50.0), (30.0, 40.0, 50.0), b)
    assert travel_length(a, b, clearance_z=50.0) == pytest.approx(40.0 + 50.0 + 30.0)
    assert travel_length(a, b, clearance_z=50.0, direct=_always) == pytest.approx(
        math.dist(a, b))
    # a point above the plane: the travel rises no higher than needed
    assert travel_length(a, (0.0, 0.0, 60.0), clearance_z=50.0) == pytest.approx(50.0)


def test_directed_costs_use_exit_and_entry() -> None:
    stops = [Stop((0.0, 0.0, 0.0), (10.0, 0.0, 0.0)), Stop((11.0, 0.0, 0.0), (0.0, 1.0, 0.0))]
    costs = cost_matrix(stops, clearance_z=0.0, direct=_always)
    assert costs[1, 2] == pytest.approx(1.0)  # exit of 0 to entry of 1
    assert costs[2, 1] == pytest.approx(1.0)  # exit of 1 to entry of 0
    assert costs[0, 1] == costs[0, 2] == 0.0  # no start: free to begin anywhere
    tour = order_stops(stops, clearance_z=0.0, direct=_always)
    assert tour.length == pytest.approx(1.0)


def test_ties_go_to_the_lower_index_and_results_repeat() -> None:
    same = _flat([(5.0, 5.0)] * 4)
    tour = order_stops(same, clearance_z=0.0, direct=_always, start=ORIGIN)
    assert tour.order == (0, 1, 2, 3)
    stops = _flat([(float(k % 7), float(k * 3 % 11)) for k in range(12)])
    first = order_stops(stops, clearance_z=20.0, start=ORIGIN)
    assert first == order_stops(stops, clearance_z=20.0, start=ORIGIN)
    assert order_stops([], clearance_z=0.0).order == ()


coordinate = st.floats(-100.0, 100.0, allow_nan=False, allow_infinity=False)
point = st.tuples(coordinate, coordinate, st.floats(0.0, 40.0))


@settings(max_examples=examples(60))
@given(entries=st.lists(point, min_size=1, max_size=12), data=st.data(),
       straight=st.booleans(), with_start=st.booleans())
def test_improvement_never_worsens_nearest_neighbour(entries: list[tuple[float, float, float]],
                                                      data: st.DataObject, straight: bool,
                                                      with_start: bool) -> None:
    exits = data.draw(st.lists(point, min_size=len(entries), max_size=len(entries)))
    stops = [Stop(a, b) for a, b in zip(entries, exits, strict=True)]
    start = (0.0, 0.0, 50.0) if with_start else None
    direct = (lambda a, b: a[2] > 20.0 and b[2] > 20.0) if straight else None
    tour = order_stops(stops, clearance_z=50.0, direct=direct, start=start)
    assert sorted(tour.order) == list(range(len(stops)))
    assert tour.length <= tour.nearest_length + 1e-9
    costs = cost_matrix(stops, clearance_z=50.0, direct=direct, start=start)
    assert tour.length == pytest.approx(tour_length([0, *(k + 1 for k in tour.order)], costs))
