"""``probegen init PART.step --machine M [-o SPEC.toml]``: a spec skeleton to start from.

The features are chosen by :func:`probegen.planning.skeleton.skeleton` (each one compiled
alone with the machine's stylus); this module writes them as TOML a user edits: every
feature with its nominal size and where it came from in a comment, a commented tolerance
line, and the features left out at the end with the reason.  The file is never
overwritten (:func:`probegen.files.write_file` with ``new``).
"""

from __future__ import annotations

import argparse
import os
import re
from pathlib import Path
from typing import Any

from probegen.cli.options import RAISED_HELP, non_negative
from probegen.errors import ExitCode
from probegen.files import write_file


def _init(args: argparse.Namespace) -> int:
    from probegen.cad import load_part
    from probegen.machine.profile import load_profile
    from probegen.planning.skeleton import skeleton

    target = Path(args.output or Path(args.model).with_suffix(".toml").name)
    if target.exists():  # before the planning, which takes a while on a large model
        write_file(target, "", "the spec skeleton", new=True)
    machine = load_profile(args.machine)
    part = load_part(args.model, raised=args.raised)
    found = skeleton(part, machine)
    text = skeleton_text(found, machine, target, args.model, args.machine, args.raised)
    write_file(target, text, "the spec skeleton", new=True)
    kinds = _counts(found)
    print(f"wrote {target}: {len(found.features)} features ({kinds}), "
          f"{len(found.left_out)} left out (listed at its end with the reason)")
    if not found.features:
        print(f"  no feature of {args.model} can be measured with this machine: a spec "
              "needs one [[feature]] at least to compile; the list says why each is out")
    return ExitCode.OK


def _counts(found: Any) -> str:
    names = {"RevolvedSpec": "revolved", "PlanarSpec": "planes", "FreeformSpec": "free-form"}
    counts = dict.fromkeys(names.values(), 0)
    for e in found.features:
        counts[names[type(e.feature).__name__]] += 1
    return ", ".join(f"{n} {k}" for k, n in counts.items())


def _relative(path: str, folder: Path) -> str:
    """``path`` relative to ``folder`` (the spec's), with ``/``."""
    return Path(os.path.relpath(Path(path).resolve(), folder.resolve())).as_posix()


def spec_head(model: str, profile: str, folder: Path, raised: float = 0.0) -> list[str]:
    """The ``[part]`` table and the start of ``[machine]`` (its ``profile``) of a spec
    written into ``folder``: ``model`` and ``profile`` as given on the command line,
    written relative to it, ``raised`` where not 0.  ``init``'s skeleton and ``plan
    --all-revolved -o``'s spec."""
    lift = [f"raised = {raised!r}   # mm above the machine table"] if raised else []
    return ["[part]", f"model = {toml_string(_relative(model, folder))}", 'units = "mm"',
            *lift, "", "[machine]", f"profile = {toml_string(_relative(profile, folder))}"]


def program_name(stem: str) -> str:
    """A program name the spec accepts (1-24 of ``A-Z 0-9 blank . _ -``) from a file stem."""
    name = re.sub(r"[^A-Z0-9 ._-]", "_", stem.upper())[:24].strip()
    return name or "PROBEGEN"


def skeleton_text(found: Any, machine: Any, target: Path, model: str, profile: str,
                  raised: float = 0.0) -> str:
    """The TOML text of a skeleton (:class:`probegen.planning.skeleton.Skeleton`) for the
    spec file ``target``; ``model`` and ``profile`` as given on the command line."""
    folder = target.parent
    ball = 2.0 * machine.probe.ball_radius
    lines = [
        f"# Spec skeleton of {Path(model).name}, written by probegen init for the machine",
        f"# profile {Path(profile).name} (stylus ball D{ball:.3f} mm). Each [[feature]] below",
        "# compiled alone with that stylus, collision check included, and the spec compiles",
        "# as it stands. Edit it: remove what you do not measure, rename the ids, uncomment",
        "# and set the tolerances (mm; a cone's angle in degrees). Recognised features left",
        "# out are listed at the end with the reason (docs/init.md).",
        f"# {len(found.features)} features ({_counts(found)}), {len(found.left_out)} left out.",
        "",
        *spec_head(model, profile, folder, raised),
        f"clearance_z = {found.clearance_z:.3f}   # at least 10 mm above the model "
        f"(the profile's: {machine.clearance_z:.3f})",
        "",
        "[program]",
        "number = 1001",
        f"name = {toml_string(program_name(Path(model).stem))}",
    ]
    for entry in found.features:
        lines += ["", f"# {entry.feature.id}: {entry.title} ({entry.source})", "[[feature]]",
                  *_keys(entry.feature), f"# tolerance = {entry.tolerance}"]
    if found.left_out:
        lines += ["", f"# Left out ({len(found.left_out)}): recognised, but not measurable "
                      "as they stand with this machine and stylus:"]
        lines += [f"#   {note}" for note in found.left_out]
    return "\n".join(lines) + "\n"


def _keys(feature: Any) -> list[str]:
    """The TOML keys of one skeleton feature (revolved, plane or free-form)."""
    out = [f"id = {toml_string(feature.id)}",
           f"kind = {toml_string(getattr(feature, 'kind', 'freeform'))}",
           f"face = {feature.face}"]
    if hasattr(feature, "contacts"):
        points = ", ".join(f"[{_num(p[0])}, {_num(p[1])}, {_num(p[2])}]"
                           for p in feature.contacts)
        out.append(f"contacts = [{points}]")
    if hasattr(feature, "grid"):
        d = feature.direction
        out += [f"grid = {toml_string(feature.grid)}",
                f"points = [{feature.counts[0]}, {feature.counts[1]}]",
                f"margin = {_num(feature.margin)}",
                f"direction = [{d[0]:.6f}, {d[1]:.6f}, {d[2]:.6f}]".replace("-0.000000",
                                                                            "0.000000")]
    return out


def _num(value: float) -> str:
    text = f"{value:.4f}"
    return "0.0000" if text == "-0.0000" else text


def toml_string(text: str) -> str:
    """A TOML basic string."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def add_init_command(sub: Any) -> None:
    """The ``init`` command's parser."""
    i = sub.add_parser("init", help="write a spec skeleton with every recognised feature of a "
                                    "model that the machine's stylus can measure")
    i.add_argument("model", help="the part model (STEP)")
    i.add_argument("--machine", required=True,
                   help="machine profile (TOML): its stylus and clearance decide what can "
                        "be measured")
    i.add_argument("-o", "--output",
                   help="the spec file to write (default: <model>.toml here; never "
                        "overwritten)")
    i.add_argument("--raised", type=non_negative, default=0.0, metavar="MM",
                   help=RAISED_HELP)
    i.set_defaults(func=_init)
