"""The constructions LK CAMIO and WinWerth write besides intersections.

Forms executed (``F(x)`` the nominal, defined before; actuals in MCS, mm)::

    CONST/POINT,F(x),MOVEPT,FA(p),dx,dy,dz     FA(p) moved by (dx,dy,dz) of the active PCS
    CONST/POINT|LINE|PLANE,F(x),BF,FA(a),FA(b),...
                                               least-squares fit through the features'
                                               locations (a point's point, a circle's centre)
    CONST/PLANE,F(x),PARTO,FA(plane),THRU,FA(p)
                                               the plane parallel to FA(plane) through FA(p)

A ``BF`` line or plane keeps the nominal's orientation sense; its form is the fit's.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from probegen.dmis.reader import Param
from probegen.errors import ProbegenError
from probegen.sim.cmm.features import DmisFeature, arr, fit_points, signed_like, vec3
from probegen.sim.cmm.state import NotExecutable, VmState

FORMS = frozenset({"MOVEPT", "BF", "PARTO"})
"""The ``CONST`` methods this module executes."""

_MINIMUM = {"POINT": 1, "LINE": 2, "PLANE": 3}


def construct(state: VmState, nominal: DmisFeature, method: str,
              params: tuple[Param, ...]) -> DmisFeature:
    """Return the actual of ``CONST/<kind>,F(x),<method>,<params>``.

    Raises:
        NotExecutable: a form this module does not execute.
        DmisProgramError: wrong parameters or degenerate features.
    """
    if method == "MOVEPT" and nominal.kind == "POINT":
        return _move_point(state, nominal, params)
    if method == "BF" and nominal.kind in _MINIMUM:
        return _best_fit(state, nominal, params)
    if method == "PARTO" and nominal.kind == "PLANE":
        return _parallel_through(state, nominal, params)
    raise NotExecutable(f"CONST/{nominal.kind},...,{method}: executed are POINT MOVEPT, "
                        "POINT/LINE/PLANE BF and PLANE PARTO ... THRU")


def _move_point(state: VmState, nominal: DmisFeature, params: tuple[Param, ...]
                ) -> DmisFeature:
    if len(params) != 4:
        raise state.error("CONST/POINT MOVEPT expects FA(point),dx,dy,dz")
    base = state.feature_ref(params[0], "CONST MOVEPT")
    shift = np.array(state.numbers(params[1:], "CONST MOVEPT offset")) * state.scale
    location = arr(base.location) + state.frame.vector_to_mcs(shift)
    return replace(nominal, location=vec3(location), form=0.0)


def _best_fit(state: VmState, nominal: DmisFeature, params: tuple[Param, ...]
              ) -> DmisFeature:
    features = [state.feature_ref(p, "CONST BF") for p in params]
    if len(features) < _MINIMUM[nominal.kind]:
        raise state.error(f"CONST/{nominal.kind} BF needs at least "
                          f"{_MINIMUM[nominal.kind]} features, found {len(features)}")
    points = np.array([f.location for f in features], dtype=float)
    try:
        return replace(fit_points(nominal, points), points=tuple(map(vec3, points)))
    except (ProbegenError, ValueError, np.linalg.LinAlgError) as exc:
        raise state.error(f"CONST/{nominal.kind} BF: {exc}") from None


def _parallel_through(state: VmState, nominal: DmisFeature, params: tuple[Param, ...]
                      ) -> DmisFeature:
    if len(params) != 3 or params[1] != "THRU":
        raise state.error("CONST/PLANE PARTO expects FA(plane),THRU,FA(point)")
    plane = state.feature_ref(params[0], "CONST PARTO")
    through = state.feature_ref(params[2], "CONST PARTO THRU")
    if plane.kind != "PLANE" or plane.vector is None:
        raise state.error(f"CONST/PLANE PARTO: {plane.name} is a {plane.kind}, not a plane")
    normal = signed_like(arr(plane.vector), nominal.vector)
    return replace(nominal, location=through.location, vector=vec3(normal), form=0.0)
