"""DMIS for the in-process decisions (``ir_actions``): tolerances and the part frame.

* A ``Check`` becomes tolerance definitions evaluated on the measured feature and
  reported with their actuals: ``T(BORE_D)=TOL/DIAM,lo,hi``, ``T(BORE_P)=TOL/POS,2D,zone``
  and ``T(BORE_F)=TOL/CIRLTY,t`` for a circle; a plane's or line's position limits must be
  symmetric (``TOL/POS,3D,2*hi``, a zone about the nominal face).  ``EVAL/FA(f),T(t)``
  then ``OUTPUT/TA(...)``: the output file says INTOL or OUTOL.
* The CMM decides nothing at run time: ``on_out_of_tolerance`` other than ``continue``, a
  tool correction and a line's angle limit raise ``UnsupportedError`` (a CMM has no
  alarms, tools or flags a program could set here; ``probegen ingest`` computes them from
  the output instead).
* Alignment and work offsets build the part frame at the end, in this order: ``D(EDGE_R)=
  ROTATE/ZAXIS,FA(EDGE),XDIR`` (then ``ROTATE/ZAXIS,-a0`` for a line whose nominal
  direction is ``a0``), ``D(BORE_M)=TRANS/XORIG,FA(BORE),YORIG,FA(BORE)`` onto the
  measured feature and ``D(BORE_N)=TRANS/XORIG,-x0,YORIG,-y0`` back by its nominal
  position: the frame in which the measured part lies at its nominal place, as the
  Fanuc program's G54 + G68.  Every checked feature is then reported again in it.
"""

from __future__ import annotations

from typing import Any

from probegen.dialects.base import Dialect
from probegen.errors import UnsupportedError
from probegen.ir.actions import ActionNode, Align, Check, SetWorkOffset, UpdateTool, describe

FORM_WORD = {"circle": "CIRLTY", "line": "STRGHT", "plane": "FLAT"}
"""The DMIS form tolerance of each fit."""


def check_lines(d: Dialect, node: Check) -> list[str]:
    """Tolerance definitions, their evaluation and output for one checked feature."""
    if node.on_fail != "continue":
        raise _unsupported(d, node, f"on_out_of_tolerance = {node.on_fail!r}: a DMIS "
                                    f"program reports OUTOL, it cannot stop or flag; use "
                                    f"\"continue\"")
    f = node.feature
    defs: list[tuple[str, str]] = []
    for lim in node.limits:
        if lim.key == "diameter":
            defs.append((f"{f}_D", f"TOL/DIAM,{d.length(lim.lower)},{d.length(lim.upper)}"))
        elif lim.key == "form":
            defs.append((f"{f}_F", f"TOL/{FORM_WORD[node.fit]},{d.length(lim.upper)}"))
        elif lim.key == "position" and node.fit == "circle":
            defs.append((f"{f}_P", f"TOL/POS,2D,{d.length(lim.upper)}"))
        elif lim.key == "position" and abs(lim.lower + lim.upper) < 1e-12:
            defs.append((f"{f}_P", f"TOL/POS,3D,{d.length(2.0 * lim.upper)}"))
        else:
            raise _unsupported(d, node, f"a {lim.key} limit [{lim.lower:g}, {lim.upper:g}] "
                                        f"of a {node.fit} has no DMIS tolerance here")
    out = [f"T({name})={text}" for name, text in defs]
    out += [f"EVAL/FA({f}),T({name})" for name, _ in defs]
    if defs:
        out.append("OUTPUT/" + ",".join(f"TA({name})" for name, _ in defs))
    return out


def frame_lines(d: Dialect, nodes: list[Any], checked: list[str],
                directions: dict[str, float]) -> list[str]:
    """The part frame from the alignment and work offsets, then the checked features
    reported in it (``directions``: the nominal direction of each checked line in XY, degrees)."""
    for node in nodes:
        if isinstance(node, UpdateTool):
            raise _unsupported(d, node, "a CMM has no tool offsets; compute the correction "
                                        "with probegen ingest from the DMIS output")
    aligns = [n for n in nodes if isinstance(n, Align)]
    offsets = [n for n in nodes if isinstance(n, SetWorkOffset)]
    if not aligns and not offsets:
        return []
    out = ["$$ the part frame: measured features at their nominal places"]
    for a in aligns:
        out.append(f"D({a.feature}_R)=ROTATE/ZAXIS,FA({a.feature}),XDIR")
        direction = directions.get(a.feature, 0.0)
        if direction:
            out.append(f"D({a.feature}_N)=ROTATE/ZAXIS,{d.num(-direction, 6)}")
    for w in offsets:
        words = [("XYZ"[i], nominal) for i, _, nominal in w.shifts]
        out.append(f"D({w.feature}_M)=TRANS/" + ",".join(
            f"{axis}ORIG,FA({w.feature})" for axis, _ in words))
        out.append(f"D({w.feature}_N)=TRANS/" + ",".join(
            f"{axis}ORIG,{d.length(-nominal)}" for axis, nominal in words))
    out += [f"OUTPUT/FA({f})" for f in checked]
    return out


def _unsupported(d: Dialect, node: ActionNode, why: str) -> UnsupportedError:
    return UnsupportedError(f"dialect {d.NAME!r} cannot express {describe(node)}: {why}")
