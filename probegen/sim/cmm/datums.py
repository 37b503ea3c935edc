"""Statement handlers for coordinate systems and constructions.

``D(x)=DATSET/...``, ``D(x)=TRANS/...`` and ``D(x)=ROTATE/...`` each build a new frame
from the active one (semantics in :mod:`probegen.sim.cmm.frames`), store it as
``D(x)`` and activate it; ``SAVE/DA(x)`` keeps the active frame as ``DA(x)``;
``RECALL/D(x)`` or ``RECALL/DA(x)`` activates a stored one.  ``DATDEF/FA(f),DAT(a)``
makes a measured or constructed feature a datum.

``CONST`` executes the two intersections the NIST programs use:
``CONST/LINE,F(x),INTOF,FA(plane),FA(plane)`` and
``CONST/POINT,F(x),INTOF,FA(line),FA(plane)`` (either order); ``MOVEPT``, ``BF`` and
``PARTO`` in :mod:`probegen.sim.cmm.construct`; any other form is not executed.
"""

from __future__ import annotations

from probegen.dmis.reader import Expr, Label, Param, Statement, format_param
from probegen.geometry.frames import FloatArray
from probegen.sim.cmm.construct import FORMS, construct
from probegen.sim.cmm.features import DmisFeature, arr, intersect_line_plane, intersect_planes
from probegen.sim.cmm.frames import (
    Frame,
    FrameError,
    alignment_angle,
    frame_from_axes,
    offset_to_plane,
    offset_to_point,
    parse_direction,
)
from probegen.sim.cmm.output import echo
from probegen.sim.cmm.state import NotExecutable, VmState

_ORIGINS = {"XORIG": 0, "YORIG": 1, "ZORIG": 2}
_ROTATIONS = {"XAXIS": 0, "YAXIS": 1, "ZAXIS": 2}


def _activate(state: VmState, st: Statement, frame: Frame) -> None:
    """Store ``frame`` under the statement's ``D(x)`` label, activate it, echo the line."""
    if st.label is None or st.label.kind != "D":
        raise state.error(f"{st.major} must define a datum set: D(name)={st.major}/...")
    state.frames[st.label.name] = frame
    state.frame = frame
    state.emit(echo(st))


def direction_word(param: Param) -> str | None:
    """Return a word parameter as text, ``-YDIR`` (parsed as a negation) as ``"-YDIR"``."""
    if isinstance(param, str):
        return param
    if isinstance(param, Expr) and param.op == "-" and len(param.operands) == 1:
        inner = param.operands[0]
        return f"-{inner}" if isinstance(inner, str) else None
    return None


def origin_offset(frame: Frame, axis: int, feature: DmisFeature) -> float:
    """Distance along ``frame``'s axis from its origin to the feature (a plane: where the
    axis meets it; any other feature: its location's coordinate)."""
    if feature.kind == "PLANE" and feature.vector is not None:
        return offset_to_plane(frame, axis, arr(feature.location), arr(feature.vector))
    return offset_to_point(frame, axis, arr(feature.location))


# ----------------------------------------------------------------------- DATSET


def do_datset(state: VmState, st: Statement) -> None:
    """``D(x)=DATSET/MCS`` or ``D(x)=DATSET/DAT(a),dir[,orig...][,DAT(b),...]``."""
    if st.params == ("MCS",):
        _activate(state, st, Frame.machine())
        return
    groups = _datum_groups(state, st.params)
    directions: dict[int, FloatArray] = {}
    origins: list[tuple[int, DmisFeature]] = []
    for feature, words in groups:
        for word in words:
            if word in _ORIGINS:
                origins.append((_ORIGINS[word], feature))
            else:
                _add_direction(state, directions, feature, word)
    if not directions:
        raise state.error("DATSET needs a direction (XDIR, YDIR or ZDIR) for its first datum")
    try:
        frame = Frame(frame_from_axes(directions, state.frame), state.frame.origin)
        for axis, feature in origins:
            frame = frame.translated(axis, origin_offset(frame, axis, feature))
    except FrameError as exc:
        raise state.error(f"DATSET: {exc}") from None
    _activate(state, st, frame)


def _datum_groups(state: VmState, params: tuple[Param, ...]
                  ) -> list[tuple[DmisFeature, list[str]]]:
    """Split DATSET parameters into (datum feature, its words) groups."""
    groups: list[tuple[DmisFeature, list[str]]] = []
    for param in params:
        if isinstance(param, Label):
            groups.append((state.feature_ref(param, "DATSET"), []))
        elif (word := direction_word(param)) is not None and groups:
            groups[-1][1].append(word)
        else:
            raise state.error(f"DATSET: expected DAT(name) or a direction/origin word, "
                              f"found {format_param(param)}")
    return groups


def _add_direction(state: VmState, directions: dict[int, FloatArray],
                   feature: DmisFeature, word: str) -> None:
    try:
        axis, sign = parse_direction(word)
    except ValueError as exc:
        raise state.error(f"DATSET: {exc}") from None
    if len(directions) == 2:
        raise NotExecutable("DATSET: a direction from a third datum (only two are used)")
    if axis in directions:
        raise state.error(f"DATSET: axis {word} is set twice")
    if feature.vector is None:
        raise state.error(f"DATSET: datum {feature.name} ({feature.kind}) has no direction")
    directions[axis] = sign * arr(feature.vector)


# ------------------------------------------------------------------ TRANS / ROTATE


def do_trans(state: VmState, st: Statement) -> None:
    """``D(x)=TRANS/XORIG,value|FA(f)|DAT(a)[,YORIG,...][,ZORIG,...]``."""
    params = list(st.params)
    if not params or len(params) % 2:
        raise state.error("TRANS expects pairs: XORIG|YORIG|ZORIG, value or feature")
    frame = state.frame
    for word, value in zip(params[::2], params[1::2], strict=True):
        if word not in _ORIGINS:
            raise state.error(f"TRANS: expected XORIG, YORIG or ZORIG, found "
                              f"{format_param(word)}")
        axis = _ORIGINS[str(word)]
        frame = frame.translated(axis, _trans_distance(state, frame, axis, value))
    _activate(state, st, frame)


def _trans_distance(state: VmState, frame: Frame, axis: int, value: Param) -> float:
    if isinstance(value, Label):
        feature = state.feature_ref(value, "TRANS")
        try:
            return origin_offset(frame, axis, feature)
        except FrameError as exc:
            raise state.error(f"TRANS: {exc}") from None
    return state.length(value, "TRANS origin")


def do_rotate(state: VmState, st: Statement) -> None:
    """``D(x)=ROTATE/ZAXIS,angle`` or ``ROTATE/ZAXIS,FA(f)|DAT(a),XDIR|YDIR|...``."""
    params = st.params
    if len(params) not in (2, 3) or params[0] not in _ROTATIONS:
        raise state.error("ROTATE expects XAXIS|YAXIS|ZAXIS then an angle, or a feature "
                          "and a direction")
    axis = _ROTATIONS[str(params[0])]
    if len(params) == 2:
        angle = state.number(params[1], "ROTATE angle") * state.angle_scale
    else:
        angle = _rotate_to_feature(state, axis, params[1], params[2])
    _activate(state, st, state.frame.rotated(axis, angle))


def _rotate_to_feature(state: VmState, axis: int, ref: Param, word: Param) -> float:
    feature = state.feature_ref(ref, "ROTATE")
    if feature.vector is None:
        raise state.error(f"ROTATE: feature {feature.name} has no direction")
    try:
        target, sign = parse_direction(direction_word(word) or format_param(word))
        return alignment_angle(state.frame, axis, target, sign, arr(feature.vector))
    except (ValueError, FrameError) as exc:
        raise state.error(f"ROTATE: {exc}") from None


# ---------------------------------------------------------- DATDEF / SAVE / RECALL


def do_datdef(state: VmState, st: Statement) -> None:
    """``DATDEF/FA(f),DAT(a)``: the actual feature becomes datum ``a``."""
    if len(st.params) != 2:
        raise state.error("DATDEF expects FA(feature),DAT(name)")
    feature = state.actual(state.label(st.params[0], ("FA",), "DATDEF").name)
    state.datums[state.label(st.params[1], ("DAT",), "DATDEF").name] = feature


def do_save(state: VmState, st: Statement) -> None:
    """``SAVE/DA(x)``: keep the active frame as ``DA(x)``."""
    if len(st.params) != 1:
        raise state.error("SAVE expects one DA(name)")
    state.saved[state.label(st.params[0], ("DA", "D"), "SAVE").name] = state.frame


def do_recall(state: VmState, st: Statement) -> None:
    """``RECALL/D(x)`` or ``RECALL/DA(x)``: activate a stored frame (echoed);
    ``RECALL/SA(x)`` recalls a calibrated sensor: the machine's stylus (noted)."""
    if len(st.params) != 1:
        raise state.error("RECALL expects one D(name), DA(name) or SA(name)")
    if isinstance(st.params[0], Label) and st.params[0].kind == "SA":
        state.use_machine_stylus(st, f"{st.params[0]} is a calibrated sensor")
        return
    ref = state.label(st.params[0], ("D", "DA"), "RECALL")
    table = state.frames if ref.kind == "D" else state.saved
    if ref.name not in table:
        state.check_skipped("D", ref.name)
        raise state.error(f"{ref} is not defined")
    state.frame = table[ref.name]
    state.emit(echo(st))


# -------------------------------------------------------------------------- CONST


def do_const(state: VmState, st: Statement) -> None:
    """``CONST/LINE|POINT,F(x),INTOF,FA(a),FA(b)``: see the module docstring."""
    params = st.params
    kind = params[0] if params else None
    if len(params) > 3 and params[2] in FORMS:
        nominal = state.nominal(state.label(params[1], ("F",), "CONST").name)
        if nominal.kind != kind:
            raise state.error(f"CONST/{kind}: F({nominal.name}) is a {nominal.kind}")
        state.actuals[nominal.name] = construct(state, nominal, str(params[2]), params[3:])
        return
    if len(params) != 5 or params[2] != "INTOF" or kind not in ("LINE", "POINT"):
        raise NotExecutable("CONST: only LINE and POINT as INTOF (intersection) of two "
                            "features are executed")
    nominal = state.nominal(state.label(params[1], ("F",), "CONST").name)
    if nominal.kind != kind:
        raise state.error(f"CONST/{kind}: F({nominal.name}) is a {nominal.kind}")
    first, second = (state.feature_ref(p, "CONST") for p in params[3:])
    state.actuals[nominal.name] = _intersection(state, nominal, first, second)


def _intersection(state: VmState, nominal: DmisFeature, first: DmisFeature,
                  second: DmisFeature) -> DmisFeature:
    kinds = {first.kind, second.kind}
    try:
        if nominal.kind == "LINE" and kinds == {"PLANE"}:
            return intersect_planes(nominal, first, second)
        if nominal.kind == "POINT" and kinds == {"LINE", "PLANE"}:
            line, plane = (first, second) if first.kind == "LINE" else (second, first)
            return intersect_line_plane(nominal, line, plane)
    except ValueError as exc:
        raise state.error(f"CONST: {exc}") from None
    raise NotExecutable(f"CONST/{nominal.kind} INTOF a {first.kind} and a {second.kind}")

