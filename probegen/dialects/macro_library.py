"""probegen's Macro B subprogram library: the touch and the protected move as G65 macros.

A compact Macro B program (``compile``'s default for Fanuc and Haas) calls these instead
of spelling every skip move out inline; each is one program (``O<n>``) in its own file
``O<n>.nc``, the name a control operator loads it by.  Numbers run up from the profile's
``[controller] library_number`` (default 8000; the compile checks each against
``[controller] program_numbers``).

Calls (argument specification I: X Y Z -> #24 #25 #26, U V W -> #21 #22 #23; every
value with a decimal point, so no argument is read in least input increments):

* ``G65 P<first> X.. Y.. Z..`` protected move to the commanded point (G31 at the
  positioning feed); a skip before the end point is a collision.
* ``G65 P<first+1> X.. Y.. Z..`` touch: G31 at the probing feed towards the end point
  (``overtravel`` past the nominal contact); reaching it means no touch.  It prints the
  skip position (``docs/dprnt-format.md``, format V2): ``PT <n> <i> X.. Y.. Z..`` (or
  ``LOC``), ``n`` the feature number, ``i`` the point index.
* ``G65 P<first+2> X.. Y.. Z.. U.. V.. W..`` point: protected move to X Y Z, touch
  towards U V W (each left out is the same as X, Y or Z: a horizontal touch has no W),
  printed as the touch prints it, ``G1`` back to X Y Z.

Commons the main program shares with the library (offsets from the variable base, see
``COMMONS``): the feeds, set once; per feature its number (the main program prints
``FEAT <id> <n>`` once, binding the number to the feature's id) and the record kind;
the move and point counters, which each macro counts up itself before its G31 (the main
program sets them only where the plan's numbering does not simply count on, e.g. at a
new feature).  A failed move prints ``ERR NOTOUCH|COLLISION <n> <counter>`` and raises
the macro alarm the inline program raises (3001 ``PROBE DID NOT TOUCH``, 3002
``UNEXPECTED PROBE TRIGGER``), in the subprogram, as a probing cycle does.  The skip
position stays in ``#5061``-``#5063`` after the return, so the caller stores it as the
inline program does.  With option ``#3004`` the touch's G31 holds single block and feed
override (``lock``, restored by ``unlock``) as the inline program's touches do.
"""

from __future__ import annotations

from dataclasses import dataclass

from probegen.dialects.macro_b import SCRATCH

MOVE, TOUCH, POINT = 0, 1, 2
"""Offsets of the protected move, the touch and the point from the library's first
number."""
NAMES = {MOVE: "PROTECTED MOVE", TOUCH: "TOUCH", POINT: "POINT"}
USAGE = {MOVE: "X Y Z TARGET",
         TOUCH: "X Y Z END POINT",
         POINT: "X Y Z APPROACH, U V W END"}
COMMONS = range(SCRATCH, SCRATCH + 6)
"""Offsets from the variable base of the commons a compact program shares with the
library: the probing and the positioning feed, the move counter, the point counter, the
feature number and the record kind (0 ``PT``, 1 ``LOC``)."""
PROBE_FEED, POSITION_FEED, MOVE_COUNT, POINT_COUNT, FEATURE, KIND = COMMONS
KINDS = {"PT": 0, "LOC": 1}
"""The value of the kind common for each touch record the library prints."""
FEATURE_DIGITS = 4
"""Digits of the printed feature number (``#base+94[40]``): at most 9999 features."""
DEFAULTS = (("#21", "#24"), ("#22", "#25"), ("#23", "#26"))
"""The point macro's end point words U V W, each X Y Z when left out."""


@dataclass(frozen=True, slots=True)
class Library:
    """What the library text depends on.

    Attributes:
        first: O number of its first subprogram.
        base: the program's variable base (commons ``#base+90``..``#base+95``).
        limit: the skip check sum below which the skip position is the end point,
            printed in program units (``MacroB.CHECK_SUM``).
        fmt: integer and fraction digits of a printed position (``44`` mm, ``35`` inch).
        lock: the blocks before a touch's G31 that hold single block and feed override
            (option ``#3004``; empty without it); ``unlock`` restores them after it.
        unlock: see ``lock``.
    """

    first: int
    base: int
    limit: str
    fmt: str = "44"
    lock: tuple[str, ...] = ()
    unlock: tuple[str, ...] = ()

    def number(self, offset: int) -> int:
        """The O number of subprogram ``offset`` (``MOVE``, ``TOUCH``, ``POINT``)."""
        return self.first + offset

    def common(self, offset: int) -> str:
        """``#n`` of the shared common at ``offset`` from the base."""
        return f"#{self.base + offset}"

    def files(self) -> dict[str, str]:
        """File name -> text of every subprogram (``O8000.nc``: ``%``, the program, ``%``)."""
        return {f"O{self.number(k):04d}.nc": self.text(k) for k in NAMES}

    def text(self, offset: int) -> str:
        """The text of subprogram ``offset``, lines ending in ``\\n``."""
        if offset == MOVE:
            body = self.skip("#24 #25 #26", moved=True, label=1)
        elif offset == TOUCH:
            body = [*self.skip("#24 #25 #26", moved=False, label=1), *self.report(2)]
        else:
            body = [*(f"IF[{end}EQ#0]THEN{end}={start}" for end, start in DEFAULTS),
                    *self.skip("#24 #25 #26", moved=True, label=1),
                    *self.skip("#21 #22 #23", moved=False, label=2), *self.report(3),
                    f"G1 X#24 Y#25 Z#26 F{self.common(POSITION_FEED)}"]
        lines = ["%", f"O{self.number(offset):04d}(PROBEGEN {NAMES[offset]})",
                 f"({USAGE[offset]})", *body, "M99", "%"]
        return "\n".join(lines) + "\n"

    def skip(self, xyz: str, *, moved: bool, label: int) -> list[str]:
        """A G31 move to the point in locals ``xyz`` and its check: a protected move
        (``moved``) counts the move counter up and fails when the skip fired before the
        end point, a touch counts the point counter up and fails when it did not; a
        failure prints ``ERR`` and raises the inline program's alarm."""
        x, y, z = xyz.split()
        feed = self.common(POSITION_FEED if moved else PROBE_FEED)
        count = self.common(MOVE_COUNT if moved else POINT_COUNT)
        lock, unlock = ((), ()) if moved else (self.lock, self.unlock)
        code, alarm = ("COLLISION", "2(UNEXPECTED PROBE TRIGGER)") if moved else \
            ("NOTOUCH", "1(PROBE DID NOT TOUCH)")
        return [f"{count}={count}+1", *lock,
                f"G31 X{x} Y{y} Z{z} F{feed}", *unlock,
                f"#10=ABS[#5061-{x}]+ABS[#5062-{y}]+ABS[#5063-{z}]",
                f"IF[#10{'LT' if moved else 'GE'}{self.limit}]GOTO{label}",
                f"DPRNT[ERR*{code}*{self.feature()}*{count}[60]]",
                f"#3000={alarm}",
                f"N{label}"]

    def feature(self) -> str:
        """The printed feature number."""
        return f"{self.common(FEATURE)}[{FEATURE_DIGITS}0]"

    def report(self, label: int) -> list[str]:
        """Print the skip position as a ``PT`` record, or as ``LOC`` when the kind common
        says so (``KINDS``), with the feature number and the point counter."""
        fields = (f"{self.feature()}*{self.common(POINT_COUNT)}[60]"
                  f"*X#5061[{self.fmt}]*Y#5062[{self.fmt}]*Z#5063[{self.fmt}]")
        return [f"IF[{self.common(KIND)}EQ{KINDS['LOC']}]GOTO{label}",
                f"DPRNT[PT*{fields}]",
                f"GOTO{label + 1}",
                f"N{label}",
                f"DPRNT[LOC*{fields}]",
                f"N{label + 1}"]
