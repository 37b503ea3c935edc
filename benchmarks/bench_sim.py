"""Benchmark: the virtual machine running a 10,000-touch Fanuc program.

Run:  .venv/bin/python benchmarks/bench_sim.py

The program has the shape the Fanuc dialect emits (per touch: a protected G31
positioning move with its check, a probing G31 with its no-touch check, a DPRNT line and
a G1 retract), 10,000 touches around an analytic 25 mm sphere (exact contact) with a
lobing probe.  Prints the run time and touches per second, with the interpreter alone
(a machine whose skip fires at once) as the baseline in the same process.
"""

from __future__ import annotations

import math
import sys
import time

N = 10_000


def program(n: int) -> str:
    out = ["%", "O1001(BENCH)", "G21", "G90 G17 G40 G49 G80 G94", "G54",
           "G0 G43 H20 Z100.0000", "POPEN", "DPRNT[PGSTART*O1001*V1]"]
    for i in range(1, n + 1):
        a = 2 * math.pi * i / n
        z = 2.0 + 8.0 * ((i * 7) % 13) / 13.0
        ring = math.sqrt(15.5**2 - z**2)
        ax, ay = (ring + 2) * math.cos(a), (ring + 2) * math.sin(a)
        tx, ty = (ring - 2) * math.cos(a), (ring - 2) * math.sin(a)
        out += [f"#190={ax:.4f}", f"#191={ay:.4f}", f"#192={z:.4f}",
                "G31 X#190 Y#191 Z#192 F2000.",
                "#193=ABS[#5061-#190]+ABS[#5062-#191]+ABS[#5063-#192]",
                f"IF[#193LT0.0050]GOTO{2 * i}", f"DPRNT[ERR*COLLISION*S*{i}]",
                "#3000=2(UNEXPECTED PROBE TRIGGER)", f"N{2 * i}",
                f"#190={tx:.4f}", f"#191={ty:.4f}", f"#192={z:.4f}",
                "G31 X#190 Y#191 Z#192 F300.",
                "#193=ABS[#5061-#190]+ABS[#5062-#191]+ABS[#5063-#192]",
                f"IF[#193GE0.0050]GOTO{2 * i + 1}", f"DPRNT[ERR*NOTOUCH*S*{i}]",
                "#3000=1(PROBE DID NOT TOUCH)", f"N{2 * i + 1}",
                f"DPRNT[PT*S*{i}*X#5061[44]*Y#5062[44]*Z#5063[44]]",
                f"G1 X{ax:.4f} Y{ay:.4f} Z{z:.4f} F2000.",
                "G0 Z30.0000", f"G0 X{ax:.4f} Y{ay:.4f}", f"G0 Z{z:.4f}"]
    return "\n".join([*out, "G0 Z100.", "DPRNT[PGEND*O1001]", "PCLOS", "M30", "%"]) + "\n"


class Instant:
    """Baseline: the skip fires at the midpoint of every G31 move (no geometry)."""

    def rapid(self, start: object, end: object) -> None:
        pass

    def feed(self, start: object, end: object, feed: float) -> None:
        pass

    def skip(self, start: tuple[float, ...], end: tuple[float, ...],
             feed: float) -> tuple[float, float, float] | None:
        if feed > 1000:
            return None
        return ((start[0] + end[0]) / 2, (start[1] + end[1]) / 2, (start[2] + end[2]) / 2)


def main() -> int:
    from probegen.machine.probe_model import Lobing, ProbeModel
    from probegen.sim.contact import PlacedPart
    from probegen.sim.macrob.machine import run_program
    from probegen.sim.vm import VirtualMachine, run_text

    text = program(N)
    t0 = time.perf_counter()
    base = run_program(text, Instant(), settings=None)  # type: ignore[arg-type]
    t_base = time.perf_counter() - t0
    assert base.alarm is None, base.alarm
    part = PlacedPart.from_spheres([[0.0, 0.0, 0.0]], [12.5])
    vm = VirtualMachine(part, ProbeModel(3.0, Lobing(0.0012, 0.0008, 0.0005)))
    t0 = time.perf_counter()
    res = run_text(text, vm, kind="macrob")
    t_vm = time.perf_counter() - t0
    assert res.alarm is None and res.touches == N, res.alarm
    print(f"{N} touches, {len(text.splitlines())} blocks")
    print(f"interpreter alone (skip at the midpoint): {t_base:.2f} s")
    print(f"virtual machine (exact contact, lobing probe): {t_vm:.2f} s, "
          f"{N / t_vm:,.0f} touches/s ({t_vm / t_base:.2f}x the interpreter alone)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
