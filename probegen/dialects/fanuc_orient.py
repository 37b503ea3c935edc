"""Orientations and stylus changes in Fanuc Macro B (``ir.Orient``, ``ir.SelectStylus``).

What the Fanuc dialect writes (``docs/dialects.md``, "Orientations and stylus changes"):

* A tilted ``Orient`` (issue 17; a rotation other than the identity, or an origin off the
  work zero): the probe first goes up out of the way, ``G53 Z0`` (machine coordinates,
  one block, rapid: machine Z zero, which on a Fanuc is the reference position when
  parameter 1240 is 0, the top of the Z travel on a vertical machine: probegen relies on
  that convention, as CAM posts do with their ``G53 Z0`` retract); ``G69`` (a feature
  coordinate system already in force is cancelled: a second G68.2 in G68.2 mode would
  be read relative to the first on controls with multiple tilted-plane commands);
  ``G68.2 X Y Z I J K`` (the frame's origin in work coordinates and its Euler angles,
  ``R = Rz(I)·Rx(J)·Rz(K)``, :func:`probegen.ir.frames.euler_zxz`; Fanuc Series 30i-A
  Descriptions B-63942EN/02, 5.44 "Tilted working plane command": X Y Z the feature
  coordinate system origin, I J K Euler's angles); ``G53.1`` (tool axis direction
  control: the control turns its rotary axes so the tool lies along the frame's +Z);
  then ``G0 G43 H<tool> Z<clearance>`` (the length offset taken again along the turned
  tool axis, as CAM posts write it after G53.1, straight down the tool axis to the frame's
  clearance level).  Every coordinate after it is in the frame: the skip positions
  ``#5061``-``#5063`` too (``docs/sim.md``).  Angles and the origin are printed with 4
  decimals (IS-C): a rounded angle moves a point 200 mm from the origin by at most 0.2 µm.
* The ``Orient`` back to the vertical (the identity) after a tilted one: ``G53 Z0``,
  ``G69``, ``G53 A0 C0`` (the rotary axes the orientations name, back to the machine
  zero where the work offset was set), then ``G0 G43 H<tool> Z<clearance>`` (the
  orientation's level, never below the program's clearance plane).  An identity
  ``Orient`` while no frame is in force writes its comment only.
* The controller option ``G68.2`` (``[controller] options``) must be declared for a
  tilted ``Orient``: a program whose setup states options without it is refused; the
  header's reset block then always holds ``G69``.
* ``SelectStylus``: the probe-off codes, ``G53 Z0``, (``G69`` when a frame is in force),
  ``T<n> M6``, (the frame again: ``G68.2`` and ``G53.1``, the rotary axes already stand
  there), ``G0 G43 H<n> Z<clearance>`` (the frame's, or the clearance plane), the probe-on
  codes.  The touches after it use that stylus's ball.
* A split program's part that starts inside a frame restates it without moving
  (``G68.2``, ``G53.1``, ``G43 H``: the probe stands where the previous part left it).
"""

from __future__ import annotations

from probegen import ir
from probegen.dialects.macro_b import MacroB
from probegen.errors import UnsupportedError
from probegen.ir import frames

RETRACT = "G53 Z0"
"""Machine Z zero: the probe out of the way before the rotary axes or the tool move."""


def setup(d: MacroB) -> ir.Setup:
    """The setup of the program ``d`` is writing."""
    if d.limits is None:
        raise RuntimeError("no program is being written")
    return d.limits


def tilted(node: ir.Orient) -> bool:
    """Whether ``node`` turns the probe away from the work frame (any rotation or origin)."""
    return not frames.is_identity(node.rotation) or any(abs(c) > 0.0 for c in node.origin)


def describe(d: MacroB, node: ir.Orient) -> str:
    """The comment naming an orientation and the rotary angles it needs (informational)."""
    angles = " ".join(f"{axis}{d.num(value, 3)}" for axis, value in node.rotary)
    return f"ORIENT {node.name}" + (f" {angles}" if angles else "")


def require_tilt(d: MacroB, node: ir.Orient) -> None:
    """Refuse a tilted frame the control cannot set: a dialect without a tilted-plane code
    (``TILT_REFUSAL``), or a setup that states its options without ``G68.2``.

    Raises:
        UnsupportedError: names the orientation, the option and the profile key.
    """
    if d.TILT_REFUSAL:
        raise UnsupportedError(f"dialect {d.NAME!r} cannot turn the probe to orientation "
                               f"{node.name}: {d.TILT_REFUSAL}")
    s = setup(d)
    if s.options is not None and "G68.2" not in s.options:
        source = s.limits_source or "the machine profile"
        raise UnsupportedError(
            f"dialect {d.NAME!r}: orientation {node.name} needs the tilted working plane "
            f"command G68.2/G53.1, expected \"G68.2\" in [controller] options ({source}), "
            f"found {list(s.options)}; declare it if the control has the option, or "
            "measure this feature in a setup of its own")


def set_frame(d: MacroB, node: ir.Orient) -> list[str]:
    """``G68.2`` with the frame's origin and Euler angles, and ``G53.1``."""
    x, y, z = (d.length(c) for c in node.origin)
    i, j, k = (d.num(a, 4) for a in frames.euler_zxz(node.rotation))
    return [f"G68.2 X{x} Y{y} Z{z} I{i} J{j} K{k}", "G53.1"]


def length_offset(d: MacroB, z: float) -> str:
    """``G0 G43 H<tool> Z<z>``: the current stylus's length offset, down to ``z``."""
    return f"G0 G43 H{d.tool} Z{d.length(z)}"


def clearance(d: MacroB) -> float:
    """The clearance level in force: the tilted frame's, else the vertical's (the
    program's clearance plane, or the higher level the last vertical ``Orient`` gave)."""
    return d.frame.clearance_z if d.frame is not None else d.level


def orient_lines(d: MacroB, node: ir.Orient) -> list[str]:
    """The blocks of an ``Orient`` (module docstring); updates the frame in force."""
    lines = [f"({describe(d, node)})"]
    if not tilted(node):
        d.level = max(node.clearance_z, setup(d).clearance_z)
    if tilted(node):
        require_tilt(d, node)
        d.axes = tuple(axis for axis, _ in node.rotary) or d.axes
        d.frame = node
        return [*lines, RETRACT, "G69", *set_frame(d, node), length_offset(d, clearance(d))]
    if d.frame is None:
        return lines
    axes = tuple(axis for axis, _ in node.rotary) or d.axes
    if not axes:
        raise UnsupportedError(
            f"dialect {d.NAME!r}: orientation {node.name} returns to the vertical after "
            f"{d.frame.name}, but neither names its rotary axes (ir.Orient.rotary): the "
            "program cannot return them to 0 before it works in the work offset again")
    d.frame = None
    return [*lines, RETRACT, "G69", "G53 " + " ".join(f"{axis}0" for axis in axes),
            length_offset(d, clearance(d))]


def stylus_lines(d: MacroB, node: ir.SelectStylus) -> list[str]:
    """The blocks of a ``SelectStylus`` (module docstring); later touches use its ball."""
    lines = [f"(STYLUS {node.label} T{node.tool_number} BALL D{d.length(node.ball_diameter)})",
             *setup(d).probe_off, RETRACT]
    if d.frame is not None:
        lines.append("G69")
    lines.append(f"T{node.tool_number} M6")
    d.tool, d.ball = node.tool_number, node.ball_diameter
    if d.frame is not None:
        lines += set_frame(d, d.frame)
    return [*lines, length_offset(d, clearance(d)), *setup(d).probe_on]


def restate_lines(d: MacroB, node: ir.Orient) -> list[str]:
    """A split part's first blocks inside frame ``node``: the frame set again without a
    move (the header's reset cancelled it; the rotary axes stand where they were)."""
    require_tilt(d, node)
    d.frame = node
    d.axes = tuple(axis for axis, _ in node.rotary) or d.axes
    return [f"(IN {describe(d, node)})", *set_frame(d, node), f"G43 H{d.tool}"]


def needs_tilt(body: tuple[ir.Node, ...], restate: ir.Orient | None) -> bool:
    """Whether a program turns the probe (its header must then reset ``G69``)."""
    return restate is not None or any(isinstance(n, ir.Orient) and tilted(n) for n in body)
