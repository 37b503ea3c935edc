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
"""

from __future__ import annotations

from typing import Any, ClassVar

from probegen import ir
from probegen.dialects.fanuc_actions import lower_action, offset_words
from probegen.dialects.macro_b import SCRATCH, MacroB


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
        blocks = [self.block(node) for node in nodes]
        return {
            "s": s, "blocks": blocks, "units_code": self.UNITS_CODE[s.units],
            "reset_codes": self.reset_block(s),
            "ball": self.length(s.ball_diameter),
            "clearance": self.length(s.clearance_z),
            "first_var": self.base, "last_var": self.base + SCRATCH + 3,
            "work_offset": self.work_offset_word(s.work_offset),
        }

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
        return {"kind": "protected", "set": self.targets(node.target),
                "feature": feature, "index": self.moves[feature],
                "t": [self.scratch(k) for k in range(4)], "f": self.feed(self.setup.position_feed),
                "limit": self.num(self.scale(self.CHECK_SUM)), "label": self.next_label()}

    def touch(self, node: ir.Touch) -> dict[str, Any]:
        r = self.setup.ball_diameter / 2.0
        k = r - node.overtravel
        end = tuple(c + k * n for c, n in zip(node.contact, node.normal, strict=True))
        stores = [f"{self.var(name)}=#{5061 + axis}" for axis, name in enumerate(node.store)
                  if name is not None]
        return {"kind": "touch", "set": self.targets(end),  # type: ignore[arg-type]
                "t": [self.scratch(k) for k in range(4)], "f": self.feed(self.setup.probe_feed),
                "limit": self.num(self.scale(self.CHECK_SUM)), "label": self.next_label(),
                "tag": node.role.value, "feature": node.feature, "index": node.index,
                "stores": stores, "fmt": self.DPRNT_FORMAT[self.units],
                **self.skip_lock()}

    def skip_lock(self) -> dict[str, list[str]]:
        """The blocks before (``lock``) and after (``unlock``) a touch's G31 that hold
        single block and feed override (``SKIP_LOCK``), empty without option ``#3004``."""
        if "#3004" not in (self.setup.options or ()):
            return {"lock": [], "unlock": []}
        return {"lock": [f"{v}={value}" for v, value in self.SKIP_LOCK],
                "unlock": [f"{v}=0" for v, _ in reversed(self.SKIP_LOCK)]}

    def assign(self, node: ir.Assign) -> dict[str, Any]:
        if node.b is not None:
            value = f"[{self.expr(node.a)}+{self.expr(node.b)}]/2"
        else:
            value = self.expr(node.a + node.offset if isinstance(node.a, ir.Var)
                              else node.a + node.offset)
        return {"kind": "assign", "var": self.var(node.name), "value": value}


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
