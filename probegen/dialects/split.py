"""A Macro B program that does not fit the control: split into a driver and its parts.

What "does not fit" means (the profile's ``[controller]``, ``docs/dialects.md``):

* ``program_size``: the largest single program the control takes (the memory left for
  one program, or the control's own limit for a stored, editable program).  A larger
  program is split at feature boundaries into parts, each its own program, and a driver
  that calls them in order with ``M98 P``.
* ``program_memory``: the memory all of probegen's programs share.  The driver, its parts
  and the macro library together must fit; if they do not, splitting cannot help and the
  program is refused (as is a single program larger than it, :meth:`Dialect.check_size`).

The driver is the program the operator runs: the header of the unsplit program (units,
absolute mode, reset codes, tool change, work offset, length offset at the clearance
plane, probe on, ``POPEN`` and the ``PGSTART`` line), one ``M98 P<part>`` per part, then
the ``PGEND`` line, ``PCLOS``, probe off and ``M30``.  A part is the unsplit program's text
for its features, between a header that sets every modal state it relies on itself
(units, ``G90``, the reset codes: plane, compensation off, rotation cancelled; the work
offset; ``G43 H`` without a move: the probe stands where the previous part left it, so
the path is the unsplit program's, collision-checked as planned) and ``M99``.  The tool
change and the probe-on codes stay in the driver (a second ``M6`` or probe-on code
would cycle the tool changer or, on a receiver that toggles, switch the probe off).  So
the machine moves as the unsplit program moves it and the DPRNT log is the same bytes.

Where a program may be cut: between two features (a top-level node after a feature or
its in-process decisions, before the next feature's travel), never inside a feature, and
never where a value measured before the cut is read after it (a located feature, an
in-process decision that reads an earlier feature's results: they stay in one part, or
the split is refused with that reason).

Orientations and stylus changes (issue 17): a part that starts after an ``ir.Orient`` or an
``ir.SelectStylus`` re-establishes them: its header takes the length offset of the stylus
in the spindle (the tool change itself stays in the part that made it), and a tilted frame
in force is set again without a move (``G68.2``, ``G53.1``, ``G43 H``: the header's reset
cancelled it with ``G69``; the rotary axes stand where the previous part left them),
as the last rotary pose (``ir.Rotary``) is restated.

One difference in the log when a move fails: the protected moves after a part's last
touch (the climb back to the clearance plane) count as its last feature's moves, so an
unexpected trigger there prints ``ERR COLLISION <that feature> <n>``, where the unsplit
program counts them as the next feature's first moves.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, replace

from probegen import ir
from probegen.dialects import fanuc_orient
from probegen.dialects.base import Dialect
from probegen.dialects.fanuc import Fanuc
from probegen.errors import UnsupportedError
from probegen.ir.actions import describe


@dataclass(frozen=True, slots=True)
class Part:
    """One part of a split program.

    Attributes:
        number: its O number.
        features: the ids of the features it measures, in order.
        text: the program text (``%`` to ``%``, ending in ``M99``).
    """

    number: int
    features: tuple[str, ...]
    text: str

    @property
    def file_name(self) -> str:
        """``O<number>.nc``: the name a control loads it by, as the macro library's."""
        return f"O{self.number:04d}.nc"


@dataclass(frozen=True, slots=True)
class Fitted:
    """What ``compile`` writes for one program: the program itself (the driver when
    split) and its parts (none when it fits)."""

    main: str
    parts: tuple[Part, ...] = ()


def size(text: str) -> int:
    """Bytes as written (ASCII: one byte per character and line end)."""
    return len(text.encode("ascii", "replace"))


def fit(dialect: Dialect, program: ir.Program, library: Mapping[str, str] | None = None,
        splits: bool = True) -> Fitted:
    """The program, split when it is larger than ``program_size``; the whole checked
    against ``program_memory``.

    Args:
        dialect: the dialect writing it (its ``compact`` form is kept in every part).
        program: the planned program.
        library: the macro library files written with it (counted in the memory).
        splits: whether the caller writes a split program's parts (a command that writes
            one program only refuses a program larger than ``program_size``).

    Raises:
        UnsupportedError: a part would still be too large (one feature alone), no cut is
            allowed, or the files together pass ``program_memory``; the message gives the
            sizes and the profile key.
    """
    whole = dialect.generate(program)
    s = program.setup
    limit = s.program_size or s.program_memory
    if not dialect.PROFILE_LIMITS or not limit or size(whole) <= limit:
        fitted = Fitted(whole)
    else:
        if not isinstance(dialect, Fanuc) or not splits:
            why = ("this command writes one program" if not splits
                   else f"dialect {dialect.NAME!r} cannot split a program")
            raise UnsupportedError(f"dialect {dialect.NAME!r}: the program is {size(whole)} "
                                   f"bytes, expected at most {limit} ({s.limits_source}: "
                                   f"controller.program_size), and {why}; raise "
                                   "program_size if the control takes it")
        fitted = split(dialect, program, size(whole))
    check_memory(dialect, s, fitted, library or {})
    return fitted


def split(dialect: Fanuc, program: ir.Program, whole: int) -> Fitted:
    """The driver and parts of ``program`` (``whole`` bytes unsplit), each part at most
    ``program_size`` bytes, cut greedily at the allowed feature boundaries."""
    s = program.setup
    body = program.body
    cuts, reasons = boundaries(body)
    too_big = (f"dialect {dialect.NAME!r}: the program is {whole} bytes, expected at most "
               f"{s.program_size} ({s.limits_source}: controller.program_size)")
    if not cuts and not reasons:
        raise UnsupportedError(f"{too_big}, and it measures one feature: a program is split "
                               "between features only; raise program_size if the control "
                               "takes it, or measure fewer touches")
    if not cuts:
        raise UnsupportedError(f"{too_big}, and it cannot be split at a feature boundary "
                               "(a value measured before a cut may not be read after it: "
                               f"features that share values stay in one program): "
                               f"{'; '.join(reasons)}; raise program_size if the control "
                               "takes it")
    ranges: list[tuple[int, int, str]] = []
    start = 0
    ends = [*cuts, len(body)]
    while start < len(body):
        k = len(ranges) + 1
        after = [e for e in ends if e > start]
        text = part_text(dialect, program, start, after[0], k)
        if size(text) > s.program_size:
            ids = features(body[start:after[0]])
            kept = f" (kept together: {'; '.join(reasons)})" if len(ids) > 1 else ""
            raise UnsupportedError(
                f"{too_big}; split at feature boundaries, the part with {', '.join(ids)} "
                f"alone is {size(text)} bytes{kept}: splitting cannot make it fit; measure "
                "fewer touches in one feature or raise program_size")
        end, text = longest(dialect, program, start, after, text, k)
        ranges.append((start, end, text))
        start = end
    parts = tuple(Part(s.program_number + k, features(body[a:b]), text)
                  for k, (a, b, text) in enumerate(ranges, start=1))
    return Fitted(driver(dialect, program, parts), parts)


def longest(dialect: Fanuc, program: ir.Program, start: int, ends: list[int], first: str,
            k: int) -> tuple[int, str]:
    """The farthest of ``ends`` part ``k`` from ``start`` may reach within
    ``program_size``, and its text (``first``: the text to ``ends[0]``, which fits).  A
    part's size grows with its end, so the search halves the candidates each time."""
    lo, hi, best = 0, len(ends) - 1, first
    while lo < hi:
        mid = (lo + hi + 1) // 2
        text = part_text(dialect, program, start, ends[mid], k)
        if size(text) <= program.setup.program_size:
            lo, best = mid, text
        else:
            hi = mid - 1
    return ends[lo], best


def check_memory(dialect: Dialect, s: ir.Setup, fitted: Fitted,
                 library: Mapping[str, str]) -> None:
    """Refuse files that together pass ``program_memory``.

    Raises:
        UnsupportedError: the sizes of each and the key.
    """
    sizes = [("the driver" if fitted.parts else "the program", size(fitted.main))]
    sizes += [(f"O{p.number:04d}", size(p.text)) for p in fitted.parts]
    sizes += [(name.removesuffix(".nc"), size(text)) for name, text in library.items()]
    total = sum(n for _, n in sizes)
    if not dialect.PROFILE_LIMITS or not s.program_memory or total <= s.program_memory:
        return
    each = ", ".join(f"{name} {n}" for name, n in sizes)
    raise UnsupportedError(
        f"dialect {dialect.NAME!r}: the programs are {total} bytes together ({each}), "
        f"expected at most {s.program_memory} ({s.limits_source}: "
        "controller.program_memory): splitting cannot help; measure fewer features per "
        "program (split the spec) or raise the limit if the control has the memory free")


# -- where a program may be cut ---------------------------------------------------------

def boundaries(body: tuple[ir.Node, ...]) -> tuple[list[int], list[str]]:
    """The positions in ``body`` where a cut is allowed (a part starts there), and why
    each other feature boundary is not."""
    cuts: list[int] = []
    reasons: list[str] = []
    for k in range(1, len(body)):
        if not isinstance(body[k - 1], ir.FeatureBlock | ir.ActionNode) or isinstance(
                body[k], ir.ActionNode):
            continue
        before, after = features(body[:k]), features(body[k:])
        if not before or not after:
            continue
        why = refusal(body[:k], body[k:])
        if why:
            reasons.append(f"not between {before[-1]} and {after[0]} ({why})")
        else:
            cuts.append(k)
    return cuts, reasons


def refusal(before: tuple[ir.Node, ...], after: tuple[ir.Node, ...]) -> str:
    """Why the program may not be cut between ``before`` and ``after`` ("" if it may)."""
    first, second = ir.walk(before), ir.walk(after)
    inside = touched(first) & touched(second)
    if inside:
        return f"feature {sorted(inside)[0]} has touches on both sides"
    made = produced(first)
    for node in second:
        for name in read(node):
            if name in made or any(name.startswith(f"{f}.") for f in checked(first)):
                return f"{reader(node)} reads {name}"
    return ""


def reader(node: ir.Node) -> str:
    """What reads a value, for a message (``align of feature EDGE``)."""
    if isinstance(node, ir.ActionNode):
        return describe(node)
    if isinstance(node, ir.Touch):
        return f"touch {node.index} of feature {node.feature}"
    if isinstance(node, ir.ReportCentre):
        return f"the centre line of feature {node.feature}"
    return "a move" if isinstance(node, ir.Move) else f"the value {getattr(node, 'name', '')}"


def features(nodes: tuple[ir.Node, ...]) -> tuple[str, ...]:
    """The ids of the feature blocks in ``nodes`` (top level), in order."""
    return tuple(n.feature.id for n in nodes if isinstance(n, ir.FeatureBlock))


def touched(nodes: list[ir.Node]) -> set[str]:
    """The features the touches among ``nodes`` belong to."""
    return {n.feature for n in nodes if isinstance(n, ir.Touch)}


def produced(nodes: list[ir.Node]) -> set[str]:
    """The run-time values ``nodes`` write: touch stores and assignments."""
    out: set[str] = set()
    for n in nodes:
        if isinstance(n, ir.Touch):
            out |= {name for name in n.store if name is not None}
        elif isinstance(n, ir.Assign):
            out.add(n.name)
    return out


def checked(nodes: list[ir.Node]) -> set[str]:
    """The features whose results a ``Check`` among ``nodes`` computes (``BORE.X`` ...)."""
    return {n.feature for n in nodes if isinstance(n, ir.Check)}


def read(node: ir.Node) -> Iterator[str]:
    """The run-time values ``node`` reads."""
    coords: tuple[ir.Coord | None, ...] = ()
    if isinstance(node, ir.Move):
        coords = node.target
    elif isinstance(node, ir.Touch):
        coords = node.contact
    elif isinstance(node, ir.Assign):
        coords = (node.a, node.b)
    elif isinstance(node, ir.ReportCentre):
        coords = node.centre
    elif isinstance(node, ir.Check):
        yield from (name for point in node.points for name in point if name is not None)
    elif isinstance(node, ir.SetWorkOffset):
        yield from (name for _, name, _ in node.shifts)
    elif isinstance(node, ir.UpdateTool):
        yield node.excess
    elif isinstance(node, ir.Align):
        yield node.angle
    yield from (c.name for c in coords if isinstance(c, ir.Var))


# -- the texts ----------------------------------------------------------------------------

def part_text(dialect: Fanuc, program: ir.Program, start: int, end: int, k: int) -> str:
    """The whole-program text of ``body[start:end]`` as part ``k`` (its own number; the
    last rotary pose before it restated; the stylus in the spindle as its probe, whose
    ``G43 H`` its header takes; the tilted frame in force set again without a move),
    written by a fresh dialect of the same kind."""
    body = program.body
    pose = [n for n in ir.walk(body[:start]) if isinstance(n, ir.Rotary)][-1:]
    s = in_spindle(program.setup, body[:start])
    sub = ir.Program(replace(s, program_number=s.program_number + k,
                             program_name=f"{s.program_name} PART {k}"[:40]),
                     (*pose, *body[start:end]))
    fresh = _like(dialect)
    fresh.preset_numbers = dialect.feature_numbers  # the whole program's (fit generated it)
    fresh.restate = frame_in_force(body[:start])
    return subprogram(fresh.generate(sub), s, k)


def in_spindle(s: ir.Setup, before: tuple[ir.Node, ...]) -> ir.Setup:
    """The setup with the stylus the last ``SelectStylus`` of ``before`` took as its probe
    (``s`` itself when there is none)."""
    taken = [n for n in before if isinstance(n, ir.SelectStylus)][-1:]
    if not taken:
        return s
    st = taken[0]
    return replace(s, tool_number=st.tool_number, ball_diameter=st.ball_diameter,
                   shank_diameter=st.shank_diameter, probe_length=st.length)


def frame_in_force(before: tuple[ir.Node, ...]) -> ir.Orient | None:
    """The tilted orientation in force after ``before`` (None: the vertical probe)."""
    last = [n for n in before if isinstance(n, ir.Orient)][-1:]
    return last[0] if last and fanuc_orient.tilted(last[0]) else None


def _like(dialect: Fanuc) -> Fanuc:
    """A fresh dialect of ``dialect``'s kind writing the same form (inline or compact)."""
    fresh = type(dialect)()
    fresh.compact = dialect.compact
    return fresh


def subprogram(text: str, s: ir.Setup, k: int) -> str:
    """A whole program's text as a subprogram of the driver: the tool change, the move to
    the clearance plane, the probe-on codes, ``POPEN`` and the ``PGSTART``/``PGCAL`` lines
    left to the driver (``G43 H`` stays, without a move), the ``PGEND`` line to ``M30``
    replaced by ``M99``."""
    lines = text.split("\n")
    popen = lines.index("POPEN")
    g43 = next(k for k, line in enumerate(lines[:popen])
               if line.startswith(f"G0 G43 H{s.tool_number} Z"))
    head = [line for line in lines[:g43] if line != f"T{s.tool_number} M6"]
    rest = lines[popen + 1:]
    while rest and rest[0].startswith(("DPRNT[PGSTART*", "DPRNT[PGCAL*")):
        rest.pop(0)
    end = next(k for k, line in enumerate(rest) if line.startswith("DPRNT[PGEND*"))
    m30 = rest.index("M30", end)
    note = f"(PART {k} OF O{s.program_number:04d}: RUN BY IT WITH M98, NOT ALONE)"
    return "\n".join([*head[:2], note, *head[2:], f"G43 H{s.tool_number}", *rest[:end],
                      "M99", *rest[m30 + 1:]])


def driver(dialect: Fanuc, program: ir.Program, parts: tuple[Part, ...]) -> str:
    """The program the operator runs: the unsplit header and footer, ``M98 P`` per part
    between them; its header comment names every part's file and features."""
    s = program.setup
    fresh = _like(dialect)  # compact too: the log header's format version is the parts'
    lines = fresh.generate(ir.Program(s, ())).split("\n")
    limit = fresh.line_limit()[0]
    notes = [f"(RUNS {len(parts)} PARTS WITH M98, FILES BESIDE IT:)"]
    for p in parts:
        ids = " ".join(p.features)
        note = f"({p.file_name.upper()}: {ids})"
        if len(note) > limit:
            note = f"({p.file_name.upper()}: {p.features[0]} TO {p.features[-1]})"
        notes.append(note)
    head = next(k for k, line in enumerate(lines) if k > 1 and not line.startswith("("))
    end = next(k for k, line in enumerate(lines) if line.startswith("DPRNT[PGEND*"))
    calls = [f"M98 P{p.number:04d}" for p in parts]
    return "\n".join([*lines[:head], *notes, *lines[head:end], *calls, *lines[end:]])
