"""The spec of a rotary-axis test (method M4): what to measure and with which machine.

A TOML file (``samples/rotary/m4.toml`` and ``samples/rotary/pivot.toml``)::

    [machine]
    profile = "../machines/vmc-fanuc.toml"   # probe, feeds, controller (Fanuc dialect)
    clearance_z = 100.0                        # work Z of the ball at B = 0 where B, C turn
    pivot_length = 150.0                       # l1: B axis to the ball centre at B = 0, mm

    [program]
    number = 4001
    name = "M4 B AXIS"

    [sphere]                                   # the reference sphere (or round workpiece)
    centre = [0.0, 0.0, 30.0]                  # on the C table, work coordinates at C = 0
    diameter = 25.0

    [test]
    kind = "m4"                                # "m4": B ±90° touches; "pivot": calibration
    radius_points = 8                          # m4: equator touches for the radius at B = 0
    repeats = 3                                # m4: touches at each of B +90° and -90°
    c_positions = [0, 60, 120, 180, 240, 300]  # pivot: C stations at B = 0, deg
    b_positions = [-90, -45, 0, 45, 90]        # pivot: B stations at C = 0, deg (with 0)
    points = 9                                 # pivot: touches per station (cap layout)
    max_polar_angle = 50.0                     # pivot: cap half-angle around the stylus, deg

Lengths are mm, angles degrees.  The rotary axes turn only with the ball at the
clearance plane, which must lie above the sphere by the ball radius and the margin, and
``|B| ≤ 90°``: every stylus point then stays above the ball centre, so no pose the
axes pass through can reach the sphere, whatever position they start from.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from probegen.errors import SpecError
from probegen.files import Table, load_toml
from probegen.machine.profile import MachineProfile
from probegen.spec.model import _machine, _program_name

Vec3 = tuple[float, float, float]
KINDS = ("m4", "pivot")
MAX_TILT = 90.0
"""Largest head tilt a test may use, deg (see the module docstring)."""


@dataclass(frozen=True, slots=True)
class RotarySpec:
    """A validated rotary-axis test spec (see the module docstring for each key).

    Attributes:
        source: the spec file.
        kind: ``"m4"`` or ``"pivot"``.
        machine: the machine profile (probe, feeds, controller).
        clearance_z: work Z of the ball centre at B = 0 where the rotary axes turn, mm.
        pivot_length: B axis to the ball centre at B = 0, mm (M4's ``l1``).
        program_number: O-number.
        program_name: short upper-case name.
        sphere_centre: nominal sphere centre on the table (work frame at C = 0), mm.
        sphere_diameter: calibrated sphere diameter, mm.
        radius_points: M4: touches on the equator at B = 0.
        repeats: M4: touches at each of B = +90° and -90°.
        c_positions: pivot: C stations (B = 0), deg.
        b_positions: pivot: B stations (C = 0), deg.
        points: pivot: touches per station.
        max_polar_angle: pivot: cap half-angle around the stylus direction, deg.
    """

    source: str
    kind: str
    machine: MachineProfile
    clearance_z: float
    pivot_length: float
    program_number: int
    program_name: str
    sphere_centre: Vec3
    sphere_diameter: float
    radius_points: int = 8
    repeats: int = 3
    c_positions: tuple[float, ...] = (0.0, 60.0, 120.0, 180.0, 240.0, 300.0)
    b_positions: tuple[float, ...] = (-90.0, -45.0, 0.0, 45.0, 90.0)
    points: int = 9
    max_polar_angle: float = 50.0

    @property
    def sphere_radius(self) -> float:
        """Half the sphere diameter, mm."""
        return self.sphere_diameter / 2.0


def load_rotary_spec(path: str | Path) -> RotarySpec:
    """Load and validate a rotary-axis test spec.

    Raises:
        SpecError: a missing or malformed key, or values the method rules out; the
            message names the file and key path.
    """
    file = str(path)
    root = Table(load_toml(path), file, "")
    m = root.table("machine", required=True)
    machine = _machine(m, Path(path).parent)
    if machine.units != "mm":
        raise m.fail("profile", "a profile in mm (rotary tests are planned in mm)")
    clearance = m.get_float("clearance_z", machine.clearance_z)
    pivot = m.get_float("pivot_length", required=True, positive=True) or 0.0
    m.done()
    prog = root.table("program")
    number = prog.get_int("number", 4001, minimum=1, maximum=9999) or 4001
    name = _program_name(prog)
    prog.done()
    sphere = root.table("sphere", required=True)
    centre = sphere.get_vec("centre")
    if centre is None:
        raise sphere.fail("centre", "[x, y, z] in mm")
    diameter = sphere.get_float("diameter", required=True, positive=True) or 0.0
    sphere.done()
    t = root.table("test", required=True)
    kind = t.get_str("kind", required=True, choices=KINDS) or "m4"
    spec = RotarySpec(
        source=file, kind=kind, machine=machine,
        clearance_z=clearance if clearance is not None else machine.clearance_z,
        pivot_length=pivot, program_number=number, program_name=name,
        sphere_centre=(centre[0], centre[1], centre[2]), sphere_diameter=diameter,
        **_test_values(t, kind),
    )
    t.done()
    root.done()
    if kind == "m4" and (spec.sphere_centre[0], spec.sphere_centre[1]) != (0.0, 0.0):
        raise sphere.fail("centre", "the sphere on the C axis for the m4 test: [0, 0, z]")
    _check_clearance(spec, root)
    return spec


def _test_values(t: Table, kind: str) -> dict[str, Any]:
    """The ``[test]`` keys of ``kind`` (the other kind's keys are refused as unknown)."""
    if kind == "m4":
        return {"radius_points": t.get_int("radius_points", 8, minimum=4, maximum=36) or 8,
                "repeats": t.get_int("repeats", 3, minimum=1, maximum=20) or 3}
    c = _angles(t, "c_positions", (0.0, 60.0, 120.0, 180.0, 240.0, 300.0), 3, 360.0)
    b = _angles(t, "b_positions", (-90.0, -45.0, 0.0, 45.0, 90.0), 3, MAX_TILT)
    if 0.0 not in b:
        raise t.fail("b_positions", "B = 0 among the stations (it fixes the sphere centre)")
    return {"c_positions": c, "b_positions": b,
            "points": t.get_int("points", 9, minimum=4, maximum=50) or 9,
            "max_polar_angle": t.get_float("max_polar_angle", 50.0, minimum=20.0,
                                           maximum=80.0) or 50.0}


def _angles(t: Table, key: str, default: tuple[float, ...], minimum: int,
            limit: float) -> tuple[float, ...]:
    """A list of at least ``minimum`` distinct angles, deg, in ``[-limit, limit]``."""
    if not t.has(key):
        return default
    value = t.data[key]
    good = isinstance(value, list) and all(
        isinstance(v, int | float) and not isinstance(v, bool) and -limit <= v <= limit
        for v in value)
    if not good or len(set(value)) != len(value) or len(value) < minimum:
        raise t.fail(key, f"at least {minimum} distinct angles in degrees, each within "
                          f"[-{limit:g}, {limit:g}]")
    return tuple(float(v) for v in value)


def _check_clearance(spec: RotarySpec, root: Table) -> None:
    """The clearance plane must clear the sphere's top by the ball radius and margin."""
    top = (spec.sphere_centre[2] + spec.sphere_radius + spec.machine.probe.ball_radius
           + spec.machine.margin)
    if spec.clearance_z < top:
        raise SpecError(f"{root.where('machine.clearance_z')}: expected at least {top:.3f} mm "
                        f"(the sphere top + ball radius + margin: the rotary axes turn at the "
                        f"clearance plane), found {spec.clearance_z:g}")
