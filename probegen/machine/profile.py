"""Machine profiles: what a program needs to know about the machine and its probe.

A profile is a TOML file (``samples/machines/vmc-fanuc.toml`` is the reference).  All
lengths in the profile's ``units`` (mm or inch) are converted to mm on load; feeds are
per minute.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from probegen.constants import MM_PER_INCH
from probegen.files import Table, load_toml

if TYPE_CHECKING:
    from probegen.machine.calibration import ProbeCalibration

WORK_OFFSETS = ("G54", "G55", "G56", "G57", "G58", "G59")


@dataclass(frozen=True, slots=True)
class Probe:
    """The stylus and how it is driven.

    Attributes:
        ball_diameter: stylus ball diameter, mm.
        shank_diameter: stylus shank diameter, mm.
        length: from the ball centre to the probe body, mm (the shank that can touch).
        tool_number: tool (and length-offset) number of the probe.
        overtravel: how far past the nominal contact a probing move may go, mm.
        approach: the default distance off the surface where probing moves start, mm.
    """

    ball_diameter: float
    shank_diameter: float
    length: float
    tool_number: int
    overtravel: float
    approach: float

    @property
    def ball_radius(self) -> float:
        """Half the ball diameter, mm."""
        return self.ball_diameter / 2.0


@dataclass(frozen=True, slots=True)
class Feeds:
    """Feed rates in mm/min: rapid (estimates only), protected positioning, probing."""

    rapid: float
    position: float
    probe: float


@dataclass(frozen=True, slots=True)
class Controller:
    """Controller facts the dialect uses.

    Attributes:
        line_length: longest block the control accepts, characters.
        variable_base: first common variable probegen may use (it uses up to 100).
        probe_on: blocks that switch the probe on (e.g. ``M19`` orient + probe on M-code).
        probe_off: blocks that switch it off again.
        tool_change: whether the program calls the probe with ``T.. M6``.
        reset_codes: modal codes the header sets so that nothing is left to chance
            (plane, cutter and length compensation off, canned cycles off, feed per
            minute, rotation off...); drop a code the control lacks the option for.
    """

    line_length: int
    variable_base: int
    probe_on: tuple[str, ...]
    probe_off: tuple[str, ...]
    tool_change: bool
    reset_codes: tuple[str, ...]


DEFAULT_RESET = ("G17", "G40", "G49", "G80", "G94", "G69")


@dataclass(frozen=True, slots=True)
class StatedUncertainty:
    """The profile's stated contributions to measurement uncertainty (``[uncertainty]``),
    standard uncertainties in mm, None when the profile does not state one.

    Attributes:
        machine: the machine's length-measurement contribution (its geometry, scales,
            thermal state), counted once per characteristic.
        probe: the probing repeatability per touch.
    """

    machine: float | None = None
    probe: float | None = None


@dataclass(frozen=True, slots=True)
class MachineProfile:
    """A machine as probegen needs to know it."""

    name: str
    dialect: str
    units: str
    work_offset: str
    clearance_z: float
    margin: float
    probe: Probe
    feeds: Feeds
    controller: Controller
    source: str
    uncertainty: StatedUncertainty = StatedUncertainty()
    calibration: ProbeCalibration | None = None
    """The probe calibration the in-process actions are compiled with (the spec's
    ``[machine] calibration`` or ``compile --calibration``), or None: nominal radius."""


def load_profile(path: str | Path) -> MachineProfile:
    """Load and validate a machine profile; errors name the file and key path."""
    file = str(path)
    root = Table(load_toml(path), file, "")
    m = root.table("machine", required=True)
    units = m.get_str("units", "mm", choices=("mm", "inch")) or "mm"
    k = MM_PER_INCH if units == "inch" else 1.0
    profile = MachineProfile(
        name=m.get_str("name", required=True) or "",
        dialect=m.get_str("dialect", "fanuc") or "fanuc",
        units=units,
        work_offset=m.get_str("work_offset", "G54", choices=WORK_OFFSETS) or "G54",
        clearance_z=k * (m.get_float("clearance_z", required=True) or 0.0),
        margin=k * (m.get_float("margin", 0.5, positive=True) or 0.5),
        probe=_probe(root.table("probe", required=True), k),
        feeds=_feeds(root.table("feeds", required=True), k),
        controller=_controller(root.table("controller")),
        source=file,
        uncertainty=_uncertainty(root.table("uncertainty"), k),
    )
    m.done()
    root.done()
    return profile


def _probe(t: Table, k: float) -> Probe:
    ball = t.get_float("ball_diameter", required=True, positive=True) or 0.0
    probe = Probe(
        ball_diameter=k * ball,
        shank_diameter=k * (t.get_float("shank_diameter", required=True, positive=True) or 0),
        length=k * (t.get_float("length", required=True, positive=True) or 0.0),
        tool_number=t.get_int("tool_number", required=True, minimum=1, maximum=9999) or 1,
        overtravel=k * (t.get_float("overtravel", 2.0, positive=True) or 0.0),
        approach=k * (t.get_float("approach", 2.0, positive=True) or 0.0),
    )
    if probe.shank_diameter > probe.ball_diameter:
        raise t.fail("shank_diameter", f"at most ball_diameter ({ball:g})")
    t.done()
    return probe


def _feeds(t: Table, k: float) -> Feeds:
    feeds = Feeds(
        rapid=k * (t.get_float("rapid", required=True, positive=True) or 0.0),
        position=k * (t.get_float("position", required=True, positive=True) or 0.0),
        probe=k * (t.get_float("probe", required=True, positive=True) or 0.0),
    )
    t.done()
    return feeds


def _uncertainty(t: Table, k: float) -> StatedUncertainty:
    machine = t.get_float("machine", minimum=0.0, maximum=1.0)
    probe = t.get_float("probe", minimum=0.0, maximum=1.0)
    t.done()
    return StatedUncertainty(None if machine is None else k * machine,
                             None if probe is None else k * probe)


def _controller(t: Table) -> Controller:
    c = Controller(
        line_length=t.get_int("line_length", 80, minimum=40, maximum=256) or 80,
        variable_base=t.get_int("variable_base", 100, minimum=100, maximum=900) or 100,
        probe_on=t.get_str_list("probe_on", ()),
        probe_off=t.get_str_list("probe_off", ()),
        tool_change=t.get_bool("tool_change", True),
        reset_codes=t.get_str_list("reset_codes", DEFAULT_RESET),
    )
    t.done()
    return c
