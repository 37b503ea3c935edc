"""The ``Dialect`` base: registry, capabilities, number formatting, templates.

A dialect is data first (the sqlglot pattern): class constants say what it is and what
it can express; templates under ``templates/<name>/`` hold one macro per IR node; the
Python side lowers IR nodes into the plain values those macros print.  Anything a
dialect cannot express raises ``UnsupportedError`` naming the node and the dialect: a
dropped probing move is a crash on a real machine.
"""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING, Any, ClassVar

from probegen import ir
from probegen.constants import MM_PER_INCH, tol
from probegen.errors import UnsupportedError, did_you_mean
from probegen.resources import template_text

if TYPE_CHECKING:
    import jinja2

REGISTRY: dict[str, type[Dialect]] = {}
RESET_NEEDS: dict[str, tuple[str, ...]] = {
    "G69": ("G68", "G68.2"), "G15": ("G15",), "G50.1": ("G50.1",)}
"""Reset codes that cancel an optional mode, and the controller options (any one of them)
they need: a program whose setup states its options (``ir.Setup.options``) leaves such
a code out of the reset block when none is declared (a control without the option cannot
be in the mode, and may refuse the code: alarm 10 on a Fanuc)."""


def get_dialect(name: str) -> Dialect:
    """Return an instance of the dialect called ``name``.

    Raises:
        UnsupportedError: unknown name, with a "did you mean".
    """
    if name not in REGISTRY:
        raise UnsupportedError(f"unknown dialect {name!r}{did_you_mean(name, REGISTRY)}; "
                               f"expected one of {', '.join(sorted(REGISTRY))}")
    return REGISTRY[name]()


class Dialect:
    """Base of every controller dialect."""

    NAME: ClassVar[str] = ""
    """Registry name, also the folder under ``templates/``."""
    EXTENSION: ClassVar[str] = ".txt"
    """File extension of emitted programs."""
    TEMPLATES: ClassVar[str] = ""
    """Folder under ``templates/`` (default: ``NAME``); a variant may reuse its parent's."""
    DECIMALS: ClassVar[dict[str, int]] = {"mm": 4, "inch": 5}
    """Decimals printed for lengths, by program units."""
    LINE_LENGTH: ClassVar[int] = 80
    """Longest line the target accepts."""
    RUNTIME_VARIABLES: ClassVar[bool] = False
    """Whether the controller computes with variables at run time (``ir.Var``, ``Assign``)."""
    FREE_FIT: ClassVar[bool] = False
    """Whether the target fits each measured feature freely itself (a CMM's ``MEAS`` ...
    ``ENDMES``), so a revolved feature's touches must determine it
    (:func:`probegen.geometry.determined.undetermined`); not a Macro B control, whose log
    probegen fits from the nominal."""
    LOCAL_FRAMES: ClassVar[bool] = False
    """Whether the language can translate its frame onto a measured feature."""
    PROFILE_LIMITS: ClassVar[bool] = True
    """Whether the profile's ``[controller]`` line length and program memory apply (a
    Macro B program in the control's memory; not DMIS, which goes to a CMM, nor
    LinuxCNC, which reads files from disk)."""
    EXTENDED_OFFSET: ClassVar[str] = ""
    """The code selecting an extended work offset ``<code> Pn`` (``G54.1`` on Fanuc,
    ``G154`` on Haas), or "" where the control has none."""
    MACRO_LIBRARY: ClassVar[bool] = False
    """Whether the dialect has a subprogram library a compact program calls
    (:meth:`library_files`; ``compact`` selects that form)."""
    NUMBERED_LIBRARY: ClassVar[bool] = True
    """Whether the library's subprograms are numbered programs (``O8000``...: Fanuc, Haas),
    each number then checked against ``[controller] program_numbers``; LinuxCNC's are
    named subroutine files (``o<name> sub``), which take no program number."""
    COMPACT_DEFAULT: ClassVar[bool] = False
    """Whether ``compile`` writes the compact form unless ``--inline`` is given (Fanuc and
    Haas; LinuxCNC's library is opt-in with ``--compact``)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.NAME:
            REGISTRY[cls.NAME] = cls

    def __init__(self) -> None:
        self.units = "mm"
        self.compact = False
        """Write calls to the macro library instead of inline skip moves (only where
        ``MACRO_LIBRARY``)."""
        self.shift: ir.Vec3 = (0.0, 0.0, 0.0)
        """The head shift of the last ``ir.Rotary`` (ball centre less commanded point)."""
        self.limits: ir.Setup | None = None
        """The setup of the program being written (its controller limits)."""

    # -- numbers ------------------------------------------------------------------
    def scale(self, mm: float) -> float:
        """A length in mm in the program's units."""
        return mm / MM_PER_INCH if self.units == "inch" else mm

    def num(self, value: float, decimals: int | None = None) -> str:
        """Fixed decimals, no exponent, never ``-0``."""
        d = self.DECIMALS[self.units] if decimals is None else decimals
        text = f"{value:.{d}f}"
        if text.lstrip("-").strip("0.") == "":
            text = text.lstrip("-")
        return text

    def length(self, mm: float) -> str:
        """A length given in mm, printed in program units."""
        return self.num(self.scale(mm))

    def feature_title(self, f: ir.FeatureDef) -> str:
        """A one-line description of a feature for comments, e.g. ``FEATURE B1 CIRCLE
        INNER D50.0000``."""
        side = "INNER" if f.inner else "OUTER"
        if isinstance(f, ir.SphereDef):
            return f"FEATURE {f.id} SPHERE D{self.length(f.diameter)}"
        if isinstance(f, ir.CircleDef):
            return f"FEATURE {f.id} CIRCLE {side} D{self.length(f.diameter)}"
        if isinstance(f, ir.FreeformDef):
            return (f"FEATURE {f.id} FREEFORM FACE {f.face} {f.method.upper()} "
                    f"{f.points} POINTS")
        if isinstance(f, ir.CylinderDef):
            return (f"FEATURE {f.id} CYLINDER {side} D{self.length(f.diameter)} "
                    f"L{self.length(f.length)}")
        if isinstance(f, ir.PlaneDef | ir.LineDef):
            kind = "PLANE" if isinstance(f, ir.PlaneDef) else "LINE"
            return f"FEATURE {f.id} {kind} N{','.join(self.num(v, 3) for v in f.normal)}"
        if isinstance(f, ir.TorusDef):
            return (f"FEATURE {f.id} TORUS {side} D{self.length(f.major_diameter)} "
                    f"T{self.length(f.minor_diameter)}")
        return f"FEATURE {f.id} CONE {side} A{self.num(2.0 * math.degrees(f.half_angle), 4)}"

    def commanded(self, p: ir.Point) -> ir.Point:
        """The commanded point for ball centre ``p`` at the current head pose (a five-axis
        head without tool-centre-point control: the point less ``shift``)."""
        x, y, z = (c + -s if s else c for c, s in zip(p, self.shift, strict=True))
        return x, y, z

    def rotary_words(self, node: ir.Rotary) -> str:
        """``B.. C..`` of a rotary move (machine angles, deg); takes its head shift."""
        words = [f"{a}{self.num(v, 4)}" for a, v in (("B", node.b), ("C", node.c))
                 if v is not None]
        if not words:
            raise self.unsupported(node, "a rotary move names B or C")
        self.shift = node.head_shift
        return " ".join(words)

    @staticmethod
    def reset_block(setup: ir.Setup) -> tuple[str, ...]:
        """The setup's reset codes less those whose option it does not declare
        (``RESET_NEEDS``); all of them when the setup states no options."""
        options = setup.options
        if options is None:
            return setup.reset_codes
        return tuple(code for code in setup.reset_codes
                     if code not in RESET_NEEDS or any(o in options for o in RESET_NEEDS[code]))

    def offset_number(self, work_offset: str) -> int:
        """The ``P`` of ``G10 L2`` for work offset ``G54`` .. ``G59`` (1 .. 6).

        Raises:
            UnsupportedError: an extended work offset (``G10 L20``: the dialect says).
        """
        if extended_p(work_offset):
            raise self.unsupported(ir.Comment(work_offset), "G10 L2 writes G54-G59 only")
        return int(work_offset[1:]) - 53

    def work_offset_word(self, work_offset: str) -> str:
        """The block selecting ``work_offset``: ``G54``-``G59`` as they are, an extended
        offset (``G54.1 Pn`` or ``G154 Pn``, the same P) in this dialect's code.

        Raises:
            UnsupportedError: an extended offset on a dialect without them.
        """
        p = extended_p(work_offset)
        if not p:
            return work_offset
        if not self.EXTENDED_OFFSET:
            raise UnsupportedError(f"dialect {self.NAME!r} has no extended work offsets, "
                                   f"found work offset {work_offset!r}; use G54-G59")
        return f"{self.EXTENDED_OFFSET} P{p}"

    def var(self, name: str) -> str:
        """How the program names run-time value ``name``; dialects with variables say."""
        raise self.unsupported(ir.Var(name), "no run-time variables")

    def sum_expr(self, c: ir.Coord) -> str | None:
        """``ref+offset`` / ``ref-offset`` for a run-time coordinate (None for a number, the
        bare reference when the offset is zero); the dialect brackets it as its syntax
        needs."""
        if not isinstance(c, ir.Var):
            return None
        if abs(c.offset) < tol.zero:
            return self.var(c.name)
        sign = "-" if c.offset < 0 else "+"
        return f"{self.var(c.name)}{sign}{self.length(abs(c.offset))}"

    # -- errors ---------------------------------------------------------------------
    def unsupported(self, node: object, why: str) -> UnsupportedError:
        """The error for an IR node this dialect cannot express."""
        return UnsupportedError(f"dialect {self.NAME!r} cannot express {type(node).__name__}"
                                f" ({why}): {node!r}")

    # -- templates ------------------------------------------------------------------
    @functools.cached_property
    def env(self) -> jinja2.Environment:
        """The Jinja environment with this dialect's filters, strict about undefined names
        (jinja2 is imported here, when a program is first rendered: a command that writes
        no program, such as ``capture`` or ``ingest``, never loads it)."""
        import jinja2

        env = jinja2.Environment(
            loader=jinja2.FunctionLoader(
                lambda name: template_text(self.TEMPLATES or self.NAME, name)),
            undefined=jinja2.StrictUndefined, keep_trailing_newline=True,
            trim_blocks=True, lstrip_blocks=True, autoescape=False,
        )
        env.filters["num"] = self.num
        env.filters["len"] = self.length
        return env

    def render(self, template: str, **context: Any) -> str:
        """Render ``templates/<NAME>/<template>`` with ``context``."""
        return self.env.get_template(template).render(**context)

    # -- the entry point -------------------------------------------------------------------
    def generate(self, program: ir.Program) -> str:
        """The program text; lines end with ``\\n``; byte-for-byte repeatable."""
        self.units = program.setup.units
        self.shift = (0.0, 0.0, 0.0)
        self.limits = program.setup
        text = self.render("program.j2", **self.lower(program))
        self.check_lines(text)
        self.check_size(text)
        return text

    def library_files(self, first: int, base: int, units: str,
                      options: tuple[str, ...] = ()) -> dict[str, str]:
        """File name -> text of the macro library's subprograms, numbered from ``first``,
        for programs with variable base ``base`` in ``units`` (``mm``, ``inch``) on a
        control with ``options`` (``[controller] options``).

        Raises:
            UnsupportedError: the dialect has no library (``MACRO_LIBRARY`` false).
        """
        raise UnsupportedError(f"dialect {self.NAME!r} has no macro library; use the "
                               "inline form")

    def lower(self, program: ir.Program) -> dict[str, Any]:
        """The template context for ``program``; each dialect defines it."""
        raise NotImplementedError

    def line_limit(self) -> tuple[int, str]:
        """The longest line allowed and what sets it: the dialect's ``LINE_LENGTH`` or the
        profile's ``[controller] line_length`` when that is shorter."""
        own = self.LINE_LENGTH
        limits = self.limits if self.PROFILE_LIMITS else None
        if limits is not None and 0 < limits.line_length < own:
            return limits.line_length, f"{limits.limits_source}: controller.line_length"
        return own, f"dialect {self.NAME!r}"

    def check_lines(self, text: str) -> None:
        """Refuse output the controller would not accept (line length, characters)."""
        limit, source = self.line_limit()
        for number, line in enumerate(text.split("\n"), start=1):
            if len(line) > limit:
                raise UnsupportedError(f"dialect {self.NAME!r}: line {number} is {len(line)} "
                                       f"characters, expected at most {limit} ({source}): "
                                       f"{line!r}")
            if not line.isascii():
                raise UnsupportedError(f"dialect {self.NAME!r}: line {number} has non-ASCII "
                                       f"text: {line!r}")

    def check_size(self, text: str) -> None:
        """Refuse a program larger than the profile's ``[controller] program_memory``
        (bytes as written: ASCII, one byte per character and line end).

        Raises:
            UnsupportedError: names the size, the limit and the profile key.
        """
        limits = self.limits if self.PROFILE_LIMITS else None
        size = len(text.encode("ascii", "replace"))
        if limits is None or not limits.program_memory or size <= limits.program_memory:
            return
        raise UnsupportedError(
            f"dialect {self.NAME!r}: the program is {size} bytes, expected at most "
            f"{limits.program_memory} ({limits.limits_source}: controller.program_memory); "
            "measure fewer features per program (split the spec) or raise the limit if the "
            "control has the memory free")


def extended_p(work_offset: str) -> int:
    """The P of an extended work offset (``G54.1 P12``, ``G154 P12``: 12), else 0."""
    head, _, p = work_offset.partition(" P")
    return int(p) if head in ("G54.1", "G154") and p.isdigit() else 0
