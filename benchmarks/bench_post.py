"""The DMIS post-processor on the NIST DMIS programs: post, run, evaluate, compare.

For each program: post it to Fanuc for the 4 mm stylus profile with its STEP model
placed as the program's comments ask (the DCX with ``--reroute``), run the program on
the virtual machine, evaluate the DPRNT log through the feature map, and compare the
features with the nominals and with the DMIS program run on the virtual CMM (same
model, same virtual machine), at the nominal place, displaced by (0.3, -0.3, 0.1) mm, and
on a machine with the sample's 21 geometric errors and a lobing probe.

Run: ``PYTHONPATH=. .venv/bin/python benchmarks/bench_post.py`` (from the repository,
with ``../shared/ref`` beside it).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from probegen import cad
from probegen.machine.kinematics import load_machine
from probegen.machine.probe_model import Lobing, ProbeModel
from probegen.machine.profile import load_profile
from probegen.post.evaluate import evaluate_log
from probegen.post.files import PostOutput, post_file
from probegen.results import parse_dprnt
from probegen.sim.cmm.interpreter import DmisRunResult, run_dmis
from probegen.sim.contact import PlacedPart
from probegen.sim.vm import CmmAdapter, VirtualMachine, run_text

REPO = Path(__file__).resolve().parent.parent
NIST = REPO.parent / "shared" / "ref" / "nist-ippdme"
CASES = [
    ("simple_in.dms", NIST / "IPlusSimplePart/DMIS/simple_in.dms",
     NIST / "IPlusSimplePart/STEP_Part21_AP203/ipp_simple.stp", (0.0, 0.0, 0.0),
     (50.0, 50.0, 200.0), False),
    ("IMTS_M_clean.dmi", NIST / "DCXpart/DMIS/IMTS_M_clean.dmi",
     NIST / "DCXpart/STEP_AP214/DaimlerChryslerTestPartAP214.stp", (355.0, 91.0, -80.0),
     (355.0, 91.0, 150.0), True),
]


def largest_difference(a: DmisRunResult, features: dict[str, object]) -> float:
    """Largest coordinate difference (mm) of location, vector and size over all features."""
    worst = 0.0
    for name, fa in a.features.items():
        fb = features[name]
        for attr in ("location", "vector"):
            va, vb = getattr(fa, attr), getattr(fb, attr)
            if va is not None and vb is not None:
                worst = max(worst, float(np.abs(np.subtract(va, vb)).max()))
        if fa.size is not None and getattr(fb, "size", None) is not None:
            worst = max(worst, abs(fa.size - fb.size))  # type: ignore[attr-defined]
    return worst


def run(out: PostOutput, program: Path, model: cad.Model, where: tuple[float, ...],
        home: tuple[float, float, float], errors: bool
        ) -> tuple[DmisRunResult, DmisRunResult, int]:
    """Both runs on one kind of virtual machine (with the sample's 21 geometric errors
    and a lobing probe when ``errors``)."""
    kinematics = load_machine(REPO / "samples/machines/errors-example.toml") if errors \
        else None
    lobing = Lobing(0.0012, 0.0008, 0.0005) if errors else Lobing(0.0, 0.0, 0.0)

    def machine() -> VirtualMachine:
        return VirtualMachine(PlacedPart.from_model(model, translation=where),
                              ProbeModel(2.0, lobing), kinematics)

    res = run_text(out.text, machine(), kind="macrob")
    assert res.alarm is None, res.alarm
    posted = evaluate_log(parse_dprnt(res.output, strict=True), out.fmap)
    direct = run_dmis(program.read_text(), CmmAdapter(machine()), home=home)
    return posted, direct, res.touches


def main() -> None:
    machine = load_profile(REPO / "samples/post/vmc-fanuc-d4.toml")
    for name, program, step, offset, home, reroute in CASES:
        t0 = time.perf_counter()
        out = post_file(program, machine, cad.load_part(step), dialect="fanuc",
                        offset=offset, reroute=reroute)
        t_post = time.perf_counter() - t0
        model = cad.load_step(step)
        segments = out.posted.segments
        print(f"{name}: {len(out.posted.touches)} touches, {len(out.text.splitlines())} "
              f"Fanuc lines, {len(segments)} segments checked (smallest clearance of a "
              f"positioning move above the margin {out.posted.move_clearance:.3f} mm), rerouted "
              f"lines {list(out.posted.rerouted)}; post {t_post:.2f} s")
        for label, shift, errors in (
                ("nominal place", (0.0, 0.0, 0.0), False),
                ("displaced 0.3,-0.3,0.1", (0.3, -0.3, 0.1), False),
                ("machine errors + lobing probe", (0.0, 0.0, 0.0), True)):
            where = tuple(np.add(offset, shift))
            posted, direct, touches = run(out, program, model, where, home, errors)
            nominal = "" if any(shift) else \
                f"|posted - nominal| {largest_difference(posted, posted.nominals):.2e} mm, "
            print(f"  {label}: {touches} touches, {len(posted.features)} features; largest "
                  f"{nominal}|posted - CMM| {largest_difference(posted, direct.features):.2e}"
                  f" mm, same DMIS output file: {posted.output == direct.output}")


if __name__ == "__main__":
    main()
