"""``probegen post`` on files: read the DMIS program, post it, write the program and map.

The part model is placed in the DMIS program's machine coordinates (the machine tool's
work coordinates) by a translation, ``model_offset`` (mm): the NIST DCX program wants
its part's origin at (355, 91, -80), the simple part sits at the origin.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from probegen import ir
from probegen.dialects import get_dialect
from probegen.dmis.reader import read_dmis_all
from probegen.errors import UnsupportedError
from probegen.files import write_file
from probegen.ir.identity import map_identity
from probegen.machine.profile import MachineProfile
from probegen.planning.collision import mesh_obstacle
from probegen.post.featuremap import FeatureMap, dumps, feature_map
from probegen.post.frontend import PostedProgram, post_dmis

if TYPE_CHECKING:
    from probegen.cad import Part

Vec3 = tuple[float, float, float]

MAP_SUFFIX = ".features.json"
"""The feature map is written next to the program: ``<program stem>.features.json``."""

_NAME = re.compile(r"[^A-Z0-9]")


@dataclass(frozen=True, slots=True)
class PostOutput:
    """What ``post_file`` produced: the program text, its feature map and the IR result."""

    text: str
    fmap: FeatureMap
    posted: PostedProgram


def program_name(path: str | Path) -> str:
    """A program name from a file name: upper case letters and digits, at most 16."""
    return _NAME.sub("", Path(path).stem.upper())[:16] or "DMIS"


def post_file(program: str | Path, machine: MachineProfile, part: Part, *,
              dialect: str, offset: Vec3 = (0.0, 0.0, 0.0), skip_unsupported: bool = False,
              reroute: bool = False, number: int = 1001,
              answers: dict[str, str | int | float] | None = None) -> PostOutput:
    """Post DMIS file ``program`` for ``machine`` with the loaded ``part`` (the command
    loads it: :func:`probegen.cad.load_part`) at ``offset``.

    Raises:
        ProgramParseError: the DMIS file does not parse (every bad statement listed).
        UnsupportedError, DmisProgramError, CollisionError: see ``post_dmis``.
    """
    target = get_dialect(dialect)
    if not target.RUNTIME_VARIABLES:
        raise UnsupportedError(f"post: dialect {dialect!r} is not a machine-tool dialect "
                               "with a DPRNT-style log; expected fanuc, haas or linuxcnc")
    parsed = read_dmis_all(program)
    posted = post_dmis(parsed, machine, obstacle=mesh_obstacle(part, offset),
                       skip_unsupported=skip_unsupported, reroute=reroute,
                       number=number, name=program_name(program), answers=answers)
    data = Path(program).read_bytes()  # read_dmis read it just now
    fmap = feature_map(posted, data, str(program), dialect)
    setup = replace(posted.program.setup, identity=map_identity(fmap.text, fmap.touches))
    text = target.generate(ir.Program(setup, posted.program.body))
    return PostOutput(text, fmap, posted)


def write_post(out: PostOutput, target: Path) -> Path:
    """Write the program to ``target`` and its feature map next to it; return the map's path."""
    write_file(target, out.text, "the posted program", encoding="ascii")
    map_path = target.with_name(target.stem + MAP_SUFFIX)
    write_file(map_path, dumps(out.fmap), "the feature map")
    return map_path
