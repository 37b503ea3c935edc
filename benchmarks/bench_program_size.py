"""Benchmark: bytes and lines per touch of the Fanuc program, inline and compact (issue 19).

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_program_size.py [MODEL.stp ...]

Without arguments: the sphere test sample (``samples/sphere25/sphere_test.toml``) and
every revolved feature of the DCX part (``all_revolved_spec`` with
``samples/machines/vmc-fanuc.toml``, as ``benchmarks/bench_revolved.py`` plans it);
with arguments, those STEP models' all-revolved programs instead of the DCX part.  Per
program: touches (one G31 touch each), bytes and lines of the inline program and of the
compact main program (``compile --compact``: G65 calls to the macro library), bytes per
touch of each, the library's size (written once per control, not per program), and
whether both forms measure the same on the virtual machine (the part at its nominal
placement, a perfect probe): the two DPRNT logs differ in their text (the compact
program's is format V2: ``FEAT`` lines and touches naming their feature by number), so
``same`` means that both read without a diagnostic to the same touches, each with its
kind, feature, index and X Y Z, in the same order.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

MACHINE = REPO / "samples/machines/vmc-fanuc.toml"
SPHERE = REPO / "samples/sphere25/sphere_test.toml"
DCX = Path("/work/shared/ref/nist-ippdme/DCXpart/STEP_AP214/DaimlerChryslerTestPartAP214.stp")


def programs(source: Path) -> tuple[object, object, object]:
    """(the planned program, the spec, the placed part at its nominal placement)."""
    from probegen import cad
    from probegen.planning import plan_program
    from probegen.sim.contact import PlacedPart

    if source.suffix == ".toml":
        from probegen.spec.model import load_spec

        spec = load_spec(source)
        assert spec.model is not None
        part = cad.load_part(spec.model)
    else:
        from probegen.machine.profile import load_profile
        from probegen.planning.revolved_spec import all_revolved_spec

        part = cad.load_part(source)
        spec, _ = all_revolved_spec(part, load_profile(MACHINE))
    planned = plan_program(spec, runtime_variables=True, part=part)
    return planned.program, spec, PlacedPart.from_model(part.model)


def measure(source: Path) -> str:
    """One table row for ``source`` (a spec or a STEP model)."""
    from probegen.dialects import get_dialect
    from probegen.errors import ProbegenError
    from probegen.machine.probe_model import ProbeModel
    from probegen.results import parse_dprnt
    from probegen.sim.vm import VirtualMachine, run_text

    program, spec, placed = programs(source)
    inline = get_dialect("fanuc").generate(program)  # type: ignore[arg-type]
    d = get_dialect("fanuc")
    d.compact = True
    compact = d.generate(program)  # type: ignore[arg-type]
    setup = program.setup  # type: ignore[attr-defined]
    library = d.library_files(setup.library_number, setup.variable_base, setup.units,
                              setup.options or ())
    touches = inline.count("#3000=1(")
    if not touches:
        raise ProbegenError("no touches")
    ball = spec.machine.probe.ball_radius  # type: ignore[attr-defined]
    with tempfile.TemporaryDirectory() as tmp:
        for name, text in library.items():
            Path(tmp, name).write_text(text, encoding="ascii")
        logs = [run_text(text, VirtualMachine(placed, ProbeModel(ball)),  # type: ignore[arg-type]
                         kind="macrob", program_dir=Path(tmp)) for text in (inline, compact)]
    read = [[(t.kind, t.feature, t.index, t.xyz) for t in
             parse_dprnt(log.output, strict=True).touches] for log in logs]
    same = "same" if read[0] == read[1] and not logs[0].alarm else "DIFFERENT"
    lines = [text.count("\n") for text in (inline, compact)]
    return (f"| {source.stem[:32]} | {touches} | {len(inline):,} | {lines[0]:,} | "
            f"{len(inline) / touches:.0f} | {lines[0] / touches:.1f} | {len(compact):,} | "
            f"{lines[1]:,} | {len(compact) / touches:.0f} | {lines[1] / touches:.1f} | "
            f"{sum(map(len, library.values()))} | {same} |")


def main(argv: list[str]) -> None:
    sources = [SPHERE] + ([Path(a) for a in argv] or [DCX])
    print("| program | touches | inline bytes | inline lines | bytes/touch | lines/touch | "
          "compact bytes | compact lines | bytes/touch | lines/touch | library bytes | "
          "VM logs |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    from probegen.errors import ProbegenError

    for source in sources:
        try:
            print(measure(source), flush=True)
        except ProbegenError as exc:  # a model with no plannable revolved feature
            print(f"| {source.stem[:32]} | not planned: {str(exc)[:60]} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
