"""Statement handlers for definitions: ``F(x)=FEAT/...``, ``T(x)=TOL/...``, ``MEAS``.

A nominal feature is read in the PCS active when it is defined and kept in machine
coordinates (:class:`~probegen.sim.cmm.features.DmisFeature`).  Forms executed::

    F(x)=FEAT/POINT,CART,x,y,z,i,j,k
    F(x)=FEAT/PLANE,CART,x,y,z,i,j,k
    F(x)=FEAT/CIRCLE,INNER|OUTER,CART,x,y,z,i,j,k,diam
    F(x)=FEAT/CYLNDR,INNER|OUTER,CART,x,y,z,i,j,k,diam[,length]
    F(x)=FEAT/SPHERE,INNER|OUTER,CART,x,y,z[,i,j,k],diam
    F(x)=FEAT/CONE,INNER|OUTER,CART,x,y,z,i,j,k,angle      (apex, axis, included angle)
    F(x)=FEAT/TORUS,INNER|OUTER,CART,x,y,z,i,j,k,major,minor  (centre, axis, diameters)
    F(x)=FEAT/LINE,UNBND,CART,x,y,z,i,j,k[,i2,j2,k2]        (point, direction, normal)
    F(x)=FEAT/LINE,BND,CART,x1,y1,z1,x2,y2,z2[,i2,j2,k2]
    MEAS/<type>,F(x),n   ...   ENDMES
"""

from __future__ import annotations

from dataclasses import replace

from probegen.dmis.reader import Param, Statement, format_param
from probegen.errors import ProbegenError
from probegen.sim.cmm.features import KINDS, SIDED, DmisFeature, arr, parse_nominal, vec3
from probegen.sim.cmm.frames import Frame
from probegen.sim.cmm.sensors import check_touch_sensor
from probegen.sim.cmm.state import MeasBlock, NotExecutable, VmState
from probegen.sim.cmm.tolerances import parse_tolerance

_QUALIFIERS = {"LINE": ("BND", "UNBND")} | {kind: ("INNER", "OUTER") for kind in SIDED}


def do_feat(state: VmState, st: Statement) -> None:
    """``F(x)=FEAT/<type>,...``: define a nominal feature in the active PCS;
    ``FA(x)=FEAT/...`` (WinWerth, PC-DMIS: an actual given by the program) defines the
    actual feature, and the nominal too unless the program defined one."""
    if st.label is None or st.label.kind not in ("F", "FA"):
        raise state.error("FEAT must define a feature: F(name)=FEAT/... or FA(name)=FEAT/...")
    params = list(st.params)
    kind = params.pop(0) if params else None
    if kind not in KINDS:
        raise NotExecutable(f"FEAT/{format_param(kind) if kind else ''} (executed: "
                            f"{', '.join(KINDS)})")
    qualifier = _qualifier(state, str(kind), params)
    system = params.pop(0) if params else None
    if system != "CART":
        raise NotExecutable(f"FEAT/{kind}: only CART coordinates are executed, found "
                            f"{format_param(system) if system else 'none'}")
    numbers = state.numbers(params, f"FEAT/{kind} value")
    try:
        nominal = parse_nominal(st.label.name, str(kind), qualifier, numbers, state.scale)
    except (ValueError, ProbegenError) as exc:  # a wrong count, a zero vector
        raise state.error(str(exc)) from None
    placed = to_machine(nominal, state.frame)
    if st.label.kind == "FA":
        state.actuals[placed.name] = placed
        state.nominals.setdefault(placed.name, placed)
    else:
        state.nominals[placed.name] = placed


def _qualifier(state: VmState, kind: str, params: list[Param]) -> str | None:
    """Pop and return INNER/OUTER or BND/UNBND where ``kind`` takes one."""
    allowed = _QUALIFIERS.get(kind)
    if allowed is None:
        return None
    word = params.pop(0) if params else None
    if word not in allowed:
        raise state.error(f"FEAT/{kind}: expected {' or '.join(allowed)}, found "
                          f"{format_param(word) if word is not None else 'nothing'}")
    return str(word)


def to_machine(feature: DmisFeature, frame: Frame) -> DmisFeature:
    """Return ``feature`` (PCS, mm) in machine coordinates."""
    def point(value: tuple[float, float, float] | None) -> tuple[float, float, float] | None:
        return None if value is None else vec3(frame.to_mcs(arr(value)))

    def vector(value: tuple[float, float, float] | None) -> tuple[float, float, float] | None:
        return None if value is None else vec3(frame.vector_to_mcs(arr(value)))

    return replace(feature, location=vec3(frame.to_mcs(arr(feature.location))),
                   vector=vector(feature.vector), end=point(feature.end),
                   normal=vector(feature.normal))


def do_tol(state: VmState, st: Statement) -> None:
    """``T(x)=TOL/DIAM|POS|FLAT|CIRLTY|CYLCTY|STRGHT,...``."""
    if st.label is None or st.label.kind != "T":
        raise state.error("TOL must define a tolerance: T(name)=TOL/...")
    try:
        tolerance = parse_tolerance(st.label.name, list(st.params), state.scale)
    except NotImplementedError as exc:
        raise NotExecutable(str(exc)) from None
    except ValueError as exc:
        raise state.error(str(exc)) from None
    state.tolerances[tolerance.name] = tolerance


def do_meas(state: VmState, st: Statement) -> None:
    """``MEAS/<type>,F(x),n``: open a block of ``n`` PTMEAS (and GOTO) statements."""
    if state.meas is not None:
        raise state.error(f"MEAS inside the MEAS block of line {state.meas.line}")
    check_touch_sensor(state)
    if len(st.params) != 3:
        raise state.error("MEAS expects <type>,F(name),number of points")
    kind = st.params[0]
    if kind not in KINDS:
        raise NotExecutable(f"MEAS/{format_param(kind)} (executed: {', '.join(KINDS)})")
    nominal = state.nominal(state.label(st.params[1], ("F",), "MEAS").name)
    if nominal.kind != kind:
        raise state.error(f"MEAS/{kind}: F({nominal.name}) is a {nominal.kind}")
    count = st.params[2]
    if isinstance(count, float) and count.is_integer():  # a REAL variable holding 7.0
        count = int(count)
    if not isinstance(count, int) or count < 1:
        raise state.error(f"MEAS: expected a positive point count, found {format_param(count)}")
    state.meas = MeasBlock(nominal, nominal.name, count, st.line)
