"""Sensors, probing settings and the statements CMM software writes for itself.

Head angles (issue 17; the DMIS dialect writes the same): ``SNSDEF/PROBE,INDEX,POL,A,B,
i,j,k,length,diameter`` with the mount vector ``i,j,k`` vertical (``0,0,-1`` as
probegen writes it, or ``0,0,1``).  ``A`` tilts the stylus from straight down (A0)
towards the horizontal (A90) and beyond; ``B`` turns it about the vertical,
counter-clockwise seen from above (right hand about +Z).  The stylus direction, from
the head to the ball, machine coordinates::

    d(A, B) = Rz(B) · (0, -sin A, -cos A) = (sin A sin B, -sin A cos B, -cos A)

so A90B0 points the ball to -Y, A90B90 to +X, A90B-90 to -X; the probe's approach axis
(frame +Z of ``ir.Orient``, from the ball towards the head) is ``-d``.  DMIS 5.3 names
the two angles (tilt, then rotation) without fixing which way B turns in the text we
could find; this is the convention of this project (docs/sim.md).

* ``S(x)=SNSDEF/PROBE,FIXED|INDEX,CART|POL|VEC,...,diameter``: a touch probe whose ball
  diameter is the last value, whatever the form (a fixed probe, an indexed head by its
  tilt and rotation, a vector); a diameter of 0 stands for the machine's calibrated
  stylus.  On a machine tool (a ``Cmm`` without ``select_sensor``) an indexed form is
  noted: the machine tool's stylus is fixed and touches the same ball centres.  On a
  CMM with a head and a rack of styli (a ``Cmm`` whose ``select_sensor`` is set)
  ``SNSLCT/S(x)`` takes the rack's stylus of the sensor's ball and turns the head to
  the sensor's direction (``POL`` angles above; a ``CART`` or ``VEC`` sensor must be
  vertical); its ball is touched and compensated with from then on.  Another kind
  (``VIDEO``, ``LASER``, ``INFRED``, ``NONCON`` ...) is read and skipped with a note;
  selecting it is allowed, and the first ``MEAS`` under it is refused naming the
  ``SNSDEF`` (:class:`~probegen.sim.cmm.state.ForeignSensor`).
* ``SNSLCT/S(x)[,...]`` and ``SNSLCT/SA(x)[,...]``: as before, the extra values (a head
  index) noted on a machine tool; on a CMM with a head they are not executed (the head
  turns to the angles of the sensor's ``SNSDEF``).
* ``SNSET``: ``APPRCH``, ``RETRCT``, ``SEARCH``, ``DEPTH`` with a distance are executed;
  ``CLRSRF`` (``dist``, ``F(x),dist``, ``OFF``) and vision settings (``VA(x)``,
  ``VL(x)``, ``VF(x)``, ``VW(x)`` with their values) are left out with a note; any other
  word is not executed.
* :data:`NOTED`: statements always skipped with their reason, no flag needed.
"""

from __future__ import annotations

import math

from probegen.dmis.reader import Label, Param, Statement, format_param
from probegen.ir.frames import head_approach
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
    state.sensor_axes[st.label.name] = _stylus_axis(state, st.params)
    length = st.params[-2] if len(st.params) > 2 else None
    state.sensor_lengths[st.label.name] = (
        state.length(length, "SNSDEF length") if isinstance(length, int | float) else None)
    state.foreign.pop(st.label.name, None)
    if _head(state) is None and "INDEX" in st.params[1:3] and not _straight_down(st.params):
        state.notes.append((st.line, st.text, "an indexed probe head: the machine tool's "
                            "stylus is fixed and touches the same ball centres"))


Axis = tuple[tuple[float, float, float], tuple[float, float] | None]
"""A sensor's stylus axis (ball towards head, unit, machine frame) and its head angles
``(A, B)`` in degrees (None for a fixed vertical sensor)."""


def head_direction(a: float, b: float) -> tuple[float, float, float]:
    """The stylus direction (head to ball, unit) at head angles ``A``, ``B`` (deg), see
    the module docstring."""
    x, y, z = head_approach(a, b)  # the approach is from the ball towards the head
    return (-x + 0.0, -y + 0.0, -z + 0.0)


def _stylus_axis(state: VmState, params: tuple[Param, ...]) -> Axis | None:
    """The axis from the ball towards the head of a ``SNSDEF/PROBE`` (machine frame) and
    the head angles ``(A, B)`` (deg) of a ``POL`` form, or None when the form does not
    say it in a way the virtual CMM executes."""
    numbers = [float(p) if isinstance(p, (int, float)) else None for p in params]
    if len(params) > 2 and params[2] == "POL":
        if len(params) < 8 or None in numbers[3:8]:
            return None
        mount = numbers[5:8]
        if mount[0] == 0.0 and mount[1] == 0.0 and mount[2] != 0.0:
            a, b = (float(v) * state.angle_scale * 180.0 / math.pi  # type: ignore[arg-type]
                    for v in numbers[3:5])
            d = head_direction(a, b)
            return (-d[0] + 0.0, -d[1] + 0.0, -d[2] + 0.0), (a, b)
        return None
    vectors = numbers[3:9]  # CART: tip offset x,y,z and i,j,k; VEC: two vectors
    if len(vectors) < 6 or None in vectors:
        return None
    off_vertical = any(v != 0.0 for k, v in enumerate(vectors) if k % 3 != 2)
    return None if off_vertical else ((0.0, 0.0, 1.0), None)


def _head(state: VmState) -> object | None:
    """The CMM's ``select_sensor`` (an indexable head with a rack of styli), or None."""
    return getattr(state.cmm, "select_sensor", None)


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
    if len(st.params) > 1 and _head(state) is not None:
        raise NotExecutable("SNSLCT with head angles: the virtual CMM turns the head to "
                            "the angles of the sensor's SNSDEF")
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
    select = _head(state)
    if select is not None:
        axis = state.sensor_axes.get(name)
        if axis is None:
            raise NotExecutable(f"S({name}): the stylus direction of this SNSDEF form (a "
                                "CART or VEC sensor that is not vertical, or a POL sensor "
                                "with a mount vector that is not vertical)")
        select(name, diameter / 2.0, *axis,  # type: ignore[operator]
               length=state.sensor_lengths.get(name))
        state.radius = diameter / 2.0
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
