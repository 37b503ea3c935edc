"""Benchmark / figures of method M5 (planar grating, 21 geometric terms) on the VM.

Run:  .venv/bin/python benchmarks/bench_grating.py [--noise 0.05] [--seed 11]

For the planted machine ``samples/grating/machine-errors.toml`` and the default plan
(``samples/grating/grating.toml``) it runs the grating programs on the virtual machine
and prints, for three plans (the seed's: one setup per plane; + a riser per plane;
+ a second head length per plane):

* rank of the linearised model and the functions the plan does not determine;
* noise-free: the largest relative RMS error (identified − planted, over the axis range,
  against the function's own RMS) of the global and the stepwise identifications, and
  the largest relative squareness error;
* with Gaussian reading noise ``--noise`` µm: the dispersion the global fit reports, and
  the largest absolute RMS difference between the stepwise and global results.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from probegen.calibrate.grating_io import GratingReading
from probegen.calibrate.identify import Identification, axis_ranges, identify_global, truth
from probegen.calibrate.identify_model import setup_of
from probegen.calibrate.identify_stepwise import identify_stepwise
from probegen.cli.grating import simulate_readings
from probegen.geometry.orthopoly import rms, rms_difference
from probegen.machine.kinematics import Machine, load_machine
from probegen.planning.grating import load_grating_spec

ROOT = Path(__file__).resolve().parent.parent
PLANS = {"seed (1 setup per plane)": {},
         "+ riser per plane": {"second_offset": True},
         "+ riser + second head": {"second_offset": True, "second_head": True}}


def worst(found: Identification, true: Identification) -> tuple[str, float, float]:
    """The function of largest relative error, that error, the largest relative
    squareness error."""
    name, f_err = "-", 0.0
    for f, t in zip(found.functions, true.functions, strict=True):
        if f.coefficients is None or t.coefficients is None:
            continue
        err = rms_difference(f.range, f.coefficients, t.coefficients) / rms(
            t.range, t.coefficients)
        if err > f_err:
            name, f_err = f.function.name, err
    s_err = max(abs((s.value or 0.0) - (t.value or 0.0)) / abs(t.value or 1.0)
                for s, t in zip(found.squareness, true.squareness, strict=True)
                if s.value is not None)
    return name, f_err, s_err


def largest_difference(a: Identification, b: Identification) -> tuple[str, float]:
    """The function with the largest RMS difference between two identifications."""
    best = ("-", 0.0)
    for fa, fb in zip(a.functions, b.functions, strict=True):
        if fa.coefficients is None or fb.coefficients is None:
            continue
        value = rms_difference(fa.range, fa.coefficients, fb.coefficients)
        if value > best[1]:
            best = (f"{fa.function.name} ({fa.function.unit})", value)
    return best


def planted(machine: Machine, readings: list[GratingReading]) -> Identification:
    return truth(machine.errors, axis_ranges(readings),
                 list(dict.fromkeys(setup_of(r) for r in readings)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--noise", type=float, default=0.05, help="reading sigma, um")
    parser.add_argument("--seed", type=int, default=11)
    args = parser.parse_args()
    machine = load_machine(ROOT / "samples" / "grating" / "machine-errors.toml")
    spec = load_grating_spec(str(ROOT / "samples" / "grating" / "grating.toml"))
    for name, options in PLANS.items():
        readings = simulate_readings(spec, machine, **options)
        glob, step = identify_global(readings), identify_stepwise(readings)
        true = planted(machine, readings)
        missing = [f.function.name for f in glob.functions if not f.determined]
        print(f"{name}: {len(readings)} readings, rank {glob.rank} of {glob.columns}, "
              f"degree {glob.degree}; not determined: {' '.join(missing)}")
        for result in (glob, step):
            which, f_err, s_err = worst(result, true)
            count = sum(f.determined for f in result.functions)
            print(f"  noise-free {result.method:8}: {count} functions, largest relative "
                  f"error {f_err:.2e} ({which}), squareness {s_err:.2e}")
        noisy = simulate_readings(spec, machine, noise=args.noise, seed=args.seed, **options)
        glob, step = identify_global(noisy), identify_stepwise(noisy)
        which, value = largest_difference(glob, step)
        worst_fn, f_err, _ = worst(glob, planted(machine, noisy))
        print(f"  noise {args.noise} um: dispersion {glob.dispersion:.4f} um "
              f"(ratio {glob.dispersion / args.noise:.3f}), degree {glob.degree}, largest "
              f"relative error {f_err:.2e} ({worst_fn}); stepwise - global largest "
              f"{which} {value:.4f} rms")


if __name__ == "__main__":
    main()
