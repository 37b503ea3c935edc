"""Real DMIS programs (LK CAMIO, WinWerth, MODUS ...) through the reader and ``post``.

For each program given on the command line: read it (statement by statement, a bad
statement costs only itself), then post it for the stylus of
``samples/post/vmc-fanuc-d4.toml`` (``--ball D`` sets another ball diameter, mm) without
a model (no collision check: the programs come without their parts), once without and
once with ``--skip-unsupported``.  A statement ``post`` refuses is counted, turned into
a comment and the program posted again, until it posts; so one refusal does not hide
the next (a refused ENDMES takes its MEAS block out; a refused ENDFIL or ENDMAC ends
the count: "the rest of the program").  Prints per program and mode: statements read,
parse errors, executed, executed with a note, skipped (with its reason), refused (the
statements of a refused MEAS block counted in "left out"), and the refused and skipped
statements by major word.

The programs are not stored in the repository: fetch them yourself (e.g.
echabert/MMTCodeGenerator ``header.dmi``, benrit/werth_cmm_lib ``00304198.dms``,
enibigir/flatness_meas ``python_test.dmi``).

Run: ``PYTHONPATH=. .venv/bin/python benchmarks/bench_vendor_dmis.py [--ball D] FILE...``
"""

from __future__ import annotations

import re
import sys
from collections import Counter
from dataclasses import replace
from pathlib import Path

from probegen.dmis.reader import decode_dmis, parse_dmis_recovering
from probegen.errors import ProbegenError
from probegen.machine.profile import load_profile
from probegen.post.frontend import post_dmis

PROFILE = Path(__file__).resolve().parent.parent / "samples" / "post" / "vmc-fanuc-d4.toml"
_LINE = re.compile(r":(\d+):")
MAX_REFUSALS = 500
_FINAL = frozenset({"ENDMES", "ENDFIL", "ENDMAC"})
"""A refusal here leaves the program unbalanced: counted, and the program not posted."""


def measure(path: Path, skip: bool, ball: float | None = None) -> dict[str, object]:
    """Read and post ``path``; return the counts (see the module docstring)."""
    machine = load_profile(PROFILE)
    if ball is not None:
        machine = replace(machine, probe=replace(machine.probe, ball_diameter=ball))
    lines = decode_dmis(path.read_bytes(), str(path)).splitlines()
    first, diagnostics = parse_dmis_recovering("\n".join(lines), source=path.name)
    majors = {s.line: s.major for s in first.statements}
    for diagnostic in diagnostics:
        lines[diagnostic.line - 1] = "$$ " + lines[diagnostic.line - 1]
    refused: Counter[str] = Counter()
    examples: dict[str, str] = {}
    posted = None
    removed = 0
    for _ in range(MAX_REFUSALS):
        program, _bad = parse_dmis_recovering("\n".join(lines), source=path.name)
        try:
            posted = post_dmis(program, machine, skip_unsupported=skip)
        except ProbegenError as exc:
            found = _LINE.search(str(exc))
            if found is None or not 0 < int(found.group(1)) <= len(lines) \
                    or majors.get(int(found.group(1))) in _FINAL - {"ENDMES"}:
                refused["(the rest of the program)"] += 1
                examples.setdefault("(the rest of the program)", str(exc).splitlines()[0][:160])
                break
            line = int(found.group(1))
            major = majors.get(line, "?")
            refused[major] += 1
            examples.setdefault(major, str(exc).splitlines()[0][:160])
            for k in _refused_lines(majors, line):
                lines[k - 1] = "$$ " + lines[k - 1]
                removed += k in majors
            continue
        break
    skipped = Counter(s.text.split("/")[0].split("=")[-1].strip().upper()
                      for s in (posted.skipped if posted else ()))
    noted = len(posted.notes) if posted else 0
    read = len(first.statements) + len(diagnostics)
    return {"read": read, "parse errors": len(diagnostics),
            "refused": sum(refused.values()),
            "left out with a refused MEAS block": removed - sum(refused.values()),
            "skipped": sum(skipped.values()), "noted": noted,
            "executed": read - len(diagnostics) - removed - sum(skipped.values()),
            "touches": len(posted.touches) if posted else 0,
            "refused by statement": dict(sorted(refused.items())),
            "skipped by statement": dict(sorted(skipped.items())),
            "first refusal of each": examples}


def _refused_lines(majors: dict[int, str], line: int) -> list[int]:
    """The line to comment out; for a refused ENDMES (the feature cannot be fitted)
    the lines of its whole MEAS block."""
    if majors.get(line) != "ENDMES":
        return [line]
    start = max((k for k, major in majors.items() if major == "MEAS" and k < line),
                default=line)
    return list(range(start, line + 1))


def main(args: list[str]) -> int:
    ball = None
    if args[:1] == ["--ball"] and len(args) > 1:
        ball, args = float(args[1]), args[2:]
    if not args:
        print(__doc__)
        return 2
    for name in args:
        for skip in (False, True):
            counts = measure(Path(name), skip, ball)
            flag = " --skip-unsupported" if skip else ""
            print(f"{Path(name).name}{flag}:")
            for key, value in counts.items():
                if isinstance(value, dict):
                    for word, item in value.items():
                        print(f"    {key}: {word}: {item}")
                else:
                    print(f"    {key}: {value}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
