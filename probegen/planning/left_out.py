"""Why a recognised feature is left out, in words the user can act on (issue 17, item 5).

One line per feature: ``R12 bore D1.600 (cylinder, faces 34): bore D1.600: the stylus
ball D6.000 needs D8.000 or more: a smaller stylus``.  The line names the feature (id,
what it is with its nominal size, its type and faces), then the reason with its numbers
and what would make it measurable (a smaller stylus, an orientation or a setup); where the
planner's own message says more (a collision: the move, the stylus part and the face), it
follows in brackets.  :func:`revolved_left_out` serves ``plan --all-revolved`` (the table
and the program header) and ``probegen init`` (the skeleton's comments);
:func:`header_comments` turns the lines into the comment block of a program header.
"""

from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING, Any

from probegen import ir
from probegen.machine.profile import MachineProfile
from probegen.planning.styli import own_reason, smallest_stylus

if TYPE_CHECKING:
    from probegen.cad import Part

_ARCS = re.compile(r"end margin ([\d.]+) mm, found arcs of ([\d., ]+?) mm")
_SMALL = re.compile(r"inner radius ([\d.]+) mm: the safe circle R - r - d = [-\d.]+ mm: "
                    r"expected R > r \+ d")
_ELEMENT = r"the (stylus ball|stylus shank|stylus holder|probe body)(?: cuts ([\d.]+) mm)?"
"""The stylus element a collision message names, and how deep it cuts (if it says)."""
_HIT = re.compile(_ELEMENT + r"[^;]*?(?:into|of) face (\d+)")
_TABLE = re.compile(_ELEMENT + r"[^;]*?(?:into|of) the table")
_TILTED = re.compile(r"at the nearest head index \w+ the stylus stands [\d.]+ deg off the "
                     r"feature's axis")
_CLIMB = re.compile(r"approach from \([^,]+, [^,]+, ([-\d.]+)\) to \([^,]+, [^,]+, ([-\d.]+)\)")
LONGEST = 240
"""A planner's message longer than this (characters) is cut (a free-form face lists
every guide point it leaves out)."""
HEADER_WIDTH = 72
"""Longest comment text of a program header line (the Fanuc block limit is 80)."""


def describe(f: Any) -> str:
    """What a recognised revolved feature is, with its nominal size: ``bore D10.000``,
    ``boss D20.000``, ``inner cone D8.000``, ``outer sphere D25.000``, ``torus D35.000
    tube D3.000``."""
    size = f"D{2.0 * f.radius:.3f}"
    if f.type == "cylinder":
        return f"{'bore' if f.inner else 'boss'} {size}"
    if f.type == "torus":
        return f"torus {size} tube D{2.0 * (f.minor_radius or 0.0):.3f}"
    return f"{'inner' if f.inner else 'outer'} {f.type} {size}"


def revolved_left_out(f: Any, part: Part, machine: MachineProfile, problem: str,
                      least: float) -> str:
    """The line of revolved feature ``f`` left out: ``problem`` is the recognition's
    reason (not accessible) or the planner's message (it does not plan, or collides);
    ``least`` the smallest bore diameter the stylus takes, mm
    (:func:`probegen.planning.revolved_spec.smallest_bore`)."""
    head = f"R{f.id} {describe(f)} ({f.type}, faces {','.join(map(str, f.faces))})"
    reasons = []
    if f.type not in ("cylinder", "cone", "sphere", "torus"):
        reasons.append(f"a {f.type}: no spec kind measures it")
    from probegen.cad.revolved_sections import VERTICAL

    tilt = math.degrees(math.acos(min(1.0, abs(f.axis[2]))))
    turns = (machine.head is not None or machine.tilt is not None) and f.type != "sphere"
    if math.hypot(f.axis[0], f.axis[1]) > VERTICAL and not turns:
        reasons.append(f"axis ({f.axis[0]:.4f}, {f.axis[1]:.4f}, {f.axis[2]:.4f}) is "
                       f"{tilt:.1f} deg from Z, not along the probe: needs an orientation "
                       "or a setup")
    if f.inner and f.type == "cylinder" and 2.0 * f.radius < least:
        reasons.append(f"bore D{2.0 * f.radius:.3f}: {_needs(machine, least)}: a smaller "
                       "stylus")
    if reasons:
        return f"{head}: {'; '.join(reasons)}"
    return f"{head}: {_planning_reason(f, part, machine, problem, least)}"


def _needs(machine: MachineProfile, least: float) -> str:
    """``the smallest stylus D2 (ball D2.000) needs D4.000 or more, the ball and 1.000 mm
    each side for the retract and safe circle``: what the smallest bore ``least`` (mm) is
    made of."""
    side = least / 2.0 - smallest_stylus(machine).ball_radius
    return (f"{_smallest_text(machine)} needs D{least:.3f} or more, the ball and "
            f"{side:.3f} mm each side for the retract and safe circle")


def _smallest_text(machine: MachineProfile) -> str:
    """``the stylus ball D6.000`` (no rack), ``the smallest stylus D1 (ball D1.000)``."""
    s = smallest_stylus(machine)
    if not machine.rack:
        return f"the stylus ball D{s.ball_diameter:.3f}"
    return f"the smallest stylus {s.label} (ball D{s.ball_diameter:.3f})"


def _planning_reason(f: Any, part: Part, machine: MachineProfile, problem: str,
                     least: float) -> str:
    """The reason of an accessible feature that does not plan or collides (the smallest
    stylus's, :func:`probegen.planning.styli.own_reason`)."""
    r, m = smallest_stylus(machine).ball_radius, machine.margin
    problem = own_reason(problem)
    if "closed above" in problem:
        return f"{_after(problem, 'closed above')}: reach it from below: needs a setup"
    small = _SMALL.search(problem)
    if small:
        return (f"{describe(f)} is D{2.0 * float(small[1]):.3f} where it is measured: "
                f"{_needs(machine, least)}: a smaller stylus")
    arcs = _ARCS.search(problem)
    if arcs:
        return _arc_reason(max(float(a) for a in arcs[2].split(", ")), float(arcs[1]), r, m)
    tilted = _TILTED.search(problem)
    if tilted is not None and _HIT.search(problem):
        rest = problem[tilted.end():].removeprefix(": it collides: ")
        return f"{tilted[0]}: {collision_reason(rest)}"
    if "no touch can be reached safely" in problem or "collides" in problem:
        depth = _blind_depth(f, part)
        if depth is not None and depth < r + m:
            return (f"blind, depth {depth:.3f} mm: the ball reaches no section (it needs "
                    f"{r + m:.3f} mm below one: radius {r:.3f} + margin {m:.3f}): a smaller "
                    f"stylus [{_detail(problem)}]")
        table = _TABLE.search(problem)
        if table is not None and _HIT.search(problem) is None:
            deep = f" {table[2]} mm" if table[2] else ""
            return (f"no room above the table: the {table[1]} reaches{deep} into the table "
                    "the part stands on (state how far it is raised: [part] raised, "
                    f"--raised; or a smaller stylus) [{_detail(problem)}]")
        climbs = [float(b) > float(a) for a, b in _CLIMB.findall(problem)]
        if climbs and all(climbs):
            return ("faces down: every touch goes up, under material: needs an orientation "
                    f"or a setup [{_detail(problem)}]")
        if _HIT.search(problem):
            return f"no touch can be reached safely: {collision_reason(problem)}"
    return _clean(problem)


def _arc_reason(longest: float, end: float, r: float, m: float) -> str:
    """The reason of a section's arcs too short (mm: the ``longest`` arc, the smallest
    stylus's full end margin ``end`` = ball radius ``r`` + margin ``m``).  The planner
    retries a short arc with the margin alone at each end
    (:func:`probegen.planning.revolved_plan.plan_revolved`), which no ball changes: an
    arc no longer than twice the margin is too short for every stylus (the part's limit
    with this margin), not a stylus too large."""
    if longest <= 2.0 * m + 1e-9:
        return (f"arc too short: the longest arc of the section measured is {longest:.3f} "
                f"mm, no longer than the margin {m:.3f} mm that every stylus keeps from "
                f"each end ({2.0 * m:.3f} mm): the part's limit with the profile's margin")
    return (f"arc too short: the longest arc of the section measured is {longest:.3f} "
            f"mm, the ball D{2.0 * r:.3f} needs {2.0 * end:.3f} mm (its radius and the "
            f"margin {end - r:.3f} mm at each end): a smaller stylus")


def collision_reason(problem: str) -> str:
    """A planner's or collision check's message as a reason: the stylus part and the face
    it meets first, then the detail in brackets; the cleaned message otherwise."""
    hit = _HIT.search(problem)
    if hit is None:
        text = _clean(problem)
        return text if len(text) <= LONGEST else text[:LONGEST - 5].rstrip() + " ..."
    if hit[1] == "probe body":  # above the stylus: a longer one lifts it
        deep = f", {hit[2]} mm deep" if hit[2] else ""
        return (f"no room: the probe body meets face {hit[3]}{deep} (a longer stylus, or "
                f"another orientation) [{_detail(problem)}]")
    return (f"no room: the {hit[1]} meets face {hit[3]} (a smaller or longer stylus, "
            f"or another orientation) [{_detail(problem)}]")


def _blind_depth(f: Any, part: Part) -> float | None:
    """The depth of a cylinder closed at one end only, mm (None for anything else): a
    bore with a bottom, a boss rising from a floor, the wall of a shallow groove or of a
    letter engraved in a face, along any axis.  An end is closed where the material lies
    just past it, beside the wall on its air side (at the middle of the first arc of the
    section: :data:`BLIND_PROBE` inside a bore's wall, outside a boss's)."""
    if f.type != "cylinder":
        return None
    import numpy as np

    from probegen.geometry.frames import rotation_to_z

    frame = rotation_to_z(f.axis)  # the azimuth frame of the feature's arcs
    sections = getattr(f, "sections", ())
    arcs = sections[0].arcs if sections else ()
    phi = 0.5 * (arcs[0][0] + arcs[0][1]) if arcs else 0.0
    inset = min(BLIND_PROBE, 0.25 * f.radius)
    radial = (f.radius - inset if f.inner else f.radius + inset) * (
        math.cos(phi) * frame[0] + math.sin(phi) * frame[1])
    axis = np.asarray(f.axis)
    low, high = f.extent
    closed = [part.exact.inside(np.asarray(f.centre_at(h)) + radial + step * axis)
              for h, step in ((low, -BLIND_PROBE), (high, BLIND_PROBE))]
    return f.length if closed[0] != closed[1] else None


BLIND_PROBE = 0.05
"""How far past an end of a cylinder (and beside its wall) :func:`_blind_depth` looks for
material, mm."""


def _after(text: str, word: str) -> str:
    return text[text.index(word):]


def _clean(problem: str) -> str:
    """The planner's message without the file and feature prefixes it carries."""
    text = re.sub(r"^.*?: revolved feature \d+: ", "", problem)
    return re.sub(r"^feature R\d+: ", "", text)


def _detail(problem: str) -> str:
    """The planner's message, cleaned: its first item and how many more touches were
    dropped."""
    text = _clean(problem)
    dropped = len(re.findall(r"touch(?:es)? [\d-]+ dropped", text))
    first = text.split("; ", 1)[0]
    return first + (f"; {dropped - 1} more touches dropped" if dropped > 1 else "")


def header_comments(left_out: tuple[str, ...]) -> tuple[ir.Comment, ...]:
    """The comment block of a program header listing the features left out: upper-case
    ASCII, no parentheses (Fanuc comments cannot nest them), each line at most
    :data:`HEADER_WIDTH` characters, the bracketed planner detail dropped."""
    if not left_out:
        return ()
    lines = [f"LEFT OUT {len(left_out)} RECOGNISED FEATURES:"]
    for note in left_out:
        short = re.sub(r" \[.*\]$", "", note)
        text = re.sub(r"[^A-Z0-9 .,:;+=/_-]", " ", short.upper().replace("(", "").replace(
            ")", ""))
        text = " ".join(text.split())
        lines += _wrap(text)
    return tuple(ir.Comment(line) for line in lines)


def _wrap(text: str) -> list[str]:
    """``text`` in lines of at most :data:`HEADER_WIDTH` characters, the next ones
    indented."""
    out: list[str] = []
    line = ""
    for word in text.split():
        candidate = f"{line} {word}" if line else word
        if len(candidate) > HEADER_WIDTH and line:
            out.append(line)
            line = "  " + word
        else:
            line = candidate
    out.append(line)
    return out
