"""probegen's Macro B subprogram library: the touch and the protected move as G65 macros.

A compact Macro B program (``compile --compact``) calls these instead of spelling every
skip move out inline; each is one program (``O<n>``) in its own file ``O<n>.nc``, the
name a control operator loads it by.  Numbers run up from the profile's
``[controller] library_number`` (default 8000; the compile checks each against
``[controller] program_numbers``).

Calls (argument specification I: X Y Z -> #24 #25 #26, I -> #4; every value with a
decimal point, so no argument is read in least input increments):

* ``G65 P<first> X.. Y.. Z.. I<n>.`` protected move to the commanded point (G31 at the
  positioning feed); a skip before the end point is a collision.
* ``G65 P<first+1> X.. Y.. Z.. I<n>.`` touch: G31 at the probing feed towards the end
  point (``overtravel`` past the nominal contact); reaching it means no touch.

The main program sets, once, the probing feed in ``#base+90`` and the positioning feed in
``#base+91``, and before each feature's calls the number of its error block in
``#base+92``.  On a failed move the macro keeps the move's number in ``#base+93`` and
returns with ``M99 P#base+92`` (no touch) or ``M99 P[#base+92+1]`` (collision) to the
caller's block that prints ``ERR NOTOUCH``/``ERR COLLISION`` with the feature's id and
raises the same macro alarm the inline program raises: the log and the alarm are those
of the inline form.  The skip position stays in ``#5061``-``#5063`` after the return,
so the caller prints it and stores it as the inline program does.
"""

from __future__ import annotations

from dataclasses import dataclass

from probegen.dialects.macro_b import SCRATCH

MOVE, TOUCH, POINT = 0, 1, 2
"""Offsets of the protected move, the touch and the point from the library's first
number."""
NAMES = {MOVE: "PROTECTED MOVE", TOUCH: "TOUCH", POINT: "POINT"}
USAGE = {MOVE: "X Y Z TARGET, I MOVE NUMBER",
         TOUCH: "X Y Z END POINT, I POINT NUMBER",
         POINT: "X Y Z APPROACH, U V W END, I POINT, J MOVE"}
PROBE_FEED, POSITION_FEED, ERROR_BLOCK, FAILED_MOVE = range(SCRATCH, SCRATCH + 4)
"""Offsets from the variable base of the commons a compact program shares with the
library."""


@dataclass(frozen=True, slots=True)
class Library:
    """What the library text depends on.

    Attributes:
        first: O number of its first subprogram.
        base: the program's variable base (commons ``#base+90``..``#base+93``).
        limit: the skip check sum below which the skip position is the end point,
            printed in program units (``MacroB.CHECK_SUM``).
    """

    first: int
    base: int
    limit: str

    def number(self, offset: int) -> int:
        """The O number of subprogram ``offset`` (``MOVE``, ``TOUCH``)."""
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
            body = self.skip("#24 #25 #26", moved=True, number="#4", label=1)
        elif offset == TOUCH:
            body = self.skip("#24 #25 #26", moved=False, number="#4", label=1)
        else:
            body = [*self.skip("#24 #25 #26", moved=True, number="#5", label=1),
                    *self.skip("#21 #22 #23", moved=False, number="#4", label=2),
                    f"G1 X#24 Y#25 Z#26 F{self.common(POSITION_FEED)}"]
        lines = ["%", f"O{self.number(offset):04d}(PROBEGEN {NAMES[offset]})",
                 f"({USAGE[offset]})", *body, "M99", "%"]
        return "\n".join(lines) + "\n"

    def skip(self, xyz: str, *, moved: bool, number: str, label: int) -> list[str]:
        """A G31 move to the point in locals ``xyz`` and its check: a protected move
        (``moved``) fails when the skip fired before the end point, a touch when it did
        not; a failure keeps move ``number`` in ``#base+93`` and returns to the caller's
        error block."""
        x, y, z = xyz.split()
        feed = self.common(POSITION_FEED if moved else PROBE_FEED)
        back = f"[{self.common(ERROR_BLOCK)}+1]" if moved else self.common(ERROR_BLOCK)
        return [f"G31 X{x} Y{y} Z{z} F{feed}",
                f"#10=ABS[#5061-{x}]+ABS[#5062-{y}]+ABS[#5063-{z}]",
                f"IF[#10{'LT' if moved else 'GE'}{self.limit}]GOTO{label}",
                f"{self.common(FAILED_MOVE)}={number}",
                f"M99 P{back}",
                f"N{label}"]
