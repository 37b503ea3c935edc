"""Benchmark: every measurable revolved feature of real parts, with the right stylus and
from any side (issue 17, "done when").

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_real_parts.py [options] [MODEL ...]

Without models: every ``../shared/ref/nist-step/*.stp``, ``../shared/ref/parts/*.step``,
the DCX part and ``samples/parts/*.step``.  Per model and machine profile (the CMM
``samples/machines/cmm.toml`` to DMIS, the five-axis ``samples/machines/vmc-5axis-fanuc.toml``
to Fanuc, each with its ``[[setup]]`` FLIPPED; a stand-in profile written into a temporary
folder where the sample is not there, see :data:`STAND_INS`), what ``probegen plan MODEL
--all-revolved --machine PROFILE -d DIALECT -o DIR`` writes, by the same functions
(``planning.setups.all_revolved_setups`` + ``plan_setups``, ``cli.plan.program_text``):
one program per setup that has features (docs/setups.md).  Prints per model and profile:

* *recognised*: the revolved features (``probegen.cad.revolved.revolved_features``);
* *fillets*: a cylinder, sphere or torus of radius under :data:`FILLET_RADIUS` (a
  torus: its tube) that covers under half a turn (:func:`turn`);
* *narrow*: a bore narrower than the smallest bore of the rack's smallest stylus
  (``smallest_bore(machine.with_stylus(smallest))``);
* *eligible*: the others, the issue's denominator;
* *planned*: the features some setup's program measures (each once), and of those the
  eligible ones (the line per model says how many each setup holds); the share
  planned / eligible (the goal: 90 % with the CMM, 80 % with the five-axis);
* *left out by reason*: the eligible features no setup's program measures, grouped by
  the reason of their line once every setup was tried (``probegen.planning.left_out``;
  :func:`reason_of`); ``lost``: in no program and on no line (a bug);
* the time: load and recognition, planning, emitting, wall clock (and CPU).

Options: ``--profile cmm`` or ``--profile 5axis`` (default both), ``--vm`` runs each
setup's program on the virtual CMM or machine as ``probegen sim PROGRAM --part MODEL
--machine PROFILE --setup SETUP`` does (the part at its nominal place turned as the setup
says, a perfect probe, the profile's rack and trunnion), ``--json PATH`` writes the
figures, ``--notes`` prints every left-out line, ``--raised MM`` stands every part that far
above the machine table (parallels; the collision check's table, docs/spec.md; default 0,
on it).  Every DMIS program's ``PTMEAS`` points
are checked on the model (the setup's turned model for a setup's program): on it within
1 um, with the vector pointing out of the material (``benchmarks/points_on_model.py``).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import tempfile
import time
import traceback
import warnings
from collections import Counter
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "benchmarks"))

from points_on_model import PointsCheck, check_points  # noqa: E402

SHARED = REPO.parent / "shared" / "ref"
DCX = SHARED / "nist-ippdme/DCXpart/STEP_AP214/DaimlerChryslerTestPartAP214.stp"
BASE = REPO / "samples/machines/vmc-fanuc.toml"

FILLET_RADIUS = 3.0
"""A fillet has a radius under this, mm (a torus: its tube radius)."""
HALF_TURN = math.pi
"""... and covers under half a turn, rad."""


def default_models() -> list[Path]:
    """The NIST models, the open-hardware parts, the DCX part and our own parts."""
    return [*sorted((SHARED / "nist-step").glob("*.stp")),
            *sorted((SHARED / "parts").glob("*.step")), DCX,
            *sorted((REPO / "samples/parts").glob("*.step"))]


# ------------------------------------------------------------------ profiles

@dataclass(frozen=True)
class ProfileCase:
    """A machine profile and the dialect its programs are written in."""

    key: str
    sample: Path
    dialect: str
    kind: str
    """The virtual machine that runs its programs: ``dmis`` or ``macrob``."""


CASES = {
    "cmm": ProfileCase("cmm", REPO / "samples/machines/cmm.toml", "dmis", "dmis"),
    "5axis": ProfileCase("5axis", REPO / "samples/machines/vmc-5axis-fanuc.toml", "fanuc",
                         "macrob"),
}

_RACK = {"cmm": (("D3", 3.0, 2.0, 40.0, 1), ("D1", 1.0, 0.7, 20.0, 0),
                 ("D2", 2.0, 1.4, 30.0, 0), ("D6", 6.0, 4.5, 50.0, 0)),
         "5axis": (("D6", 6.0, 4.5, 50.0, 20), ("D3", 3.0, 2.0, 40.0, 21),
                   ("D2", 2.0, 1.4, 30.0, 22))}
"""Stand-in racks: (label, ball, shank, length, tool number); the first is [probe]'s."""
STAND_INS = {
    "cmm": ('name = "Stand-in bridge CMM, PH10-like head (bench_real_parts)"',
            'dialect = "dmis"', 0.3, "\n[head]\na = [0.0, 105.0]\nb = [-180.0, 180.0]\n"
            "step = 7.5\nbody_diameter = 14.0\nbody_length = 65.0\n"),
    "5axis": ('name = "Stand-in trunnion five-axis, Fanuc G68.2 (bench_real_parts)"',
              'dialect = "fanuc"', 0.5, '\n[tilt]\ncommand = "G68.2"\ntilt_axis = "A"\n'
              'rotary_axis = "C"\ntilt_range = [-110.0, 110.0]\n'),
}
"""Stand-in profiles (design17.md's keys) made from samples/machines/vmc-fanuc.toml while
the samples are not on this branch: name, dialect, margin (mm), the head or tilt table;
the styli, margins and head are those of the samples the ``rack`` lane wrote."""


def stand_in_text(key: str) -> str:
    """The stand-in profile's TOML: vmc-fanuc.toml with another name, dialect, margin,
    [probe] stylus, the rack, and a head (CMM) or a tilted plane (five-axis)."""
    name, dialect, margin, extra = STAND_INS[key]
    text = BASE.read_text(encoding="utf-8")
    text = re.sub(r'^name = ".*"$', name, text, count=1, flags=re.M)
    text = re.sub(r'^dialect = ".*"$', dialect, text, count=1, flags=re.M)
    text = re.sub(r"^margin = [\d.]+", f"margin = {margin}", text, count=1, flags=re.M)
    label, ball, shank, length, tool = _RACK[key][0]
    for k, v in (("ball_diameter", ball), ("shank_diameter", shank), ("length", length),
                 ("tool_number", tool)):
        text = re.sub(rf"^{k} = [\d.]+", f"{k} = {v}", text, count=1, flags=re.M)
    if key == "5axis":
        text = text.replace('options = ["G68", "#3004"]', 'options = ["G68", "G68.2", "#3004"]')
    rack = "".join(f'\n[[probe.stylus]]\nlabel = "{s[0]}"\nball_diameter = {s[1]}\n'
                   f"shank_diameter = {s[2]}\nlength = {s[3]}\ntool_number = {s[4]}\n"
                   for s in _RACK[key])
    return text + rack + extra


def load_case(case: ProfileCase, folder: Path) -> tuple[Any, Path, str]:
    """The case's profile, its file and where it came from: the sample when it exists,
    else the stand-in written into ``folder`` (its rack, head and tilt set on the loaded
    record when this branch's parser does not know the keys yet; the file then holds
    the rest, for ``probegen sim``)."""
    from probegen.errors import ProbegenError
    from probegen.machine.profile import Head, Stylus, Tilt, load_profile

    if case.sample.exists():
        return load_profile(case.sample), case.sample, str(case.sample.relative_to(REPO))
    path = folder / f"stand-in-{case.key}.toml"
    text = stand_in_text(case.key)
    path.write_text(text, encoding="utf-8")
    try:
        return load_profile(path), path, "stand-in (keys parsed)"
    except ProbegenError:
        pass
    base = text.split("\n[[probe.stylus]]", 1)[0]
    path.write_text(base, encoding="utf-8")
    rack = tuple(Stylus(*s) for s in _RACK[case.key])
    profile = replace(load_profile(path), rack=rack,
                      head=Head(body_diameter=14.0, body_length=65.0)
                      if case.key == "cmm" else None,
                      tilt=Tilt() if case.key == "5axis" else None)
    return profile, path, "stand-in (rack, head/tilt set on the record)"


# ------------------------------------------------------------------ eligibility

def turn(f: Any) -> float:
    """How far round its axis a feature goes, rad: the most of any default section's
    arcs (2π for a full circle); a torus: the least of that and its tube's sweep (the
    faces lie on one half of the tube, so an axial extent of ``length`` spans
    ``2·asin(length / 2 / tube)`` at least)."""
    around = max((sum(b - a for a, b in s.arcs) for s in f.sections), default=2.0 * math.pi)
    if f.type != "torus" or not f.minor_radius:
        return around
    tube = 2.0 * math.asin(min(1.0, f.length / 2.0 / f.minor_radius))
    return min(around, tube) if f.length < 2.0 * f.minor_radius - 1e-6 else around


def is_fillet(f: Any) -> bool:
    """A cylinder, sphere or torus of radius (tube) under :data:`FILLET_RADIUS` that
    covers under half a turn."""
    if f.type not in ("cylinder", "sphere", "torus"):
        return False
    radius = f.minor_radius if f.type == "torus" else f.radius
    return bool(radius is not None and radius < FILLET_RADIUS and turn(f) < HALF_TURN - 1e-6)


def least_bore(machine: Any) -> float:
    """The smallest bore diameter the rack's smallest stylus measures, mm."""
    from probegen.planning.revolved_spec import smallest_bore
    from probegen.planning.styli import smallest_stylus

    smallest = smallest_stylus(machine)
    return float(smallest_bore(machine.with_stylus(smallest)))


def is_narrow(f: Any, least: float) -> bool:
    """A bore narrower than ``least`` mm."""
    return bool(f.inner and f.type == "cylinder" and 2.0 * f.radius < least - 1e-9)


def eligibility(part: Any, machine: Any) -> tuple[set[int], set[int], set[int]]:
    """The ids of the part's recognised revolved features that are fillets, narrow bores
    (not fillets) and eligible (the others), for ``machine``'s rack."""
    from probegen.cad.revolved import revolved_features

    features = revolved_features(part)
    least = least_bore(machine)
    fillets = {f.id for f in features if is_fillet(f)}
    narrow = {f.id for f in features if f.id not in fillets and is_narrow(f, least)}
    return fillets, narrow, {f.id for f in features} - fillets - narrow


# ------------------------------------------------------------------ reasons

REASONS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("table", ("no room above the table",)),
    ("too few touches", ("too few touches to evaluate",)),
    ("free fit", ("a free ",)),
    ("head grid", ("deg grid",)),
    ("orientation", ("not along the probe", "needs an orientation", "faces down",
                     "no orientation", "beyond the")),
    ("setup", ("needs a setup", "closed above")),
    ("blind depth", ("blind, depth", "blind depth")),
    ("arc too short", ("arc too short",)),
    ("stylus too large", ("a smaller stylus", "or more:", "smallest stylus")),
    ("collision", ("no room", "collides", "no touch can be reached safely")),
    ("not accessible", ("not accessible", "centre lies in material", "no arc of the section",
                        "no open end")),
    ("no spec kind", ("no spec kind",)),
)
"""Reason classes of a left-out line, tried in this order against the line's first
reason (the text after the feature's head)."""


def reason_of(line: str) -> str:
    """The class of a left-out line (``planning.left_out`` wording): of its first reason
    as loaded; where that is *orientation* or *setup* and the line says why the setups
    tried do not reach the feature either (``...; in setup FLIPPED: <reason>``,
    ``planning.setups.all_revolved_setups``), of the first setup's reason that is not
    (what stops it once the part is turned), else the first."""
    body = line.split("): ", 1)[1] if "): " in line else line
    loaded, *tried = re.split(r"; in setup [A-Z0-9_]+: ", body)
    first = _reason_class(loaded)
    if not tried or first not in ("orientation", "setup"):
        return first
    turned = [_reason_class(t) for t in tried]
    return next((c for c in turned if c not in ("orientation", "setup")), first)


def _reason_class(body: str) -> str:
    """The class of one reason text: its first reason (up to ``; ``), else the whole."""
    first = body.split("; ", 1)[0]
    for text in (first, body):
        for name, needles in REASONS:
            if any(n in text for n in needles):
                return name
    return "other"


def feature_id(line: str) -> int | None:
    """The recognised feature's id of a left-out line (``R12 bore ...``), or None."""
    m = re.match(r"R(\d+)\b", line)
    return int(m[1]) if m else None


# ------------------------------------------------------------------ one model

@dataclass
class Row:
    """One model with one profile."""

    model: str
    profile: str
    recognised: int = 0
    fillets: int = 0
    narrow: int = 0
    eligible: int = 0
    planned: int = 0
    planned_eligible: int = 0
    left_out: dict[str, int] = field(default_factory=dict)
    touches: int = 0
    load_s: float = 0.0
    plan_s: float = 0.0
    plan_cpu: float = 0.0
    emit: str = ""
    vm: str = ""
    points: str = ""
    """The DMIS programs' points checked on the model (``points_on_model.py``)."""
    error: str = ""
    setups: dict[str, int] = field(default_factory=dict)
    """Planned features per setup (``AS LOADED``, ``FLIPPED``, ...)."""
    notes: list[str] = field(default_factory=list)

    @property
    def share(self) -> float | None:
        """Planned eligible / eligible, or None without an eligible feature."""
        return self.planned_eligible / self.eligible if self.eligible else None


def run(part: Any, model: Path, case: ProfileCase, machine: Any, load_s: float,
        simulate: Path | None) -> Row:
    """Plan one loaded model with one profile as ``probegen plan MODEL --all-revolved
    --machine PROFILE -d DIALECT -o DIR`` does (the same functions:
    ``planning.setups.all_revolved_setups``, ``plan_setups``, ``cli.plan.program_text``):
    one program per setup; with ``simulate`` (the profile's file) run each on the virtual
    CMM or machine with its setup."""
    from probegen.cli.plan import program_text
    from probegen.dialects import get_dialect
    from probegen.errors import ProbegenError
    from probegen.planning.setups import all_revolved_setups, plan_setups

    row = Row(model.stem, case.key, load_s=load_s)
    fillets, narrow, eligible = eligibility(part, machine)
    row.recognised = len(fillets | narrow | eligible)
    row.fillets, row.narrow, row.eligible = len(fillets), len(narrow), len(eligible)
    runtime = get_dialect(case.dialect).RUNTIME_VARIABLES
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        spec, notes = all_revolved_setups(part, machine)
        setups = plan_setups(spec, runtime_variables=runtime, part=part)
    except ProbegenError as exc:
        row.plan_s, row.plan_cpu = time.perf_counter() - t0, time.process_time() - c0
        row.error = str(exc)
        return row
    except Exception as exc:  # noqa: BLE001 - a bug: noted, the other models still run
        row.plan_s, row.plan_cpu = time.perf_counter() - t0, time.process_time() - c0
        row.error = f"CRASH {type(exc).__name__}: {exc}"
        traceback.print_exc()
        return row
    row.plan_s, row.plan_cpu = time.perf_counter() - t0, time.process_time() - c0
    count(row, setups, notes, eligible)
    t1 = time.perf_counter()
    texts = []
    try:
        for _sp, planned in setups:
            texts.append(program_text(case.dialect, planned, notes))
    except ProbegenError as exc:
        row.emit = f"refused ({setups[len(texts)][0].name}): {str(exc)[:70]}"
        return row
    lines = " + ".join(str(len(x.splitlines())) for x in texts)
    names = f" ({', '.join(sp.name for sp, _ in setups)})" if len(setups) > 1 else ""
    row.emit = f"{lines} lines{names}, {time.perf_counter() - t1:.1f} s"
    if case.dialect == "dmis":
        row.points = points_text([
            check_points(text, sp.part)  # the part as it lies in the setup (R·p_part)
            for text, (sp, _) in zip(texts, setups, strict=True)])
    if simulate is not None:
        said = [simulate_program(model, text, case, simulate,
                                 sum(len(p.normals) for p in planned.revolved),
                                 sp.setup.name if sp.setup is not None else None)
                for text, (sp, planned) in zip(texts, setups, strict=True)]
        alarms = [s for s in said if s.startswith("ALARM")]
        row.vm = (alarms[0] if len(said) == 1 else "; ".join(alarms)) if alarms else \
            "; ".join(s for s in said if s != "no alarm") or "no alarm"
    return row


def count(row: Row, setups: Any, notes: tuple[str, ...], eligible: set[int]) -> None:
    """Fill ``row``'s planned, touches, per-setup and left-out figures from the setups'
    planned programs and the notes: a feature is planned when some setup's program
    measures it (once, however many programs name it), left out when none does, by the
    reason of its line; an eligible feature in no program and on no line is counted
    ``lost`` (a bug to look at)."""
    planned_ids: dict[str, str] = {}
    for sp, planned in setups:
        for p in planned.revolved:
            planned_ids.setdefault(p.spec.id, sp.name)
        row.touches += sum(len(p.normals) for p in planned.revolved)
    ids = {int(f[1:]) for f in planned_ids if f[1:].isdigit()}
    row.planned, row.planned_eligible = len(planned_ids), len(ids & eligible)
    row.setups = dict(Counter(planned_ids.values()))
    row.notes = list(notes)
    noted = {feature_id(n) for n in notes}
    reasons = Counter(reason_of(n) for n in notes
                      if feature_id(n) in eligible and feature_id(n) not in ids)
    lost = len(eligible - ids - noted)
    if lost:
        reasons["lost"] = lost
    row.left_out = dict(sorted(reasons.items()))


def simulate_program(model: Path, text: str, case: ProfileCase, profile: Path,
                     touches: int, setup: str | None = None) -> str:
    """The program on the virtual CMM or machine as ``probegen sim PROGRAM --part MODEL
    --machine PROFILE [--setup SETUP]`` runs it (the part at its nominal place, turned as
    the setup says, a perfect probe, the profile's rack and trunnion): ``no alarm``, or
    the alarm or error (prefixed with the setup's name for a setup's program)."""
    import contextlib
    import io

    from probegen.cli.app import main as cli

    with tempfile.TemporaryDirectory() as tmp:
        program = Path(tmp) / f"{model.stem}.{'dmi' if case.kind == 'dmis' else 'nc'}"
        program.write_text(text, encoding="ascii")
        said = io.StringIO()
        with contextlib.redirect_stderr(said), contextlib.redirect_stdout(said):
            code = cli(["-q", "sim", str(program), "--part", str(model), "--machine",
                        str(profile), "-o", str(Path(tmp) / "sim.log"),
                        *(["--setup", setup] if setup else [])])
    out = said.getvalue()
    where = f"[{setup}] " if setup else ""
    alarm = re.search(r"stopped on alarm (.*)", out)
    if alarm:
        return f"ALARM {where}{alarm[1][:80]}"
    if code:
        return f"ALARM {where}sim exit {code}: {' '.join(out.split())[:80]}"
    made = re.search(r"\((\d+) touches\)", out)
    count = int(made[1]) if made else -1
    return "no alarm" + ("" if count == touches
                         else f" ({where}{count} of {touches} touches)")


# ------------------------------------------------------------------ tables

def left_out_text(row: Row) -> str:
    """``orientation 12, stylus too large 3`` (the eligible features left out)."""
    return ", ".join(f"{k} {v}" for k, v in row.left_out.items()) or "-"


def points_text(checks: list[Any]) -> str:
    """One text of the points checks of a model's DMIS programs
    (``benchmarks/points_on_model.py``)."""
    total = PointsCheck()
    for c in checks:
        total.points += c.points
        total.off_model += c.off_model
        total.inward += c.inward
        total.unclassified += c.unclassified
        total.worst = max(total.worst, c.worst)
    return total.text()


def table(rows: list[Row]) -> str:
    """The Markdown table, one line per model and profile, with totals per profile."""
    head = ("| model | profile | recognised | fillets | narrow bores | eligible | planned "
            "(eligible) | planned / eligible | left out (eligible) by reason | touches | "
            "load s | plan s (CPU) | program |")
    out = [head, "|" + "---|" * 13]
    for r in rows:
        share = "-" if r.share is None else f"{100.0 * r.share:.0f} %"
        program = r.error and f"not planned: {r.error[:60]}" or r.emit
        if r.points:
            program += f"; {r.points}"
        if r.vm:
            program += f"; {r.vm}"
        out.append(f"| {r.model} | {r.profile} | {r.recognised} | {r.fillets} | {r.narrow} | "
                   f"{r.eligible} | {r.planned} ({r.planned_eligible}) | {share} | "
                   f"{left_out_text(r)} | {r.touches} | {r.load_s:.1f} | "
                   f"{r.plan_s:.1f} ({r.plan_cpu:.1f}) | {program} |")
    for key in dict.fromkeys(r.profile for r in rows):
        mine = [r for r in rows if r.profile == key]
        eligible = sum(r.eligible for r in mine)
        planned = sum(r.planned_eligible for r in mine)
        share = f"{100.0 * planned / eligible:.0f} %" if eligible else "-"
        reasons: Counter[str] = Counter()
        for r in mine:
            reasons.update(r.left_out)
        out.append(f"| **all {len(mine)}** | {key} | {sum(r.recognised for r in mine)} | "
                   f"{sum(r.fillets for r in mine)} | {sum(r.narrow for r in mine)} | "
                   f"{eligible} | {sum(r.planned for r in mine)} ({planned}) | {share} | "
                   + (", ".join(f"{k} {v}" for k, v in sorted(reasons.items())) or "-")
                   + f" | {sum(r.touches for r in mine)} | {sum(r.load_s for r in mine):.1f} | "
                   f"{sum(r.plan_s for r in mine):.1f} ({sum(r.plan_cpu for r in mine):.1f}) "
                   f"| |")
    return "\n".join(out)


def goals(rows: list[Row]) -> list[str]:
    """Per profile: the models at or above the issue's share (90 % CMM, 80 % five-axis)."""
    lines = []
    for key, goal in (("cmm", 0.9), ("5axis", 0.8)):
        mine = [r for r in rows if r.profile == key and r.share is not None]
        if mine:
            met = [r for r in mine if r.share is not None and r.share >= goal]
            lines.append(f"{key}: {len(met)} of {len(mine)} models with an eligible "
                         f"feature plan {100 * goal:.0f} % or more of them")
    return lines


def main(argv: list[str]) -> int:
    import probegen.cli.progress
    from probegen import cad
    from probegen.errors import ProbegenError

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="*", type=Path)
    parser.add_argument("--profile", choices=sorted(CASES), action="append")
    parser.add_argument("--vm", action="store_true")
    parser.add_argument("--notes", action="store_true")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--raised", type=float, default=0.0, metavar="MM",
                        help="every part's lowest point this far above the machine table "
                             "(parallels; default 0: on the table, docs/spec.md)")
    args = parser.parse_args(argv)
    probegen.cli.progress.ENABLED = False
    warnings.simplefilter("ignore")
    cases = [CASES[k] for k in (args.profile or ["cmm", "5axis"])]
    rows: list[Row] = []
    with tempfile.TemporaryDirectory() as tmp:
        machines, files = {}, {}
        for case in cases:
            machines[case.key], files[case.key], where = load_case(case, Path(tmp))
            print(f"{case.key}: {where}, to {case.dialect}; styli "
                  + ", ".join(f"{s.label} D{s.ball_diameter:g}"
                              for s in machines[case.key].styli())
                  + f"; smallest bore {least_bore(machines[case.key]):.3f} mm", flush=True)
        for model in args.models or default_models():
            t0 = time.perf_counter()
            try:
                part = cad.load_part(model, raised=args.raised)
            except ProbegenError as exc:
                print(f"{model.stem}: not loaded: {exc}", flush=True)
                continue
            load_s = time.perf_counter() - t0
            for case in cases:
                row = run(part, model, case, machines[case.key], load_s,
                          files[case.key] if args.vm else None)
                rows.append(row)
                share = "-" if row.share is None else f"{100.0 * row.share:.0f} %"
                print(f"{row.model} [{case.key}]: {row.recognised} recognised, "
                      f"{row.eligible} eligible, {row.planned} planned "
                      f"({row.planned_eligible} eligible, {share}); left out: "
                      f"{left_out_text(row)}; by setup: "
                      f"{', '.join(f'{k} {v}' for k, v in row.setups.items()) or '-'}; "
                      f"plan {row.plan_s:.1f} s; "
                      f"{row.error or row.emit} {row.points} {row.vm}", flush=True)
                for n in row.notes if args.notes else ():
                    print(f"  {n[:300]}")
    print()
    print(table(rows))
    print()
    print("\n".join(goals(rows)))
    if args.json:
        args.json.write_text(json.dumps([asdict(r) for r in rows], indent=1) + "\n",
                             encoding="utf-8")
    return 1 if any(r.vm.startswith("ALARM") or r.error.startswith("CRASH") for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
