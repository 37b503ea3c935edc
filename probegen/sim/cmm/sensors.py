"""Sensors, probing settings and the statements CMM software writes for itself.

* ``S(x)=SNSDEF/PROBE,FIXED|INDEX,CART|POL|VEC,...,diameter``: a touch probe whose ball
  diameter is the last value, whatever the form (a fixed probe, an indexed head by its
  tilt and rotation, a vector); a diameter of 0 stands for the machine's calibrated
  stylus.  An indexed form is noted: the machine tool's stylus is fixed and touches the
  same ball centres.  Another kind (``VIDEO``, ``LASER``, ``INFRED``, ``NONCON`` ...) is
  read and skipped with a note; selecting it is allowed, and the first ``MEAS`` under it
  is refused naming the ``SNSDEF`` (:class:`~probegen.sim.cmm.state.ForeignSensor`).
* ``SNSLCT/S(x)[,...]`` and ``SNSLCT/SA(x)[,...]``: as before, the extra values (a head
  index) noted.
* ``SNSET``: ``APPRCH``, ``RETRCT``, ``SEARCH``, ``DEPTH`` with a distance are executed;
  ``CLRSRF`` (``dist``, ``F(x),dist``, ``OFF``) and vision settings (``VA(x)``,
  ``VL(x)``, ``VF(x)``, ``VW(x)`` with their values) are left out with a note; any other
  word is not executed.
* :data:`NOTED`: statements always skipped with their reason, no flag needed.
"""

from __future__ import annotations

from probegen.dmis.reader import Label, Param, Statement, format_param
from probegen.sim.cmm.state import ForeignSensor, NotExecutable, SkipWithNote, VmState

SENSOR_MATCH = 1e-4
"""Largest difference, mm, between a program's sensor ball radius and the machine's."""

_CMM_SETTING = "a setting of the CMM software, nothing a touch depends on"
_VISION = "an optical/vision definition (WinWerth, Zeiss); the machine tool only touches"

NOTED: dict[str, str] = {
    "TECOMP": "temperature compensation of the CMM (the machine tool's own compensation "
              "is set on the control, not by this program)",
    "FLY": "fly mode (blended moves through approach points): a machine tool probes "
           "with a stop at each touch",
    "CRMODE": "carriage mode of a multi-carriage CMM: the machine tool has one spindle",
    "CRSLCT": "carriage selection of a multi-carriage CMM: the machine tool has one spindle",
    "CRGDEF": "carriage definition of a multi-carriage CMM: the machine tool has one spindle",
    "CZSLCT": "clearance zone of the CMM's automatic moves: the posted program moves as the "
              "program's GOTOs say, every move checked against the part model",
    "CZONE": "clearance zone of the CMM's automatic moves: the posted program moves as the "
             "program's GOTOs say, every move checked against the part model",
    "MODE": "CMM operating mode (MAN/PROG/AUTO): a machine tool runs the posted program "
            "automatically",
    "WKPLAN": "working plane of 2D features: every feature here carries its own vector",
    "DECPL": "decimal places of the CMM's report",
    "DMESWV": "version of the CMM software",
    "DMISMD": "module name of a DMIS macro file",
    "VFORM": "report format of the CMM",
    "PAUSE": "an operator pause on the CMM: the posted program runs through",
    "CALIB": "calibration on the CMM: the machine tool's stylus is calibrated on the "
             "machine (probegen calibrate, sphere test)",
    "ALGDEF": _VISION, "LITDEF": _VISION, "FILDEF": _VISION,
    "W3D": _CMM_SETTING + " (WinWerth)", "POINTDIST": _CMM_SETTING + " (WinWerth)",
    "PIEZOWFP": _CMM_SETTING + " (WinWerth)", "SCANFILTER": _CMM_SETTING + " (WinWerth)",
    "SPLINESCAN3D": "scanning parameters (WinWerth): the machine tool touches the PTMEAS "
                    "points one by one",
    "GEOALG": "fit algorithm of the CMM: features are fitted least squares",
}
"""Major word -> why it is left out (a ``SKIPPED`` comment and a line in the report)."""

_VISION_LABELS = frozenset({"VA", "VL", "VF", "VW"})
_SNSET = {"APPRCH": "approach", "RETRCT": "retract", "SEARCH": "search", "DEPTH": "depth"}


def do_noted(state: VmState, st: Statement) -> None:
    """A statement of :data:`NOTED`: left out with its reason."""
    if st.major == "GEOALG" and any(p in ("MINMAX", "MAXINS", "MININS") for p in st.params):
        raise NotExecutable("GEOALG: only least-squares fits (LSTSQR, DEFALT) are executed")
    raise SkipWithNote(NOTED[st.major])


def do_snsdef(state: VmState, st: Statement) -> None:
    """``S(x)=SNSDEF/...`` (module docstring)."""
    if st.label is None or st.label.kind != "S":
        raise state.error("SNSDEF must define a sensor: S(name)=SNSDEF/...")
    kind = st.params[0] if st.params else None
    if kind != "PROBE":
        name = format_param(kind) if kind is not None else "no kind"
        state.foreign[st.label.name] = ForeignSensor(st.line, st.text, name)
        raise SkipWithNote(f"a {name} sensor is not a touch probe: a MEAS with it is "
                           "refused")
    diameter = state.length(st.params[-1], "SNSDEF diameter")
    if diameter < 0.0:
        raise state.error(f"SNSDEF: the ball diameter must be >= 0, found {diameter}")
    state.sensors[st.label.name] = diameter
    state.foreign.pop(st.label.name, None)
    if "INDEX" in st.params[1:3] and not _straight_down(st.params):
        state.notes.append((st.line, st.text, "an indexed probe head: the machine tool's "
                            "stylus is fixed and touches the same ball centres"))


def _straight_down(params: tuple[object, ...]) -> bool:
    """Whether an indexed ``SNSDEF/PROBE,INDEX,POL,a,b,...`` stands at A0 B0 (the stylus
    straight down, as a machine tool's spindle probe stands: nothing to note)."""
    return (len(params) > 4 and params[2] == "POL"
            and all(isinstance(a, (int, float)) and a == 0 for a in params[3:5]))


def do_snslct(state: VmState, st: Statement) -> None:
    """``SNSLCT/S(x)``: compensate with that sensor's ball from now on, which must be the
    machine's; ``SNSLCT/SA(x)`` and a zero-diameter sensor select the machine's stylus;
    a sensor that is not a touch probe is selected, and refused at its first MEAS."""
    if not st.params:
        raise state.error("SNSLCT expects S(name) or SA(name)")
    ref = st.params[0]
    machine = float(state.cmm.ball_radius)
    if len(st.params) > 1:
        state.notes.append((st.line, st.text, "the head orientation "
                            f"{', '.join(format_param(p) for p in st.params[1:])}: the "
                            "machine tool's stylus is fixed and touches the same ball "
                            "centres"))
    state.selected_foreign = None
    if isinstance(ref, Label) and ref.kind == "SA":
        state.use_machine_stylus(st, f"{ref} is a calibrated sensor")
        return
    name = state.label(ref, ("S",), "SNSLCT").name
    if name in state.foreign:
        state.selected_foreign = state.foreign[name]
        return
    if name not in state.sensors:
        state.check_skipped("S", name)
        raise state.error(f"S({name}) is not defined")
    diameter = state.sensors[name]
    if diameter == 0.0:
        state.use_machine_stylus(st, f"S({name}) has a zero ball diameter")
        return
    if abs(diameter / 2.0 - machine) > SENSOR_MATCH:
        raise NotExecutable(f"the sensor's ball is D{diameter:g} mm, the machine's stylus "
                            f"D{2 * machine:g} mm (give a machine profile with this stylus, "
                            "or skip the SNSLCT to compensate with the machine's)")
    state.radius = diameter / 2.0


def check_touch_sensor(state: VmState) -> None:
    """Refuse a MEAS under a selected sensor that is not a touch probe."""
    sensor = state.selected_foreign
    if sensor is not None:
        raise NotExecutable(f"the selected sensor is a {sensor.kind} sensor, not a touch "
                            f"probe (SNSDEF at line {sensor.line}: {sensor.text})")


def do_snset(state: VmState, st: Statement) -> None:
    """``SNSET/word,value[,word,value...]`` (module docstring)."""
    params = list(st.params)
    if not params:
        raise state.error("SNSET expects APPRCH|RETRCT|SEARCH|DEPTH, distance")
    ignored: list[str] = []
    executed = 0
    k = 0
    while k < len(params):
        word, k = params[k], k + 1
        values: list[Param] = []
        while k < len(params) and not _setting_word(params[k]):
            values.append(params[k])
            k += 1
        if isinstance(word, str) and word in _SNSET:
            if len(values) != 1:
                raise state.error(f"SNSET/{word}: expected one distance")
            distance = state.length(values[0], f"SNSET {word}")
            if distance < 0.0:
                raise state.error(f"SNSET/{word}: expected a distance >= 0, found {distance}")
            setattr(state, _SNSET[word], distance)
            executed += 1
        elif word == "CLRSRF" or (isinstance(word, Label) and word.kind in _VISION_LABELS):
            ignored.append(format_param(word))
        else:
            raise NotExecutable(f"SNSET/{format_param(word)}: executed are "
                                f"{', '.join(_SNSET)}; CLRSRF and VA/VL/VF/VW are noted")
    if ignored:
        reason = (f"SNSET {', '.join(ignored)}: the CMM's clearance surface or vision "
                  "settings; the posted program moves as the program's GOTOs say")
        if not executed:
            raise SkipWithNote(reason)
        state.notes.append((st.line, st.text, reason))


def _setting_word(param: Param) -> bool:
    return (isinstance(param, str) and param in (*_SNSET, "CLRSRF")) or (
        isinstance(param, Label) and param.kind in _VISION_LABELS)
