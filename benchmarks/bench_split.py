"""Benchmark: a program split for a control's ``program_size`` (issue 19).

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_split.py [SIZE ...]

The Fanuc program for every revolved feature of the NIST DCX part (``all_revolved_spec``
with ``samples/machines/vmc-fanuc.toml``, as ``benchmarks/bench_program_size.py`` plans
it), inline and compact, split for each ``program_size`` in bytes (default 65536 and
32768).  Per row: the unsplit size, the number of parts, the largest part, the driver's
size, the time the split took, and whether the driver running its parts on the virtual
machine (the part at its nominal placement, a perfect probe) prints the unsplit
program's DPRNT log byte for byte: it must be ``same``.
"""

from __future__ import annotations

import dataclasses
import re
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from bench_program_size import DCX, programs  # noqa: E402


def row(program: object, placed: object, ball: float, size: int, compact: bool) -> str:
    """One table row: ``program`` split for ``size`` bytes and run on the VM."""
    from probegen.dialects import get_dialect
    from probegen.dialects.split import fit
    from probegen.errors import ProbegenError
    from probegen.machine.probe_model import ProbeModel
    from probegen.sim.vm import VirtualMachine, run_text

    setup = dataclasses.replace(program.setup, program_size=size)  # type: ignore[attr-defined]
    program = dataclasses.replace(program, setup=setup)  # type: ignore[type-var]
    d = get_dialect("fanuc")
    d.compact = compact
    whole = d.generate(program)  # type: ignore[arg-type]
    form = "compact" if compact else "inline"
    start = time.perf_counter()
    try:
        d = get_dialect("fanuc")
        d.compact = compact
        split = fit(d, program)  # type: ignore[arg-type]
    except ProbegenError as exc:
        alone = re.search(r"the part with (.*) alone is (\d+) bytes", str(exc))
        why = f"{alone[1]} alone is {alone[2]} bytes" if alone else str(exc)
        return f"| {form} | {size} | {len(whole)} | refused: {why} | | | | |"
    took = time.perf_counter() - start
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        if compact:
            for name, text in d.library_files(8000, 100, "mm").items():
                (folder / name).write_text(text, encoding="ascii")
        for p in split.parts:
            (folder / p.file_name).write_text(p.text, encoding="ascii")
        logs = [run_text(text, VirtualMachine(placed, ProbeModel(ball)),  # type: ignore[arg-type]
                         kind="macrob", program_dir=folder).output
                for text in (whole, split.main)]
    largest = max((len(p.text) for p in split.parts), default=len(split.main))
    same = "same" if logs[0] == logs[1] and "PGEND" in logs[0] else "DIFFERENT"
    return (f"| {form} | {size} | {len(whole)} | {len(split.parts)} | {largest} | "
            f"{len(split.main)} | {took:.2f} s | {same} |")


def main(sizes: list[int]) -> None:
    program, spec, placed = programs(DCX)
    ball = spec.machine.probe.ball_radius  # type: ignore[attr-defined]
    print("| form | program_size | unsplit bytes | parts | largest part | driver | split "
          "time | log |")
    print("|---|---|---|---|---|---|---|---|")
    for compact in (False, True):
        for size in sizes:
            print(row(program, placed, ball, size, compact), flush=True)


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [65536, 32768])
