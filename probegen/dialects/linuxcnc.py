"""LinuxCNC (rs274ngc), as run by LinuxCNC 2.9 and its standalone interpreter ``rs274``.

Conventions this dialect follows (see ``docs/dialects.md`` and the LinuxCNC G-code
reference):

* Header: ``%``, the program number and name as a comment (an ``o`` word is flow control
  in rs274ngc, not a program number), units, ``G90`` and the profile's reset codes
  translated by ``RESET_CODES`` (LinuxCNC has no programmed rotation, polar mode,
  mirror image or scaling to cancel), ``G61`` exact path, the probe tool and work offset,
  a check that no G92/G52 offset is applied (``#5210``; the program aborts rather than
  measure in a shifted frame), ``G43 H``, the probe-on codes, ``(LOGAPPEND,...)`` and the
  ``PGSTART`` line.  The work offset's own XY rotation (``G10 L2 R``) is part of the frame
  the operator set, like its origin, and is kept.
* ``RAPID`` moves are ``G0`` (a straight line on LinuxCNC).
* ``PROTECTED`` moves are ``G38.3`` at the positioning feed; if the probe tripped
  (``#5070`` = 1) the program logs ``ERR COLLISION <feature> <move>`` and stops with
  ``(ABORT,UNEXPECTED PROBE TRIGGER ...)``.
* Touches are ``G38.2`` at the probing feed to ``overtravel`` past the nominal contact:
  LinuxCNC itself stops the program with an error if the probe never trips, so a missed
  touch leaves a log without ``ERR NOTOUCH`` and without ``PGEND`` (an incomplete log).
* ``RETRACT`` moves are ``G1`` back along the approach line.
* A move to the point the previous move ended at is dropped (rs274ngc calls a probe
  move that starts within 0.254 mm of its end point an error), also across the
  parameter settings and ``LOG`` lines between them (unless a setting changes a
  parameter the point is written with); it still counts in the move numbers of
  ``ERR COLLISION``, which stay those of the Fanuc program.
* Results are ``(LOG,...)`` lines in the line format of ``docs/dprnt-format.md``, the
  probe position printed as ``%.4f#5061`` (``%.5f`` in inch), so
  :func:`probegen.results.parse_dprnt` reads the log as it is.
* Rotary axes (``ir.Rotary``): ``G53 G0 B.. C..`` (machine angles); every later point
  is commanded less the node's ``head_shift`` (no tool-centre-point control, as in the
  Fanuc dialect).  ``ir.WorkOffsetShift``: ``G10 L2 Pn X[#5221+dx] ...`` (the current
  value plus the shift, written out: LinuxCNC's G10 L2 does not add in G91).
* Orientations and stylus changes (issue 17): an ``ir.Orient`` other than the identity
  is refused (:data:`TILT_REFUSAL`: LinuxCNC turns a work plane only through a five-axis
  kinematics module and its own G-codes, which this dialect does not configure); the
  identity writes its comment.  ``ir.SelectStylus``: the probe-off codes, ``G53 G0 Z0``
  (machine Z zero, LinuxCNC's home convention for a mill's Z at the top of its travel),
  ``T<n> M6``, ``G0 G43 H<n> Z<clearance>``, the probe-on codes; the touches after it use
  that stylus's ball.
* Run-time values are global named parameters ``#<_pg_name>``; ``variable_base`` is not
  used (numbered parameters would share the operator's ``#31-#5000``).
* Compact form (``compact``, ``compile --compact``; the inline form is the default):
  the protected move and the touch are subroutines in files of the macro library
  (:data:`LIBRARY`, ``pg_move.ngc`` and ``pg_touch.ngc``, found by LinuxCNC in
  ``[RS274NGC] SUBROUTINE_PATH`` or the program's folder), called ``o<pg_move> call [x]
  [y] [z] [move]`` and ``o<pg_touch> call [x] [y] [z]``.  The main program sets the
  feeds once (``#<_pg_mf>``, ``#<_pg_pf>``) and defines, per feature, a numbered
  subroutine that logs ``ERR COLLISION <feature> <move>`` and aborts; it sets
  ``#<_pg_err>`` to that number before the feature's moves and ``pg_move`` calls it
  (``o[#<_pg_err>] call [move]``) when the probe tripped: a subroutine cannot print a
  feature id (no strings), so the log and the stop are the inline program's.  The touch
  keeps its stores and ``LOG`` line in the main program.
"""

from __future__ import annotations

import re
from typing import Any, ClassVar

from probegen import ir
from probegen.constants import tol
from probegen.dialects.base import Dialect
from probegen.dialects.fanuc import feature_owners
from probegen.errors import UnsupportedError
from probegen.ir import frames
from probegen.ir.actions import describe

LIBRARY: dict[str, str] = {
    "pg_move.ngc": """(PROBEGEN LIBRARY: PROTECTED MOVE - #1 #2 #3 TARGET, #4 MOVE NUMBER)
(G38.3 AT #<_PG_MF>; A TRIP CALLS THE CALLER'S SUBROUTINE #<_PG_ERR> WITH THE MOVE)
o<pg_move> sub
G38.3 X#1 Y#2 Z#3 F#<_pg_mf>
o1 if [#5070 EQ 1]
o[#<_pg_err>] call [#4]
o1 endif
o<pg_move> endsub
M2
""",
    "pg_touch.ngc": """(PROBEGEN LIBRARY: TOUCH - #1 #2 #3 END POINT)
(G38.2 AT #<_PG_PF>: LINUXCNC STOPS THE PROGRAM IF THE PROBE NEVER TRIPS)
o<pg_touch> sub
G38.2 X#1 Y#2 Z#3 F#<_pg_pf>
o<pg_touch> endsub
M2
""",
}
"""The LinuxCNC macro library: file name → text (the same for every profile)."""

_ACTIVE_COMMENT = re.compile(
    r"\s*(MSG|DEBUG|PRINT|LOG|LOGOPEN|LOGAPPEND|LOGCLOSE|PROBEOPEN|PROBECLOSE|ABORT|PY)\b",
    re.IGNORECASE)
"""Comments that rs274ngc acts on (message, log, probe log, abort, Python)."""


TILT_REFUSAL = ("LinuxCNC: a tilted frame needs a five-axis kinematics this dialect does "
                "not configure; plan this feature with a setup or on a CMM")
"""The message for a tilted ``ir.Orient``."""


class LinuxCnc(Dialect):
    """LinuxCNC rs274ngc G-code."""

    NAME: ClassVar[str] = "linuxcnc"
    EXTENSION: ClassVar[str] = ".ngc"
    LINE_LENGTH: ClassVar[int] = 255
    PROFILE_LIMITS: ClassVar[bool] = False
    """rs274ngc reads 255-character lines and files from disk: the profile's
    ``line_length`` and ``program_memory`` (a Fanuc-style control's) do not apply."""
    """rs274ngc reads at most 256 characters a line, the end of line included."""
    RUNTIME_VARIABLES: ClassVar[bool] = True
    UNITS_CODE: ClassVar[dict[str, str]] = {"mm": "G21", "inch": "G20"}
    """The G code for each unit system."""
    RESET_CODES: ClassVar[dict[str, str | None]] = {
        "G69": None, "G15": None, "G50.1": None, "G50": None}
    """Fanuc reset codes whose mode does not exist on LinuxCNC (rotation is only the work
    offset's R, polar coordinates are per word, no mirror image, no scaling): dropped."""
    MODAL_CODES: ClassVar[frozenset[str]] = frozenset({
        "G7", "G8", "G17", "G18", "G19", "G17.1", "G18.1", "G19.1", "G20", "G21", "G40",
        "G49", "G61", "G61.1", "G64", "G80", "G90", "G90.1", "G91.1", "G93", "G94", "G95",
        "G97", "G98", "G99"})
    """Reset codes rs274ngc accepts on their own; any other is refused, not emitted."""
    PATH_MODE: ClassVar[str] = "G61"
    """Exact path: under G64, LinuxCNC's default, consecutive moves are blended and the
    corners the collision check cleared are cut."""
    PARAM_PREFIX: ClassVar[str] = "_pg_"
    """Prefix of the global named parameters (never a predefined name such as ``_x``)."""
    LOG_FILE: ClassVar[str] = "probegen-{number}.log"
    """The log file (LOGAPPEND: a rerun adds a run, as a DPRNT capture appends)."""
    FEED_DECIMALS: ClassVar[dict[str, int]] = {"mm": 0, "inch": 1}
    """Decimals of F words, by program units."""

    MACRO_LIBRARY: ClassVar[bool] = True
    NUMBERED_LIBRARY: ClassVar[bool] = False

    def __init__(self) -> None:
        super().__init__()
        self.params: dict[str, str] = {}
        self.label = 1000
        self.position: ir.Point | None = None
        self.errors: dict[str, int] = {}
        self.error_of: str | None = None
        self.ball = 0.0
        """The ball diameter of the stylus in the spindle, mm."""

    def library_files(self, first: int, base: int, units: str,
                      options: tuple[str, ...] = ()) -> dict[str, str]:
        """The macro library (:data:`LIBRARY`): named subroutines, so ``first``, ``base``
        and ``options`` do not apply, and the feeds come from the program in its units."""
        for text in LIBRARY.values():
            self.check_lines(text)
        return dict(LIBRARY)

    # -- values -----------------------------------------------------------------
    def param(self, name: str) -> str:
        """The named parameter holding run-time value ``name``."""
        if name not in self.params:
            word = self.PARAM_PREFIX + re.sub(r"[^a-z0-9]+", "_", name.lower())
            if word in self.params.values():
                raise self.unsupported(ir.Var(name), f"two run-time values named {word}")
            self.params[name] = word
        return f"#<{self.params[name]}>"

    def var(self, name: str) -> str:
        """The run-time value ``name`` as a named parameter (see :meth:`param`)."""
        return self.param(name)

    def expr(self, c: ir.Coord) -> str:
        """A coordinate as a number, a parameter or a bracketed expression."""
        e = self.sum_expr(c)
        if e is None:
            return self.length(c)  # type: ignore[arg-type]
        return e if isinstance(c, ir.Var) and abs(c.offset) < tol.zero else f"[{e}]"

    def feed(self, mm_per_min: float) -> str:
        """A feed in program units per minute."""
        return self.num(self.scale(mm_per_min), self.FEED_DECIMALS[self.units])

    def log_number(self, word: str) -> str:
        """``word`` (``#5061``, ``#<_pg_x>``) as a LOG field with the program's decimals."""
        return f"%.{self.DECIMALS[self.units]}f{word}"

    def next_label(self) -> int:
        """A fresh o-word number for an ``if`` block."""
        self.label += 1
        return self.label

    def reset_codes(self, codes: tuple[str, ...]) -> list[str]:
        """The profile's reset codes as rs274ngc accepts them (see ``RESET_CODES``)."""
        out = []
        for code in codes:
            word = self.RESET_CODES.get(code, code)
            if word is None:
                continue
            if word not in self.MODAL_CODES:
                raise self.unsupported(ir.Comment(code), "not a LinuxCNC modal code")
            out.append(word)
        return out

    def comment(self, text: str) -> str:
        """Comment text rs274ngc reads as a plain comment (no nesting, never active)."""
        text = text.upper().replace("(", "[").replace(")", "]")
        return "NOTE " + text if _ACTIVE_COMMENT.match(text) else text

    # -- lowering -----------------------------------------------------------------
    def lower(self, program: ir.Program) -> dict[str, Any]:
        s = program.setup
        self.setup = s
        nodes = ir.walk(program.body)
        self.owners = feature_owners(nodes)
        self.moves: dict[str, int] = {}
        self.errors, self.error_of = {}, None
        self.ball = s.ball_diameter
        offset_check = self.next_label()
        blocks = [self.block(n) for n in nodes]
        library = None
        if self.compact:
            library = {"move_feed": self.feed(s.position_feed),
                       "probe_feed": self.feed(s.probe_feed),
                       "errors": [{"label": label, "feature": feature}
                                  for feature, label in self.errors.items()]}
        return {
            "s": s, "units_code": self.UNITS_CODE[s.units],
            "reset": " ".join(["G90", *self.reset_codes(self.reset_block(s)),
                               self.PATH_MODE]),
            "offset_check": offset_check, "blocks": blocks, "library": library,
            "ball": self.length(s.ball_diameter), "clearance": self.length(s.clearance_z),
            "name": self.comment(s.program_name),
            "log": self.LOG_FILE.format(number=s.program_number),
            "work_offset": self.work_offset_word(s.work_offset),
        }

    def block(self, node: ir.Node) -> dict[str, Any]:
        """One IR node as the values its template macro prints."""
        if isinstance(node, ir.Rotary):
            self.position = None
            return {"kind": "rotary", "words": self.rotary_words(node)}
        if isinstance(node, ir.WorkOffsetShift):
            return self.offset_shift(node)
        if isinstance(node, ir.Orient):
            return self.orient(node)
        if isinstance(node, ir.SelectStylus):
            self.position = None
            return {"kind": "lines", "lines": self.stylus(node)}
        if isinstance(node, ir.Comment):
            return {"kind": "comment", "text": self.comment(node.text)}
        if isinstance(node, ir.FeatureBlock):
            return {"kind": "comment", "text": self.comment(self.feature_title(node.feature))}
        if isinstance(node, ir.Move):
            block = self.move(node, self.owners[id(node)])
            self.position = node.target
            return block
        if isinstance(node, ir.ReportCentre):
            return self.centre(node)  # moves nothing, changes no value
        if isinstance(node, ir.Assign):
            if self.position is not None and node.name in {
                    c.name for c in self.position if isinstance(c, ir.Var)}:
                self.position = None  # the same words now name another point
            return self.assign(node)
        self.position = None  # after a touch, where it tripped
        if isinstance(node, ir.Touch):
            return self.touch(node)
        if isinstance(node, ir.Check | ir.SetWorkOffset | ir.UpdateTool | ir.Align):
            raise UnsupportedError(f"dialect {self.NAME!r} cannot express {describe(node)}: "
                                   f"the in-process decisions are emitted for fanuc and haas "
                                   f"(and tolerances and frames for dmis) only")
        raise self.unsupported(node, "no run-time frames; use run-time variables instead")

    def orient(self, node: ir.Orient) -> dict[str, Any]:
        """The identity's comment; any other orientation is refused.

        Raises:
            UnsupportedError: :data:`TILT_REFUSAL`, naming the orientation.
        """
        if not frames.is_identity(node.rotation) or any(node.origin):
            raise UnsupportedError(f"{TILT_REFUSAL} (orientation {node.name})")
        return {"kind": "comment", "text": self.comment(f"ORIENT {node.name}")}

    def stylus(self, node: ir.SelectStylus) -> list[str]:
        """The tool change to another stylus (module docstring)."""
        self.ball = node.ball_diameter
        s = self.setup
        return [f"({self.comment(f'STYLUS {node.label} T{node.tool_number}')} BALL "
                f"D{self.length(node.ball_diameter)})", *s.probe_off, "G53 G0 Z0",
                f"T{node.tool_number} M6",
                f"G0 G43 H{node.tool_number} Z{self.length(s.clearance_z)}", *s.probe_on]

    def offset_shift(self, node: ir.WorkOffsetShift) -> dict[str, Any]:
        """``G10 L2 Pn`` with each axis its current value plus the shift (G10 L2 ignores
        G91 on LinuxCNC, so the sum is written out)."""
        number = self.offset_number(node.work_offset)
        first = 5201 + 20 * number
        xyz = [f"[#{first + k}+{self.length(v)}]" if v >= 0 else
               f"[#{first + k}-{self.length(-v)}]" for k, v in enumerate(node.shift)]
        return {"kind": "offset", "p": number, "xyz": xyz}

    def move(self, node: ir.Move, feature: str) -> dict[str, Any]:
        xyz = [self.expr(c) for c in self.commanded(node.target)]
        f = self.feed(self.setup.position_feed)
        if node.mode is ir.MoveMode.PROTECTED:
            self.moves[feature] = self.moves.get(feature, 0) + 1
        if node.target == self.position:
            return {"kind": "none"}
        if node.mode is ir.MoveMode.RAPID:
            return {"kind": "rapid", "xyz": xyz}
        if node.mode is ir.MoveMode.RETRACT:
            return {"kind": "retract", "xyz": xyz, "f": f}
        if self.compact:
            return {"kind": "call_move", "args": [*map(bracketed, xyz),
                                                  f"[{self.moves[feature]}]"],
                    "error": self.error_label(feature)}
        return {"kind": "protected", "xyz": xyz, "f": f, "feature": feature,
                "index": self.moves[feature], "label": self.next_label()}

    def error_label(self, feature: str) -> int | None:
        """The number of ``feature``'s error subroutine when ``#<_pg_err>`` must be set
        to it (the first move of a feature), else None."""
        if feature not in self.errors:
            self.errors[feature] = self.next_label()
        if self.error_of == feature:
            return None
        self.error_of = feature
        return self.errors[feature]

    def touch(self, node: ir.Touch) -> dict[str, Any]:
        k = self.ball / 2.0 - node.overtravel
        end = [c + k * n for c, n in zip(node.contact, node.normal, strict=True)]
        stores = [f"{self.param(name)} = #{5061 + axis}"
                  for axis, name in enumerate(node.store) if name is not None]
        point: ir.Point = (end[0], end[1], end[2])
        return {"kind": "call_touch" if self.compact else "touch",
                "xyz": [self.expr(c) for c in self.commanded(point)],
                "f": self.feed(self.setup.probe_feed), "stores": stores,
                "tag": node.role.value, "feature": node.feature, "index": node.index,
                "log": [self.log_number(f"#{5061 + axis}") for axis in range(3)]}

    def assign(self, node: ir.Assign) -> dict[str, Any]:
        if node.b is not None:
            value = f"[[{self.expr(node.a)}+{self.expr(node.b)}]/2]"
        else:
            value = self.expr(node.a + node.offset)
        return {"kind": "assign", "var": self.param(node.name), "value": value}

    def centre(self, node: ir.ReportCentre) -> dict[str, Any]:
        log = []
        for c in node.centre:
            if not isinstance(c, ir.Var) or c.offset:
                raise self.unsupported(node, "LOG prints plain parameters only")
            log.append(self.log_number(self.param(c.name)))
        return {"kind": "centre", "feature": node.feature, "log": log}


def bracketed(value: str) -> str:
    """A word's value as a call argument: in brackets (``[19.5]``, ``[#<_pg_x>+2.]``)."""
    return value if value.startswith("[") else f"[{value}]"
