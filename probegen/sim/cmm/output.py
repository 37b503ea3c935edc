"""The DMIS output file the virtual CMM writes, in the shape of NIST's ``output.dms``.

* Echoed statements: ``LABEL = MAJOR/p1, p2, ...`` (``", "`` between parameters,
  ``" = "`` after a label); program numbers in their shortest form.
* Results: ``FA(C1) = FEAT/CIRCLE, INNER, CART,  $`` then the values on continuation
  lines indented by two spaces, five decimals each, never ``-0.00000``;
  ``TA(T1) = TOL/DIAM, 0.00100, INTOL``.
* A physical line never exceeds :data:`LINE_LIMIT` characters where the items allow;
  a continued line ends in ``",  $"``.  Lines end in ``\\n``.
"""

from __future__ import annotations

from probegen.dmis.reader import Label, Param, Statement, format_param
from probegen.dmis.values import EvalError
from probegen.errors import ProbegenError
from probegen.sim.cmm.features import SIDED, DmisFeature, Vec3, arr, vec3
from probegen.sim.cmm.frames import Frame
from probegen.sim.cmm.state import NotExecutable, VmState
from probegen.sim.cmm.tolerances import ToleranceResult

LINE_LIMIT = 80
"""Longest physical output line (characters) when items can be wrapped."""

DECIMALS = 5
"""Decimals of every reported number (as NIST's output.dms)."""


def number(value: float) -> str:
    """Format a reported value with :data:`DECIMALS` decimals, never as ``-0.00000``."""
    text = f"{value:.{DECIMALS}f}"
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text


def wrap(head: str, groups: list[list[str]]) -> str:
    """Join ``head`` and item groups into continued DMIS lines.

    The first group follows ``head`` on its line; each later group starts a new
    continuation line; items of a group are packed up to :data:`LINE_LIMIT`.
    """
    lines: list[str] = []
    current = head
    fresh = True  # nothing after the head yet
    for index, group in enumerate(groups):
        if index > 0 and not fresh:
            lines.append(current + ",  $")
            current, fresh = "  ", True
        for item in group:
            joined = current + ("" if fresh else ", ") + item
            if not fresh and len(joined) + 4 > LINE_LIMIT:
                lines.append(current + ",  $")
                joined = "  " + item
            current, fresh = joined, False
    lines.append(current)
    return "\n".join(lines)


def echo(statement: Statement) -> str:
    """Return a program statement as it appears in the output file."""
    head = f"{statement.label} = {statement.major}" if statement.label else statement.major
    if not statement.params:
        return head
    return wrap(head + "/", [[format_param(p) for p in statement.params]])


def feature_text(label: str, feature: DmisFeature, frame: Frame, scale: float) -> str:
    """Return ``FA(x) = FEAT/...`` (or ``F(x)``) with values in the PCS, program units.

    Args:
        label: ``"FA"`` or ``"F"``.
        feature: the feature (MCS, millimetres).
        frame: the active frame.
        scale: millimetres per program unit.
    """
    words = [feature.kind]
    if feature.qualifier is not None:
        words.append(feature.qualifier)
    words.append("CART")
    values = [number(v) for v in _values(feature, frame, scale)]
    return wrap(f"{label}({feature.name}) = FEAT/", [words, values])


def _values(feature: DmisFeature, frame: Frame, scale: float) -> list[float]:
    """The numbers after ``CART`` in the order of the ``FEAT`` definition."""
    out = [*_point(feature.location, frame, scale)]
    if feature.kind == "LINE" and feature.end is not None:
        out += _point(feature.end, frame, scale)
    elif feature.vector is not None:
        out += _direction(feature.vector, frame)
    if feature.kind == "LINE" and feature.normal is not None:
        out += _direction(feature.normal, frame)
    if feature.kind in SIDED and feature.size is not None:
        out.append(feature.size if feature.kind == "CONE" else feature.size / scale)
    if feature.minor is not None:
        out.append(feature.minor / scale)
    if feature.length is not None:
        out.append(feature.length / scale)
    return out


def _point(point: Vec3, frame: Frame, scale: float) -> list[float]:
    return [v / scale for v in vec3(frame.to_pcs(arr(point)))]


def _direction(vector: Vec3, frame: Frame) -> list[float]:
    return list(vec3(frame.vector_to_pcs(arr(vector))))


def tolerance_text(result: ToleranceResult, scale: float) -> str:
    """Return ``TA(x) = TOL/<kind>[, 2D|3D], <actual>, INTOL|OUTOL`` in program units."""
    tolerance = result.tolerance
    items = [tolerance.kind] + ([tolerance.mode] if tolerance.mode else [])
    items += [number(result.deviation / scale), "INTOL" if result.in_tolerance else "OUTOL"]
    return wrap(f"TA({tolerance.name}) = TOL/", [items])


class StateHost:
    """What ``OBTAIN`` reads on a run (:class:`probegen.dmis.execute.Host`): a parameter
    of ``FA(x)`` or ``F(x)`` as the output file gives it (PCS, program units)."""

    def __init__(self, state: VmState) -> None:
        self.state = state

    def obtain(self, label: Label, index: int) -> tuple[Param, bool]:
        """Parameter ``index`` (1-based) of ``FA(x) = FEAT/...`` or ``F(x) = FEAT/...``
        as output (``FEAT/CIRCLE,INNER,CART,x,...``: 1 is CIRCLE, 4 is x), unrounded;
        measured for ``FA``."""
        state = self.state
        if label.kind not in ("FA", "F"):
            raise EvalError(f"OBTAIN/{label}: only FA(x) and F(x) are read")
        try:
            feature = state.actual(label.name) if label.kind == "FA" else \
                state.nominal(label.name)
        except (ProbegenError, NotExecutable) as exc:
            raise EvalError(str(exc)) from None
        words: list[Param] = [feature.kind, *([feature.qualifier] if feature.qualifier
                                                else []), "CART"]
        params = [*words, *_values(feature, state.frame, state.scale)]  # full precision
        if index > len(params):
            raise EvalError(f"OBTAIN/{label},{index}: {label} has {len(params)} parameters")
        return params[index - 1], label.kind == "FA"
