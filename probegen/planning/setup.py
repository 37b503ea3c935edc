"""What every planner of a spec shares: the program's setup block and the part model.

Below the feature planners (:mod:`probegen.planning.revolved_spec` checks a feature
alone with a setup of its own) and :func:`probegen.planning.plan_program`, which both
import it.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

from probegen import ir
from probegen.machine.profile import MachineProfile
from probegen.spec.model import Spec

if TYPE_CHECKING:
    from probegen.cad import Part


def part_of(spec: Spec) -> Part | None:
    """The spec's ``[part] model`` loaded (:func:`probegen.cad.load_part`); None for a spec
    without a model.  Load it once and hand the part down.

    Raises:
        ModelError: the model cannot be loaded.
    """
    if spec.model is None:
        return None
    from probegen.cad import load_part  # lazily: only planning from a model needs OCP

    return load_part(spec.model, raised=spec.raised)


def make_setup(spec: Spec) -> ir.Setup:
    """The program's setup block from the spec and its machine profile."""
    return setup_for(spec.machine, spec.program_number, spec.program_name, spec.clearance_z)


def setup_for(m: MachineProfile, number: int, name: str, clearance_z: float) -> ir.Setup:
    """The setup block of program ``number``/``name`` for machine ``m`` (clearance in mm,
    work coordinates)."""
    return ir.Setup(
        program_number=number, program_name=name, units=m.units,
        work_offset=m.work_offset, clearance_z=clearance_z,
        ball_diameter=m.probe.ball_diameter, shank_diameter=m.probe.shank_diameter,
        tool_number=m.probe.tool_number, tool_change=m.controller.tool_change,
        position_feed=m.feeds.position, probe_feed=m.feeds.probe,
        probe_on=m.controller.probe_on, probe_off=m.controller.probe_off,
        variable_base=m.controller.variable_base, reset_codes=m.controller.reset_codes,
        probe_length=m.probe.length, options=m.controller.options,
        line_length=m.controller.line_length, program_memory=m.controller.program_memory,
        limits_source=m.source, library_number=m.controller.library_number,
        program_size=m.controller.program_size,
        common_variables=m.controller.common_variables,
        alarm_text_length=m.controller.alarm_text_length,
        stylus=m.stylus.label if m.rack else "",
        **calibration_header(m),
    )


def calibration_header(m: MachineProfile) -> dict[str, Any]:
    """The setup's ``calibration`` comment lines and ``calibration_id`` (empty without
    a calibration): fingerprint, date, source file name and mean effective radius."""
    cal = m.calibration
    if cal is None:
        return {}
    source = Path(cal.source).name if cal.source else "UNKNOWN SOURCE"
    lines = (f"PROBE CALIBRATION {cal.fingerprint} DATED {cal.date or 'UNDATED'}",
             f"FROM {source}",
             f"MEAN EFFECTIVE RADIUS {cal.effective_radius:.4f} MM")
    return {"calibration": tuple(re.sub(r"[^A-Z0-9 .,:_/+-]", "_", t.upper())[:72]
                                 for t in lines),
            "calibration_id": cal.fingerprint}
