"""Real DMIS programs (LK CAMIO, WinWerth, MODUS ...) through the reader and ``post``.

For each program given on the command line: read it (statement by statement, a bad
statement costs only itself), then post it with ``--skip-unsupported`` for the 4 mm
stylus of ``samples/post/vmc-fanuc-d4.toml`` without a model (no collision check: the
programs come without their parts).  A statement ``post`` refuses even with the flag
is counted, turned into a comment and the program posted again, until it posts; so
one refusal does not hide the next.  Prints per program: statements read, parse
errors, executed, executed with a note, skipped (with its reason), refused (with the
statement), and the refused and skipped statements by major word.

The programs are not stored in the repository: fetch them yourself (e.g.
echabert/MMTCodeGenerator ``header.dmi``, benrit/werth_cmm_lib ``00304198.dms``,
enibigir/flatness_meas ``python_test.dmi``).

Run: ``PYTHONPATH=. .venv/bin/python benchmarks/bench_vendor_dmis.py FILE...``
"""

from __future__ import annotations

import re
import sys
from collections import Counter
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


def measure(path: Path) -> dict[str, object]:
    """Read and post ``path``; return the counts (see the module docstring)."""
    machine = load_profile(PROFILE)
    lines = decode_dmis(path.read_bytes(), str(path)).splitlines()
    first, diagnostics = parse_dmis_recovering("\n".join(lines), source=path.name)
    majors = {s.line: s.major for s in first.statements}
    for diagnostic in diagnostics:
        lines[diagnostic.line - 1] = "$$ " + lines[diagnostic.line - 1]
    refused: Counter[str] = Counter()
    examples: dict[str, str] = {}
    posted = None
    for _ in range(MAX_REFUSALS):
        program, _bad = parse_dmis_recovering("\n".join(lines), source=path.name)
        try:
            posted = post_dmis(program, machine, skip_unsupported=True)
        except ProbegenError as exc:
            found = _LINE.search(str(exc))
            if found is None or not 0 < int(found.group(1)) <= len(lines) \
                    or majors.get(int(found.group(1))) in _FINAL:
                refused["(the rest of the program)"] += 1
                examples.setdefault("(the rest of the program)", str(exc).splitlines()[0][:160])
                break
            line = int(found.group(1))
            major = majors.get(line, "?")
            refused[major] += 1
            examples.setdefault(major, str(exc).splitlines()[0][:160])
            lines[line - 1] = "$$ " + lines[line - 1]
            continue
        break
    skipped = Counter(s.text.split("/")[0].split("=")[-1].strip().upper()
                      for s in (posted.skipped if posted else ()))
    noted = len(posted.notes) if posted else 0
    read = len(first.statements) + len(diagnostics)
    return {"read": read, "parse errors": len(diagnostics),
            "refused": sum(refused.values()), "skipped": sum(skipped.values()),
            "noted": noted,
            "executed": read - len(diagnostics) - sum(refused.values())
            - sum(skipped.values()),
            "touches": len(posted.touches) if posted else 0,
            "refused by statement": dict(sorted(refused.items())),
            "skipped by statement": dict(sorted(skipped.items())),
            "first refusal of each": examples}


def main(paths: list[str]) -> int:
    if not paths:
        print(__doc__)
        return 2
    for name in paths:
        counts = measure(Path(name))
        print(f"{Path(name).name}:")
        for key, value in counts.items():
            if isinstance(value, dict):
                for word, item in value.items():
                    print(f"    {key}: {word}: {item}")
            else:
                print(f"    {key}: {value}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
