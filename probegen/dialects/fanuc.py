"""Fanuc Macro B (0i/30i series, custom macro B).

Conventions this dialect follows (see ``docs/dialects.md`` and the Fanuc manuals):

* Header sets units (G20/G21), absolute mode (G90), the profile's reset codes (plane,
  compensation and canned cycles off, feed per minute, rotation off), the work offset,
  the probe tool and its length offset: the program relies on no state it did not set.
* ``RAPID`` moves are G0, used only at the clearance plane or straight up to it.
* ``PROTECTED`` moves are G31 at the positioning feed; if the skip signal fires the skip
  position differs from the end point, and the program prints ``ERR COLLISION <feature>
  <move>`` and stops with macro alarm 3002.
* Touches are G31 at the probing feed from the approach point to ``overtravel`` past the
  nominal contact; if the skip position equals the end point the probe never triggered,
  and the program prints ``ERR NOTOUCH`` and stops with macro alarm 3001.
* With controller option ``#3004`` (``ir.Setup.options``) each touch's G31 is preceded
  by ``#3003=1`` ``#3004=2`` (no single block stop, feed override held at 100 %) and
  followed by ``#3004=0`` ``#3003=0`` (``SKIP_LOCK``).
* The work offset is ``G54``-``G59`` or ``G54.1 Pn`` (``EXTENDED_OFFSET``; Haas
  ``G154 Pn``); the reset codes are the profile's less those of undeclared options.
* ``RETRACT`` moves are G1 back along the approach line (the stylus may still be
  deflected at their start, so they are not skip moves).
* Skip positions ``#5061-#5063`` are printed with DPRNT in the line format of
  ``docs/dprnt-format.md`` inside POPEN/PCLOS.
* Run-time values live in common variables from the profile's ``variable_base``
  (``#100`` by default): named values from base+0, scratch at base+90..base+93.
* Rotary axes (``ir.Rotary``): ``G53 B.. C..``, machine angles, so no rotary work
  offset is relied upon; the linear axes stand still.  Without tool-centre-point
  control X, Y, Z command the ball centre as it is at ``B = 0``: every point after a
  tilt is commanded less the node's ``head_shift``; the DPRNT skip positions are the
  commanded point too (the reader adds the shift back).
* ``ir.WorkOffsetShift``: ``G91 G10 L2 Pn X.. Y.. Z..`` (in G91 the values add to the
  offset), then ``G90``.
* ``ir.Orient`` and ``ir.SelectStylus`` (issue 17): ``G53 Z0``, ``G68.2``/``G53.1``/``G69``
  and tool changes, :mod:`probegen.dialects.fanuc_orient`.
"""

from __future__ import annotations

import re
from typing import Any, ClassVar

from probegen import ir
from probegen.dialects import fanuc_orient
from probegen.dialects.fanuc_actions import lower_action, offset_words
from probegen.dialects.macro_b import SCRATCH, MacroB
from probegen.dialects.macro_library import (
    COMMONS,
    FEATURE,
    FEATURE_DIGITS,
    KIND,
    KINDS,
    MOVE,
    MOVE_COUNT,
    POINT,
    POINT_COUNT,
    POSITION_FEED,
    PROBE_FEED,
    TOUCH,
    Library,
)
from probegen.errors import UnsupportedError


class Fanuc(MacroB):
    """Fanuc Macro B G-code."""

    NAME: ClassVar[str] = "fanuc"
    EXTENSION: ClassVar[str] = ".nc"
    LINE_LENGTH: ClassVar[int] = 80
    UNITS_CODE: ClassVar[dict[str, str]] = {"mm": "G21", "inch": "G20"}
    """The G code for each unit system."""
    EXTENDED_OFFSET: ClassVar[str] = "G54.1"
    SKIP_LOCK: ClassVar[tuple[tuple[str, str], ...]] = (("#3003", "1"), ("#3004", "2"))
    """Set before every touch's G31 when the profile declares option ``#3004``, each set to
    0 after it: ``#3003`` bit 0 suppresses single block stops, ``#3004`` bit 1 (2) holds
    feed override at 100 % (bit 0, feed hold, and bit 2, exact stop, stay enabled: the
    operator can still stop the machine)."""
    MACRO_LIBRARY: ClassVar[bool] = True
    COMPACT_DEFAULT: ClassVar[bool] = True

    def __init__(self) -> None:
        super().__init__()
        self.feature_numbers: dict[str, int] = {}
        """The numbers the last compact program bound its features to (``FEAT`` records),
        in the order of their first calls."""
        self.preset_numbers: dict[str, int] = {}
        """Numbers to bind features to instead (``split`` gives every part the whole
        program's ``feature_numbers``, so the parts print the whole program's log)."""

    def library_for(self, first: int, base: int, units: str,
                    options: tuple[str, ...] = ()) -> Library:
        """The macro library from O``first`` for programs with variable base ``base`` in
        ``units`` on a control with ``options`` (``#3004``: the touch is locked)."""
        self.units = units
        lock, unlock = self.lock_blocks(options)
        return Library(first, base, self.num(self.scale(self.CHECK_SUM)),
                       self.DPRNT_FORMAT[units], lock, unlock)

    def library_files(self, first: int, base: int, units: str,
                      options: tuple[str, ...] = ()) -> dict[str, str]:
        files = self.library_for(first, base, units, options).files()
        for text in files.values():
            self.check_lines(text)
        return files

    def check_lines(self, text: str) -> None:
        """Line length and characters, and the length of every alarm message."""
        super().check_lines(text)
        self.check_messages(text)

    # -- lowering -----------------------------------------------------------------
    def lower(self, program: ir.Program) -> dict[str, Any]:
        s = program.setup
        self.base = s.variable_base
        self.setup = s
        nodes = ir.walk(program.body)
        self.owners = feature_owners(nodes)
        self.moves: dict[str, int] = {}
        self.lib = self.library_for(s.library_number, s.variable_base, s.units,
                                    s.options or ())
        self.frame, self.axes, self.tool, self.ball = None, (), s.tool_number, s.ball_diameter
        self.level = s.clearance_z
        blocks = [] if self.restate is None else [
            {"kind": "lines", "lines": fanuc_orient.restate_lines(self, self.restate)}]
        blocks += [self.block(node) for node in nodes]
        if self.compact:
            blocks = self.bind(self.points(blocks))
        return {
            "s": s, "blocks": blocks, "units_code": self.UNITS_CODE[s.units],
            "reset_codes": self.header_reset(program),
            "ball": self.length(s.ball_diameter),
            "clearance": self.length(s.clearance_z),
            "first_var": self.base, "last_var": self.last_variable(self.base),
            "version": 2 if self.compact else 1,
            "work_offset": self.work_offset_word(s.work_offset),
            "library": self.library_header(s) if self.compact else None,
        }

    def header_reset(self, program: ir.Program) -> tuple[str, ...]:
        """The reset block, with ``G69`` added when the program turns the probe and the
        profile's reset codes lack it (a program relies on no state it did not set)."""
        codes = self.reset_block(program.setup)
        if "G69" in codes or not fanuc_orient.needs_tilt(program.body, self.restate):
            return codes
        return (*codes, "G69")

    def last_variable(self, base: int) -> int:
        """The last common variable a program with variable base ``base`` uses: the
        inline form's scratch ends at ``#base+93``, the compact form's commons at
        ``#base+95`` (``macro_library.COMMONS``)."""
        return base + (COMMONS[-1] if self.compact else SCRATCH + 3)

    # -- the compact form: G65 calls to the macro library ------------------------------
    def library_header(self, s: ir.Setup) -> dict[str, Any]:
        """The library's numbers and the feeds the main program sets for it."""
        return {"first": self.lib.number(MOVE), "last": self.lib.number(POINT),
                "feeds": [f"{self.lib.common(PROBE_FEED)}={self.feed(s.probe_feed)}",
                          f"{self.lib.common(POSITION_FEED)}={self.feed(s.position_feed)}"]}

    def call(self, offset: int, point: ir.Point) -> dict[str, Any]:
        """``G65 P.. X.. Y.. Z..`` of library subprogram ``offset``."""
        xyz = [short(self.addr(c)) for c in self.commanded(point)]
        call = {"p": self.lib.number(offset), "xyz": xyz, "words": ""}
        return {**call, "line": call_line(call)}

    def points(self, blocks: list[dict[str, Any]]) -> list[dict[str, Any]]:
        """Each protected move, touch and retract to the move's target, one call to the
        library's point macro (which prints the skip position before it moves back, as
        the inline program prints it before the retract)."""
        out: list[dict[str, Any]] = []
        k = 0
        while k < len(blocks):
            move, touch, back = (blocks[k:k + 3] + [{}, {}, {}])[:3]
            if (move.get("kind") == "call_move" and touch.get("kind") == "call_touch"
                    and back.get("kind") == "retract"
                    and [short(v) for v in back["xyz"]] == move["xyz"]
                    and move["feature"] == touch["feature"]
                    and not stored_in(touch["stores"], back["xyz"])):
                words = "".join(f"{a}{end}" for a, end, start in
                                zip("UVW", touch["xyz"], move["xyz"], strict=True)
                                if end != start)  # the macro takes X Y Z for them
                call = {**touch, "p": self.lib.number(POINT), "xyz": move["xyz"],
                        "words": words, "move": move["move"]}
                call["line"] = call_line(call)
                if len(call["line"]) <= self.LINE_LENGTH:  # else the three calls
                    out.append(call)
                    k += 3
                    continue
            out.append(move)
            k += 1
        return out

    def bind(self, blocks: list[dict[str, Any]]) -> list[dict[str, Any]]:
        """The commons each call needs, set where they do not already hold it.

        A feature's first call is preceded by ``DPRNT[FEAT*<id>*<n>]``, binding its
        number to its id in the log.  Before every call the feature number, the record
        kind and the counters (the call's move or point number less one: the macro
        counts up before its G31) are assigned only where the values the earlier calls
        left differ, so a feature's calls in the plan's order set nothing.
        """
        out: list[dict[str, Any]] = []
        held: dict[int, int] = {}
        preset = self.preset_numbers
        numbers: dict[str, int] = {}
        for b in blocks:
            if not b.get("call"):
                out.append(b)
                continue
            feature = b["feature"]
            if feature not in numbers:
                numbers[feature] = preset.get(feature, len(numbers) + 1)
                if numbers[feature] >= 10 ** FEATURE_DIGITS:
                    raise UnsupportedError(
                        f"dialect {self.NAME!r}: a compact program prints at most "
                        f"{10 ** FEATURE_DIGITS - 1} features (their numbers have "
                        f"{FEATURE_DIGITS} digits), found more at {feature}; split the spec "
                        "or compile --inline")
                out.append({"kind": "bind", "feature": feature, "number": numbers[feature]})
            wanted = {FEATURE: numbers[feature]}
            if "move" in b:
                wanted[MOVE_COUNT] = b["move"] - 1
            if "tag" in b:
                wanted[KIND] = KINDS[b["tag"]]
                wanted[POINT_COUNT] = b["index"] - 1
            for offset in sorted(wanted):
                if held.get(offset) != wanted[offset]:
                    out.append({"kind": "assign", "var": self.lib.common(offset),
                                "value": str(wanted[offset])})
            held.update(wanted)
            for counter in (MOVE_COUNT, POINT_COUNT):
                if counter in wanted:
                    held[counter] += 1
            out.append(b)
        self.feature_numbers = numbers
        return out

    def block(self, node: ir.Node) -> dict[str, Any]:
        """One IR node as the values its template macro prints."""
        if isinstance(node, ir.Comment):
            return {"kind": "comment", "text": node.text.upper()}
        if isinstance(node, ir.FeatureBlock):
            return {"kind": "comment", "text": self.feature_title(node.feature)}
        if isinstance(node, ir.Move):
            return self.move(node, self.owners[id(node)])
        if isinstance(node, ir.Touch):
            return self.touch(node)
        if isinstance(node, ir.Assign):
            return self.assign(node)
        if isinstance(node, ir.Dwell):
            return {"kind": "dwell", "p": f"{round(node.seconds * 1000.0):d}"}
        if isinstance(node, ir.ReportCentre):
            return self.centre(node)
        if isinstance(node, ir.Check | ir.SetWorkOffset | ir.UpdateTool | ir.Align):
            return {"kind": "lines", "lines": lower_action(self, node)}
        if isinstance(node, ir.Rotary):
            return self.rotary(node)
        if isinstance(node, ir.WorkOffsetShift):
            return self.offset_shift(node)
        if isinstance(node, ir.Orient):
            return {"kind": "lines", "lines": fanuc_orient.orient_lines(self, node)}
        if isinstance(node, ir.SelectStylus):
            return {"kind": "lines", "lines": fanuc_orient.stylus_lines(self, node)}
        raise self.unsupported(node, "no run-time frames; use run-time variables instead")

    def rotary(self, node: ir.Rotary) -> dict[str, Any]:
        """``G53 B.. C..``; later points are commanded less the new head shift."""
        return {"kind": "rotary", "words": self.rotary_words(node)}

    def offset_shift(self, node: ir.WorkOffsetShift) -> dict[str, Any]:
        words, _ = offset_words(self.work_offset_word(node.work_offset))
        return {"kind": "offset", "words": words, "xyz": [self.length(v) for v in node.shift]}

    def centre(self, node: ir.ReportCentre) -> dict[str, Any]:
        xyz = []
        for c in node.centre:
            if not isinstance(c, ir.Var) or c.offset:
                raise self.unsupported(node, "DPRNT prints plain variables only")
            xyz.append(self.var(c.name))
        return {"kind": "centre", "feature": node.feature, "xyz": xyz,
                "fmt": self.DPRNT_FORMAT[self.units]}

    def targets(self, p: ir.Point) -> list[str]:
        """Assignments of a target ball centre's commanded point to the scratch variables."""
        return [f"{self.scratch(k)}={self.expr(c)}" for k, c in enumerate(self.commanded(p))]

    def move(self, node: ir.Move, feature: str) -> dict[str, Any]:
        xyz = [self.addr(c) for c in self.commanded(node.target)]
        if node.mode is ir.MoveMode.RAPID:
            return {"kind": "rapid", "xyz": xyz}
        if node.mode is ir.MoveMode.RETRACT:
            return {"kind": "retract", "xyz": xyz, "f": self.feed(self.setup.position_feed)}
        self.moves[feature] = self.moves.get(feature, 0) + 1
        if self.compact:
            return {"kind": "call_move", "call": True, "feature": feature,
                    "move": self.moves[feature], **self.call(MOVE, node.target)}
        return {"kind": "protected", "set": self.targets(node.target),
                "feature": feature, "index": self.moves[feature],
                "t": [self.scratch(k) for k in range(4)], "f": self.feed(self.setup.position_feed),
                "limit": self.num(self.scale(self.CHECK_SUM)), "label": self.next_label()}

    def touch(self, node: ir.Touch) -> dict[str, Any]:
        r = self.ball / 2.0
        k = r - node.overtravel
        end = tuple(c + k * n for c, n in zip(node.contact, node.normal, strict=True))
        stores = [f"{self.var(name)}=#{5061 + axis}" for axis, name in enumerate(node.store)
                  if name is not None]
        if self.compact:
            return {"kind": "call_touch", "call": True, "tag": node.role.value,
                    "feature": node.feature, "index": node.index, "stores": stores,
                    "fmt": self.DPRNT_FORMAT[self.units],
                    **self.call(TOUCH, end)}  # type: ignore[arg-type]
        return {"kind": "touch", "set": self.targets(end),  # type: ignore[arg-type]
                "t": [self.scratch(k) for k in range(4)], "f": self.feed(self.setup.probe_feed),
                "limit": self.num(self.scale(self.CHECK_SUM)), "label": self.next_label(),
                "tag": node.role.value, "feature": node.feature, "index": node.index,
                "stores": stores, "fmt": self.DPRNT_FORMAT[self.units],
                **self.skip_lock()}

    def skip_lock(self) -> dict[str, list[str]]:
        """The blocks before (``lock``) and after (``unlock``) an inline touch's G31."""
        lock, unlock = self.lock_blocks(self.setup.options or ())
        return {"lock": list(lock), "unlock": list(unlock)}

    def lock_blocks(self, options: tuple[str, ...]) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """The blocks before and after a touch's G31 that hold single block and feed
        override (``SKIP_LOCK``), in the inline form and in the library's touch alike;
        empty without option ``#3004``."""
        if "#3004" not in options:
            return (), ()
        return (tuple(f"{v}={value}" for v, value in self.SKIP_LOCK),
                tuple(f"{v}=0" for v, _ in reversed(self.SKIP_LOCK)))

    def assign(self, node: ir.Assign) -> dict[str, Any]:
        if node.b is not None:
            value = f"[{self.expr(node.a)}+{self.expr(node.b)}]/2"
        else:
            value = self.expr(node.a + node.offset if isinstance(node.a, ir.Var)
                              else node.a + node.offset)
        return {"kind": "assign", "var": self.var(node.name), "value": value}


def call_line(b: dict[str, Any]) -> str:
    """The ``G65`` block of a call: program ``p``, X Y Z ``xyz`` and the other ``words``."""
    x, y, z = b["xyz"]
    return f"G65P{b['p']}X{x}Y{y}Z{z}{b['words']}"


def stored_in(stores: list[str], xyz: list[str]) -> bool:
    """Whether a touch's stores (``#100=#5063``) write a variable a point names (the
    inline retract would read the new value, a call its value before the touch)."""
    written = {store.split("=")[0] for store in stores}
    return any(re.search(rf"{re.escape(var)}(?!\d)", " ".join(xyz)) for var in written)


NUMBER = re.compile(r"(?<![#0-9.])([0-9]*)\.([0-9]*)")
"""A number with a decimal point (a variable's ``#101`` has none)."""


def short(value: str) -> str:
    """A value with the fewest digits that keep it exact: a number (alone or in an
    expression) without its trailing zeros and its leading zero (``21.0000`` -> ``21.``,
    ``-0.5000`` -> ``-.5``, ``[#104+8.7500]`` -> ``[#104+8.75]``, ``0.0000`` -> ``0.``);
    the decimal point stays, so no control reads it in least input increments."""
    return NUMBER.sub(_short_number, value)


def _short_number(m: re.Match[str]) -> str:
    whole, fraction = m[1].lstrip("0"), m[2].rstrip("0")
    return f"{whole}.{fraction}" if whole or fraction else "0."


def feature_owners(nodes: list[ir.Node]) -> dict[int, str]:
    """For each node (by id), the feature it serves: that of the next touch, else the last.

    A protected move that stops on an unexpected trigger prints this feature and the
    move's number within it (``ERR COLLISION SPH1 3``).
    """
    out: dict[int, str] = {}
    feature = ""
    for node in reversed(nodes):
        if isinstance(node, ir.Touch):
            feature = node.feature
        out[id(node)] = feature
    last = ""
    for node in nodes:
        if isinstance(node, ir.Touch):
            last = node.feature
        if not out[id(node)]:
            out[id(node)] = last or "NONE"
    return out
