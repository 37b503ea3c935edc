"""Machine profiles: what a program needs to know about the machine and its probe.

A profile is a TOML file (``samples/machines/vmc-fanuc.toml`` is the reference).  All
lengths in the profile's ``units`` (mm or inch) are converted to mm on load; feeds are
per minute.  The stylus rack, a CMM's indexable head, a five-axis machine's tilted plane
and named setups (``[[probe.stylus]]``, ``[head]``, ``[tilt]``, ``[[setup]]``) are read
and checked by :mod:`probegen.machine.rack`, whose records this module re-exports.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from probegen.constants import MM_PER_INCH
from probegen.errors import SpecError, did_you_mean
from probegen.files import Table, load_toml
from probegen.machine.rack import (
    Head,
    NamedSetup,
    Stylus,
    Tilt,
    probe_stylus,
    read_head,
    read_rack,
    read_setups,
    read_tilt,
)

if TYPE_CHECKING:
    from probegen.machine.calibration import ProbeCalibration

WORK_OFFSETS = ("G54", "G55", "G56", "G57", "G58", "G59")
"""The six standard work offsets every control has."""
EXTENDED_OFFSET = re.compile(r"(G54\.1|G154) P([1-9][0-9]{0,2})\Z")
"""An extended work offset: ``G54.1 Pn`` (Fanuc, P1-P300) or ``G154 Pn`` (Haas, P1-P99)."""
EXTENDED_MAX = {"G54.1": 300, "G154": 99}
"""Highest P of each extended work offset code (Fanuc: 48 standard, 300 with the
300-pair option; Haas: 99)."""
EXTENDED_CODE = {"fanuc": "G54.1", "haas": "G154"}
"""The extended work offset code of each dialect that has them."""

OPTIONS: dict[str, str] = {
    "G68": "coordinate rotation G68/G69",
    "G68.2": "tilted working plane G68.2/G69",
    "G15": "polar coordinate command G15/G16",
    "G50.1": "programmable mirror image G50.1/G51.1 (Haas G100/G101)",
    "G54.1": "additional work coordinate systems G54.1 Pn (Fanuc)",
    "G154": "additional work coordinate systems G154 Pn (Haas)",
    "#3004": "macro control of single block and feed override (#3003/#3004)",
}
"""Controller options a program may need, by the G code (or variable) that names them in
``[controller] options``, with what they are."""
DEFAULT_OPTIONS: dict[str, tuple[str, ...]] = {
    "fanuc": ("G68", "#3004"),
    "haas": ("G68", "G50.1", "G154"),
}
"""Options of a profile that does not list them, by dialect (others: none): what every
control of the family has as standard (see ``docs/spec.md``)."""


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
        body_diameter: the probe body above the stylus (and the head or spindle nose it
            hangs from, as far as ``body_length`` reaches), mm: the collision check's
            cylinder on top of every stylus, so that a ball deeper than its stylus is
            long never takes the body into the part (``[probe] body_diameter``; 0: none
            stated, no body checked).
        body_length: that cylinder's length from the stylus's end, mm.
    """

    ball_diameter: float
    shank_diameter: float
    length: float
    tool_number: int
    overtravel: float
    approach: float
    body_diameter: float = 0.0
    body_length: float = 0.0

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
            minute, rotation off...); the dialect writes a code that cancels an optional
            mode (G69, G15, G50.1) only when ``options`` declares the option
            (``dialects.base.RESET_NEEDS``).
        program_numbers: the O numbers probegen may give a program, ``(first, last)``
            (``[controller] program_numbers``; default :func:`default_program_numbers`).
        options: the controller options the machine has (keys of :data:`OPTIONS`;
            default :data:`DEFAULT_OPTIONS` of the dialect).
        program_memory: the part-program memory free for probegen's programs, bytes:
            every file one ``compile`` writes (the program, or the driver and its parts,
            and the macro library) must fit in it together (0: not checked).
        program_size: the largest single program the control takes, bytes (the memory
            left for one program, or the control's limit for a program it stores and
            edits); a larger program is split into a driver and parts (0: the same as
            ``program_memory``).
        common_variables: the common variables the control has, ``(first, last)``
            ranges (``[controller] common_variables``; default
            :data:`DEFAULT_COMMON_VARIABLES` of the dialect; empty: not checked).
        alarm_text_length: the longest macro alarm message the control shows whole,
            characters (0: the dialect's, 26 on Fanuc and Haas).
        library_number: the O number of the first subprogram of probegen's macro
            library (``[controller] library_number``, default 8000; the library takes
            the numbers from it up, each checked against ``program_numbers``).
    """

    line_length: int
    variable_base: int
    probe_on: tuple[str, ...]
    probe_off: tuple[str, ...]
    tool_change: bool
    reset_codes: tuple[str, ...]
    program_numbers: tuple[int, int] = (1, 8999)
    options: tuple[str, ...] = ()
    program_memory: int = 0
    library_number: int = 8000
    program_size: int = 0
    common_variables: tuple[tuple[int, int], ...] = ()
    alarm_text_length: int = 0

    def has(self, option: str) -> bool:
        """Whether the profile declares ``option`` (a key of :data:`OPTIONS`)."""
        return option in self.options


DEFAULT_COMMON_VARIABLES: dict[str, tuple[tuple[int, int], ...]] = {
    "fanuc": ((100, 199), (500, 999)),
    "haas": ((100, 199), (500, 549), (600, 699), (800, 999)),
}
"""Common variables of a profile that does not list them, by dialect (others: not
checked): a Fanuc 0i has #100-#199 (cleared at power-off) and #500-#999 (kept); the
option "addition of custom macro common variables" gives #100-#499, which a profile
declares with ``common_variables = [[100, 499], [500, 999]]``.  Haas: #100-#199 and
#500-#999 less #550-#599 (probe calibration, as ``dialects/haas.py`` refuses them) and
#700-#799 (#700-#749 hidden, for the control; the rest left out for want of a manual)."""
VARIABLE_MAX = 99999
"""Highest variable number a ``common_variables`` range may name."""
DEFAULT_RESET = ("G17", "G40", "G49", "G80", "G94", "G69")
PROTECTED = (9000, 9999)
"""Program numbers Fanuc controls protect (parameter NE9) and Haas controls lock
(setting 23, 9xxx programs edit lock): a shop's own macros and the probe maker's cycles
live there, so probegen stays out unless the profile's ``program_numbers`` lets it in."""
PROGRAM_NUMBER_MAX = 9999
"""Highest program number of a spec (four digits, which every control reads)."""


def default_program_numbers(dialect: str) -> tuple[int, int]:
    """The program numbers a profile without ``program_numbers`` allows: below
    :data:`PROTECTED` for a Fanuc or Haas machine, any for the others (LinuxCNC and DMIS
    use the number as a name only)."""
    return (1, PROTECTED[0] - 1) if dialect in ("fanuc", "haas") else (1, PROGRAM_NUMBER_MAX)


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
    rack: tuple[Stylus, ...] = ()
    """The styli a program may take (issue 17), ``[[probe.stylus]]``; empty: only the
    ``[probe]`` stylus."""
    head: Head | None = None
    """A CMM's indexable head, or None."""
    tilt: Tilt | None = None
    """A five-axis machine's tilted work plane, or None."""
    setups: tuple[NamedSetup, ...] = ()
    """Named setups (the part turned), or none."""

    @property
    def stylus(self) -> Stylus:
        """The stylus of ``[probe]`` (the one in the spindle or head when a program
        starts): the rack's entry with its ball, shank and length and its tool number
        (or none, on a CMM), else one labelled ``PRB<tool number>``."""
        p = self.probe
        return probe_stylus(self.rack, p.tool_number, p.ball_diameter, p.shank_diameter,
                            p.length)

    def styli(self) -> tuple[Stylus, ...]:
        """Every stylus a program may take: the ``[probe]`` stylus first, then the rack's
        others in profile order."""
        first = self.stylus
        return (first, *(s for s in self.rack if s != first))

    def with_stylus(self, s: Stylus) -> MachineProfile:
        """This profile with ``s`` as its probe's stylus (approach, overtravel, feeds
        and everything else kept): how a feature is planned with another stylus.  A
        calibration is switched to the stylus's entry (its vertical one; the orientation
        planner asks for another with ``calibration.entry_for``).

        Raises:
            SpecError: the profile has a calibration without an entry for ``s``, or one
                of another ball (a program compiled with a calibration is calibrated for
                every stylus it takes).
        """
        from probegen.machine.calibration import stylus_calibration

        probe = replace(self.probe, ball_diameter=s.ball_diameter,
                        shank_diameter=s.shank_diameter, length=s.length,
                        tool_number=s.tool_number)
        cal = self.calibration
        if cal is not None:
            cal = stylus_calibration(cal, s.label, s.ball_radius, "",
                                     f"probe calibration {cal.fingerprint}")
        return replace(self, probe=probe, calibration=cal)

    def check_program_number(self, number: int, where: str) -> None:
        """Refuse a program number outside ``controller.program_numbers``.

        Args:
            number: the O number a program is to get.
            where: what set it, for the message (``spec.toml: program.number``).

        Raises:
            SpecError: ``number`` is outside the range; the message names both keys
                and, for O9000-O9999, why they are kept out.
        """
        first, last = self.controller.program_numbers
        if first <= number <= last:
            return
        why = (f": O{PROTECTED[0]}-O{PROTECTED[1]} are protected on Fanuc and Haas controls "
               "(editing locked), the shop's own macros live there"
               if PROTECTED[0] <= number <= PROTECTED[1] else "")
        raise SpecError(f"{where}: expected a program number in O{first}-O{last} (the "
                        f"machine's range, {self.source}: controller.program_numbers), found "
                        f"{number}{why}; to use it, set [controller] program_numbers = "
                        "[first, last] in the machine profile to a range that holds it")

    def require(self, option: str, where: str, what: str) -> None:
        """Refuse ``what`` (set at ``where``) when the profile lacks ``option``.

        Raises:
            SpecError: names the option, what needs it and the profile key.
        """
        if self.controller.has(option):
            return
        raise SpecError(f"{where}: {what} needs the controller option {option} "
                        f"({OPTIONS[option]}), which {self.source} does not declare; add "
                        f"{option!r} to [controller] options if the control has it")


def load_profile(path: str | Path) -> MachineProfile:
    """Load and validate a machine profile; errors name the file and key path."""
    file = str(path)
    root = Table(load_toml(path), file, "")
    m = root.table("machine", required=True)
    units = m.get_str("units", "mm", choices=("mm", "inch")) or "mm"
    k = MM_PER_INCH if units == "inch" else 1.0
    dialect = m.get_str("dialect", "fanuc") or "fanuc"
    probe_table = root.table("probe", required=True)
    probe = _probe(probe_table, k)
    controller = _controller(root.table("controller"), dialect)
    first = (probe.tool_number, probe.ball_diameter, probe.shank_diameter, probe.length)
    profile = MachineProfile(
        name=m.get_str("name", required=True) or "",
        dialect=dialect,
        units=units,
        work_offset=_work_offset(m, dialect),
        clearance_z=k * (m.get_float("clearance_z", required=True) or 0.0),
        margin=k * (m.get_float("margin", 0.5, positive=True) or 0.5),
        probe=probe,
        feeds=_feeds(root.table("feeds", required=True), k),
        controller=controller,
        source=file,
        uncertainty=_uncertainty(root.table("uncertainty"), k),
        rack=read_rack(probe_table, k, dialect, first, controller.tool_change),
        head=read_head(root, k, dialect),
        tilt=read_tilt(root, dialect),
        setups=read_setups(root, k),
    )
    probe_table.done()
    m.done()
    root.done()
    if EXTENDED_OFFSET.match(profile.work_offset):
        profile.require(profile.work_offset.split()[0], f"{file}: machine.work_offset",
                        f"work offset {profile.work_offset}")
    if profile.tilt is not None and profile.tilt.command == "G68.2":
        profile.require("G68.2", root.where("tilt.command"), "[tilt] command = \"G68.2\"")
    return profile


def _work_offset(m: Table, dialect: str) -> str:
    """``[machine] work_offset``: G54-G59, or ``G54.1 Pn`` (Fanuc) / ``G154 Pn`` (Haas)."""
    name = m.get_str("work_offset", "G54") or "G54"
    return check_work_offset(name, dialect, m.where("work_offset"))


def check_work_offset(name: str, dialect: str, where: str) -> str:
    """``name`` if it is a work offset ``dialect`` can select.

    Raises:
        SpecError: not G54-G59 nor an extended offset of the dialect (``G54.1 Pn`` on
            Fanuc, ``G154 Pn`` on Haas), or P out of range.
    """
    if name in WORK_OFFSETS:
        return name
    extended = EXTENDED_CODE.get(dialect, "")
    found = EXTENDED_OFFSET.match(name)
    if not extended:
        hint = f" (dialect {dialect!r} has no extended work offsets)"
    else:
        hint = f" or \"{extended} Pn\" (n 1-{EXTENDED_MAX[extended]})"
        if found and found[1] == extended and int(found[2]) <= EXTENDED_MAX[extended]:
            return name
    raise SpecError(f"{where}: expected G54 to G59{hint}, found {name!r}")


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
    return _probe_body(t, k, probe)


def _probe_body(t: Table, k: float, probe: Probe) -> Probe:
    """``probe`` with its body: ``body_diameter`` and ``body_length`` (mm, both or
    neither); without them no body is checked (the profiles written before the keys)."""
    body = t.get_float("body_diameter", positive=True)
    long = t.get_float("body_length", positive=True)
    if (body is None) != (long is None):
        given, missing = ("body_diameter", "body_length") if long is None else \
            ("body_length", "body_diameter")
        raise t.fail(missing, f"a {missing} with {given} (the probe body is a cylinder: "
                              "its diameter and its length from the stylus's end)")
    if body is None or long is None:
        return probe
    probe = replace(probe, body_diameter=k * body, body_length=k * long)
    if probe.body_diameter < probe.shank_diameter:
        raise t.fail("body_diameter", f"at least shank_diameter ({probe.shank_diameter:g})")
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


def _controller(t: Table, dialect: str) -> Controller:
    c = Controller(
        line_length=t.get_int("line_length", 80, minimum=40, maximum=256) or 80,
        variable_base=t.get_int("variable_base", 100, minimum=100, maximum=900) or 100,
        probe_on=t.get_str_list("probe_on", ()),
        probe_off=t.get_str_list("probe_off", ()),
        tool_change=t.get_bool("tool_change", True),
        reset_codes=t.get_str_list("reset_codes", DEFAULT_RESET),
        program_numbers=_program_numbers(t, dialect),
        options=_options(t, dialect),
        program_memory=t.get_int("program_memory", 0, minimum=0) or 0,
        library_number=t.get_int("library_number", 8000, minimum=1,
                                 maximum=PROGRAM_NUMBER_MAX) or 8000,
        program_size=t.get_int("program_size", 0, minimum=0) or 0,
        common_variables=_common_variables(t, dialect),
        alarm_text_length=t.get_int("alarm_text_length", 0, minimum=12, maximum=255) or 0,
    )
    if c.program_memory and c.program_size > c.program_memory:
        raise t.fail("program_size", f"at most program_memory ({c.program_memory}): one "
                                     "program cannot be larger than the memory all share")

    t.done()
    return c


def _program_numbers(t: Table, dialect: str) -> tuple[int, int]:
    """``program_numbers = [first, last]``: whole numbers, 1 <= first <= last <= 9999."""
    value = t.get_any("program_numbers")
    if value is None:
        return default_program_numbers(dialect)
    ok = (isinstance(value, list) and len(value) == 2
          and all(isinstance(v, int) and not isinstance(v, bool) for v in value)
          and 1 <= value[0] <= value[1] <= PROGRAM_NUMBER_MAX)
    if not ok:
        raise t.fail("program_numbers", f"[first, last] program numbers with "
                                        f"1 <= first <= last <= {PROGRAM_NUMBER_MAX}")
    return value[0], value[1]


def _common_variables(t: Table, dialect: str) -> tuple[tuple[int, int], ...]:
    """``common_variables = [[first, last], ...]``: at least one range of whole numbers
    with 1 <= first <= last <= :data:`VARIABLE_MAX`; the dialect's default when absent."""
    value = t.get_any("common_variables")
    if value is None:
        return DEFAULT_COMMON_VARIABLES.get(dialect, ())
    ok = isinstance(value, list) and len(value) > 0 and all(
        isinstance(r, list) and len(r) == 2
        and all(isinstance(v, int) and not isinstance(v, bool) for v in r)
        and 1 <= r[0] <= r[1] <= VARIABLE_MAX for r in value)
    if not ok:
        raise t.fail("common_variables", "a non-empty array of [first, last] variable "
                                         f"ranges with 1 <= first <= last <= {VARIABLE_MAX}")
    return tuple(sorted((r[0], r[1]) for r in value))


def _options(t: Table, dialect: str) -> tuple[str, ...]:
    """``options = [...]``: keys of :data:`OPTIONS`, sorted; the dialect's default when
    absent."""
    if not t.has("options"):
        return DEFAULT_OPTIONS.get(dialect, ())
    names = t.get_str_list("options")
    for name in names:
        if name not in OPTIONS:
            raise t.fail("options", "an array of controller options out of "
                                    f"{', '.join(OPTIONS)}{did_you_mean(name, OPTIONS)}")
    return tuple(sorted(set(names)))
