"""Named setups (issue 17, item 2): the part turned on the table, one program per setup.

The machine profile's ``[[setup]]`` tables (:class:`probegen.machine.profile.NamedSetup`)
name the ways the operator may turn the part: ``p_table = R·p_part + origin``.  Each
revolved feature of a spec is measured in one setup:

1. the one the spec forces (``setup = "NAME"``);
2. else the part as loaded (no transform), when the machine reaches the feature there
   (the vertical probe or an orientation of :mod:`probegen.planning.orient`);
3. else the first ``[[setup]]``, in profile order, in which it reaches it;
4. else the part as loaded, where it is planned as today (and refused with the reason).

Other kinds (sphere tests, lines, planes, free-form faces) stay in the part as loaded.

A setup's program is planned by :func:`probegen.planning.plan_program` on the part turned
(``part.turned(Rᵀ)``: :meth:`probegen.cad.Part.turned` takes ``p_frame = Rᵀ·p_work``, so
``Rᵀ`` of it gives ``p_table = R·p_part``; its model made a part of its own, so that a
feature of the setup that needs an orientation turns it further), the spec's points
turned with it: its work coordinates are the table frame.  Its program number is the
spec's plus the setup's place in the profile (1 for the first ``[[setup]]``), its name
the spec's with the setup's, and its header says the setup's name, rotation, origin and
fixture note.  A non-zero
``origin`` is refused (the operator sets the work offset at the part's datum again after
turning it; an origin would shift every coordinate of the program).

A profile without ``[[setup]]`` gives one program, exactly today's.
"""

from __future__ import annotations

import re
import textwrap
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, TypeVar

from probegen import ir
from probegen.errors import PlanningError, ProbegenError, SpecError
from probegen.ir import frames
from probegen.machine.profile import MachineProfile, NamedSetup
from probegen.planning.orient import Orientation, frame_clearance
from probegen.planning.oriented import plan_oriented
from probegen.spec.model import Feature, RevolvedSpec, Spec

if TYPE_CHECKING:
    from probegen.cad import Part
    from probegen.planning import PlannedProgram

AS_LOADED = "AS LOADED"
"""What the headers and tables call the part as loaded (the default setup)."""
HEADER_WIDTH = 72
"""Longest comment text of a setup header line (as planning/left_out.py's)."""


@dataclass(frozen=True, slots=True)
class SetupProgram:
    """One setup's program: the setup, its spec and the part as it lies.

    Attributes:
        setup: the profile's setup; None for the part as loaded.
        index: 0 for the part as loaded, else the setup's place in the profile (1-based).
        spec: the setup's spec: its features (points in the table frame), program number
            and name, clearance plane (above the turned part).
        part: the part as it lies on the table (``part.turned(Rᵀ)``; the part itself as
            loaded), or None for a spec without a model.
    """

    setup: NamedSetup | None
    index: int
    spec: Spec
    part: Part | None

    @property
    def name(self) -> str:
        """The setup's name; :data:`AS_LOADED` for the part as loaded."""
        return AS_LOADED if self.setup is None else self.setup.name

    @property
    def rotation(self) -> frames.Rotation:
        """``R``: part to table coordinates (the identity as loaded)."""
        return frames.IDENTITY if self.setup is None else self.setup.rotation

    @property
    def features(self) -> tuple[str, ...]:
        """The ids of the features this program measures."""
        return tuple(f.id for f in self.spec.features)

    def to_part(self, p: ir.Vec3) -> ir.Vec3:
        """Table point ``p`` in part coordinates: ``Rᵀ·(p − origin)``."""
        o = (0.0, 0.0, 0.0) if self.setup is None else self.setup.origin
        return frames.apply_t(self.rotation, (p[0] - o[0], p[1] - o[1], p[2] - o[2]))


def transpose(r: frames.Rotation) -> frames.Rotation:
    """``Rᵀ``."""
    return ((r[0][0], r[1][0], r[2][0]), (r[0][1], r[1][1], r[2][1]),
            (r[0][2], r[1][2], r[2][2]))


def setup_named(machine: MachineProfile, name: str) -> tuple[int, NamedSetup]:
    """The profile's setup called ``name`` and its place (1-based).

    Raises:
        SpecError: no setup has that name (the profile's names listed).
    """
    for k, s in enumerate(machine.setups, start=1):
        if s.name == name:
            return k, s
    known = ", ".join(s.name for s in machine.setups) or "none"
    raise SpecError(f"{machine.source}: setup: expected one of the profile's setups "
                    f"({known}), found {name!r}")


def check_origin(machine: MachineProfile, k: int, setup: NamedSetup) -> None:
    """Refuse a setup with a non-zero origin (see the module docstring).

    Raises:
        SpecError: names the setup and the origin.
    """
    if any(abs(v) > 0.0 for v in setup.origin):
        o = ", ".join(f"{v:g}" for v in setup.origin)
        raise SpecError(f"{machine.source}: setup[{k - 1}].origin: expected [0, 0, 0] (set "
                        f"the work offset at the part's datum after turning it; probegen "
                        f"does not shift a setup's program), found [{o}] in setup "
                        f"{setup.name}")


def table_part(part: Part | None, setup: NamedSetup | None) -> Part | None:
    """The part as it lies in ``setup``: the model of ``part.turned(Rᵀ)`` as a part of
    its own (kept on ``part``), so that its own :meth:`~probegen.cad.Part.turned` (an
    orientation of a feature in the setup) turns it further, from the table frame; the
    part itself for None."""
    if part is None or setup is None or frames.is_identity(setup.rotation):
        return part
    from probegen.cad import Part as Whole

    turned = part.turned(transpose(setup.rotation))
    return part.original.memo(("setup", setup.name, setup.rotation),
                              lambda: Whole(turned.model, raised=part.raised))


F = TypeVar("F", bound=Feature)


def in_setup(feature: F, setup: NamedSetup | None) -> F:
    """A feature as the setup's table frame sees it (``at`` turned: ``R·at``)."""
    if setup is None or not isinstance(feature, RevolvedSpec) or feature.at is None:
        return feature
    return replace(feature, at=frames.apply(setup.rotation, feature.at))


def setup_clearance(part: Part | None, setup: NamedSetup | None, clearance_z: float) -> float:
    """The clearance plane of a setup's program (table Z, mm): the turned part's top plus
    the gap the spec's plane has above the part as loaded (at least
    :data:`probegen.planning.orient.LEAST_GAP`)."""
    if setup is None or part is None:
        return clearance_z
    return frame_clearance(part, Orientation(transpose(setup.rotation)), clearance_z)


def reaches(feature: RevolvedSpec, part: Part | None, machine: MachineProfile,
            clearance_z: float) -> bool:
    """Whether the machine plans ``feature`` (in table coordinates) on ``part`` as it lies:
    the vertical probe or an orientation, with some stylus of the rack."""
    try:
        plan_oriented(feature, part, machine, clearance_z)
    except ProbegenError:
        return False
    return True


def assign(spec: Spec, part: Part | None) -> dict[str, int]:
    """The setup of each spec feature (0: as loaded, k: the profile's k-th), by id (see
    the module docstring for the rule; a feature whose ``setup`` is :data:`AS_LOADED`,
    as :func:`all_revolved_setups` marks those it planned as loaded, stays as loaded
    without a second trial).

    Raises:
        SpecError: a forced setup the profile does not have, or a setup with an origin.
    """
    machine = spec.machine
    out: dict[str, int] = {}
    for feature in spec.features:
        out[feature.id] = 0
        if not isinstance(feature, RevolvedSpec) or not machine.setups:
            continue
        if feature.setup == AS_LOADED:
            continue  # all_revolved_setups: planned as loaded already
        if feature.setup is not None:
            k, s = setup_named(machine, feature.setup)
            check_origin(machine, k, s)
            out[feature.id] = k
            continue
        if reaches(feature, part, machine, spec.clearance_z):
            continue
        for k, s in enumerate(machine.setups, start=1):
            check_origin(machine, k, s)
            if reaches(in_setup(feature, s), table_part(part, s), machine,
                       setup_clearance(part, s, spec.clearance_z)):
                out[feature.id] = k
                break
    return out


def program_name(spec: Spec, setup: NamedSetup | None) -> str:
    """A setup program's name: the spec's, its end cut to make room for the setup's name
    (at most 24 characters)."""
    if setup is None:
        return spec.program_name
    room = max(24 - len(setup.name) - 1, 0)
    return f"{spec.program_name[:room].rstrip()} {setup.name}".strip()[:24]


def split_setups(spec: Spec, part: Part | None) -> tuple[SetupProgram, ...]:
    """The programs of ``spec``: one per setup that has features, as loaded first, then
    the profile's order.  A profile without setups: one program, ``spec`` itself.

    Raises:
        SpecError: see :func:`assign`; a setup program's number outside the machine's
            range.
    """
    machine = spec.machine
    if not machine.setups:
        return (SetupProgram(None, 0, spec, part),)
    for k, named in enumerate(machine.setups, start=1):
        check_origin(machine, k, named)
    where = assign(spec, part)
    out: list[SetupProgram] = []
    for k, s in enumerate((None, *machine.setups)):
        features = tuple(in_setup(f, s) for f in spec.features if where[f.id] == k)
        if not features and (k > 0 or any(v > 0 for v in where.values())):
            continue  # no program for a setup without features (as loaded: unless alone)
        number = spec.program_number + k
        if k:
            machine.check_program_number(number, f"{spec.source}: program.number + {k} "
                                                 f"(setup {s.name if s else ''})")
        local = replace(spec, features=features, program_number=number,
                        program_name=program_name(spec, s),
                        clearance_z=setup_clearance(part, s, spec.clearance_z))
        out.append(SetupProgram(s, k, local, table_part(part, s)))
    return tuple(out)


def _clean(text: str) -> str:
    """Upper-case ASCII a Fanuc comment takes (no parentheses)."""
    text = re.sub(r"[^A-Z0-9 .,:;+=/_-]", " ", text.upper())
    return " ".join(text.split())


def _number(v: float) -> str:
    return f"{round(v, 6) + 0.0:g}"


def header_comments(sp: SetupProgram, programs: tuple[SetupProgram, ...]
                    ) -> tuple[ir.Comment, ...]:
    """The comment block of a setup program's header: the setup's name and place among
    the programs, the part's rotation (G68.2-style Euler angles Z-X-Z and the matrix
    rows, part to table) and origin, the fixture note (``TURN THE PART: ...``) and the
    features it measures; upper-case ASCII, lines of at most :data:`HEADER_WIDTH`."""
    others = ", ".join(f"O{p.spec.program_number:04d} {p.name}" for p in programs)
    lines = [f"SETUP {sp.name}: PROGRAM {programs.index(sp) + 1} OF {len(programs)}: "
             f"{others}"]
    if sp.setup is not None:
        s = sp.setup
        i, j, k = frames.euler_zxz(s.rotation)
        rows = " / ".join(" ".join(_number(v) for v in row) for row in s.rotation)
        lines += [f"PART TO TABLE: EULER ZXZ I{_number(i)} J{_number(j)} K{_number(k)}",
                  f"ROTATION ROWS {rows}",
                  f"ORIGIN X{_number(s.origin[0])} Y{_number(s.origin[1])} "
                  f"Z{_number(s.origin[2])}",
                  f"TURN THE PART: {s.note or 'SEE THE SETUP ' + s.name}"]
    else:
        lines.append("THE PART AS LOADED: NO TURN")
    lines.append(f"FEATURES: {' '.join(sp.features)}")
    out: list[str] = []
    for line in lines:
        out += textwrap.wrap(_clean(line), HEADER_WIDTH, subsequent_indent="  ",
                             break_long_words=True) or [""]
    return tuple(ir.Comment(t) for t in out)


def plan_setups(spec: Spec, *, runtime_variables: bool, part: Part | None,
                progress: Callable[[int], None] | None = None,
                check_collisions: bool = True
                ) -> tuple[tuple[SetupProgram, PlannedProgram], ...]:
    """Plan each setup's program (:func:`split_setups`,
    :func:`probegen.planning.plan_program`); with setups in the profile, each program
    with its setup header (:func:`header_comments`) at the head of its body.  A profile
    without setups: today's one program, unchanged."""
    from probegen.planning import plan_program

    programs = split_setups(spec, part)
    out = []
    for sp in programs:
        try:
            planned = plan_program(sp.spec, runtime_variables=runtime_variables,
                                   progress=progress, check_collisions=check_collisions,
                                   part=sp.part)
        except PlanningError as exc:
            raise PlanningError(setup_hint(str(exc), spec.machine)) from exc
        if spec.machine.setups:
            program = ir.Program(planned.program.setup,
                                 (*header_comments(sp, programs), *planned.program.body))
            planned = replace(planned, program=program)
        out.append((sp, planned))
    return tuple(out)


ASKS = re.compile(r"\ba setup\b|\bno orientation\b|\bneeds an orientation\b")
"""A left-out line that a turn of the part might answer (the setups' reasons follow it)."""
HINT = "add a [[setup]] to the machine profile"
"""What a reason that asks for a setup adds: the profile key."""


def setup_hint(reason: str, machine: MachineProfile) -> str:
    """``reason`` (a planner's message or a left-out line) with the profile key named
    where it asks for a setup: ``...: needs a setup: add a [[setup]] to the machine
    profile`` (the setups it has, when it has some: none of them reaches it)."""
    if not re.search(r"\ba setup\b", reason) or HINT in reason:
        return reason
    tried = ", ".join(s.name for s in machine.setups)
    hint = HINT + (f" (none of its setups {tried} reaches it)" if tried else "")
    detail = re.search(r" \[.*\]$", reason)
    if detail is None:
        return f"{reason}: {hint}"
    return f"{reason[:detail.start()]}: {hint}{reason[detail.start():]}"


def all_revolved_setups(part: Part, machine: MachineProfile
                        ) -> tuple[Spec, tuple[str, ...]]:
    """``plan --all-revolved`` with setups: the features of
    :func:`probegen.planning.revolved_spec.all_revolved_spec` (as loaded), then for each
    ``[[setup]]`` in order the recognised features left out as loaded (and by the setups
    before it) that the part turned so brings within reach
    (:func:`probegen.planning.revolved_spec.all_revolved` on ``part.turned(Rᵀ)``, those
    features only), each with ``setup = NAME`` and the id it has as loaded (those as
    loaded with ``setup =`` :data:`AS_LOADED`: :func:`assign` need not try them again);
    the notes of
    the features still left out, the profile key named where they ask for a setup
    (:func:`setup_hint`), each followed by why every setup that was tried does not reach
    it where the line as loaded asks for a setup or an orientation (``...; in setup
    FLIPPED: <reason>``); a profile without setups: exactly
    ``all_revolved_spec``'s."""
    from probegen.cad.revolved import revolved_features
    from probegen.planning.revolved_spec import all_revolved, all_revolved_spec

    spec, notes = all_revolved_spec(part, machine)
    if not machine.setups:
        return spec, notes  # as today (the lines already say "a setup")
    ids = {face: f"R{f.id}" for f in revolved_features(part) for face in f.faces}
    left = {n.split(" ", 1)[0] for n in notes}
    taken: set[str] = {f.id for f in spec.features}
    extra: list[RevolvedSpec] = []
    why: dict[str, list[str]] = {}
    for k, s in enumerate(machine.setups, start=1):
        check_origin(machine, k, s)
        turned = table_part(part, s)
        assert turned is not None
        faces = frozenset(face for face, fid in ids.items() if fid in left and fid not in taken)
        if not faces:
            break  # every feature is in a program already
        found, missed = all_revolved(turned, machine,
                                     setup_clearance(part, s, spec.clearance_z), faces=faces)
        for f in found:
            fid = ids.get(f.face or 0)
            if fid is None or fid in taken or fid not in left:
                continue
            taken.add(fid)
            extra.append(replace(f, id=fid, setup=s.name))
        for fid, reason in _reasons(turned, ids, missed):
            why.setdefault(fid, []).append(f"in setup {s.name}: {reason}")
    kept = tuple("; ".join([setup_hint(n, machine),
                            *(why.get(n.split(" ", 1)[0], []) if ASKS.search(n) else [])])
                 for n in notes if n.split(" ", 1)[0] not in taken)
    loaded = tuple(replace(f, setup=AS_LOADED) if isinstance(f, RevolvedSpec) else f
                   for f in spec.features)
    return replace(spec, features=(*loaded, *extra)), kept


def _reasons(turned: Part, ids: dict[int, str], notes: tuple[str, ...]
             ) -> list[tuple[str, str]]:
    """The left-out lines of a setup's turned part as (the feature's id as loaded, the
    reason: the line after its head ``R<n> kind D.. (type, faces ..): ``); lines of
    features recognised otherwise on the turned part (no face in common) dropped."""
    from probegen.cad.revolved import revolved_features

    faces = {f"R{f.id}": f.faces for f in revolved_features(turned)}
    out = []
    for n in notes:
        head, _, reason = n.partition("): ")
        loaded = {ids[face] for face in faces.get(head.split(" ", 1)[0], ()) if face in ids}
        if len(loaded) == 1 and reason:
            out.append((loaded.pop(), reason))
    return out


def setup_file(target: str, sp: SetupProgram, first: bool) -> str:
    """The file of a setup's program: ``target`` for the first program,
    ``<stem>_<SETUP><ext>`` beside it for the others (``target`` a path text)."""
    if first:
        return target
    from pathlib import Path

    path = Path(target)
    return str(path.with_name(f"{path.stem}_{sp.name.replace(' ', '_')}{path.suffix}"))
