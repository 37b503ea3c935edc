"""Several DMIS outputs of one part, one per named setup: ``probegen ingest A.dms B.dms``
(issue 17, item 2).

A CMM runs each setup's DMIS program (:mod:`probegen.planning.setups`) with the part
turned as the setup says and reports each feature it measured (``FA(<id>)=FEAT/...``) in
that setup's table frame.  Each output is paired with its setup program by what the output
itself says, never by the order the user gives the files in:

1. the output's ``FILNAM/'<name>'`` is the name of one of the spec's setup programs (the
   CMM names its output after the program's ``DMISMN``: ``ALL REVOLVED FLIPPED``);
2. else the output's feature actuals are all features of one setup program and of no
   other;
3. else it is refused (:class:`~probegen.errors.ProbegenError`): the output of another
   spec, or one that says nothing of its program.

Every feature actual of a paired output must be one of its program's features (an output
of another spec with the same program name is refused), and two outputs of one program
are refused.  Each revolved feature is then reported in the part's coordinates: the
actual's point and axis turned back (``p_part = Rᵀ·p_table``), compared with the nominal
the program was written with (the setup program planned again, its definition turned back
the same way): ``X``, ``Y``, ``Z`` (the centre; a cone's apex), ``POS`` (twice the centre's
offset square to the nominal axis), ``D`` (a cone: ``ANGLE``, the half angle in degrees).
What a feature actual does not carry (form, roundness, taper: the CMM reports them as
tolerance actuals) is not evaluated here, and a note says so.  The free-form features
stay in the part as loaded: they are evaluated from its output's point actuals
(:func:`probegen.evaluate.ingest.ingest_dmis_freeform`).  A setup whose output is not
given leaves its features NOT EVALUATED, never OK.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from probegen import ir
from probegen.errors import ProbegenError
from probegen.evaluate.characteristics import Characteristic, NotEvaluated
from probegen.evaluate.ingest import (
    Ingested,
    _only,
    _revolved_names,
    budget_of,
    ingest_dmis_freeform,
)
from probegen.evaluate.revolved import RevolvedResult
from probegen.evaluate.setups import _merged, _not_measured, pair_each
from probegen.ir import frames
from probegen.results import DmisOutput, DprntLog, read_dmis_output
from probegen.results.dmis_records import FeatureActual
from probegen.spec.model import FreeformSpec, RevolvedSpec, Spec

if TYPE_CHECKING:
    from probegen.cad import Part
    from probegen.planning.setups import SetupProgram

NOT_IN_ACTUALS = ("FORM", "RON", "TAPER")
"""Characteristics a feature actual does not carry (the CMM reports them as tolerance
actuals): not evaluated from a DMIS output."""


def _filnam(path: str | Path) -> str | None:
    """The name of the output's ``FILNAM/'name'`` line, or None."""
    for line in Path(path).read_text(encoding="latin-1").splitlines():
        text = line.strip()
        if text.upper().startswith("FILNAM/"):
            name = text[7:].split(",", 1)[0].strip()
            return name.strip("'\"").strip() or None
    return None


def _known(programs: Sequence[SetupProgram]) -> str:
    return ", ".join(f"'{sp.spec.program_name}' (setup {sp.name})" for sp in programs)


def output_program(path: str | Path, output: DmisOutput,
                   programs: Sequence[SetupProgram]) -> int:
    """The index in ``programs`` of the setup program whose output ``output`` is (see
    the module docstring for the rule).

    Raises:
        ProbegenError: the output names none of the programs and its features are not
            those of exactly one, or a feature actual is not one of its program's.
    """
    names = {sp.spec.program_name.upper(): k for k, sp in enumerate(programs)}
    labels = {fa.name for fa in output.features if "_" not in fa.name or
              fa.name.rpartition("_")[0] not in _freeform_ids(programs)}
    filnam = _filnam(path)
    k = names.get(filnam.upper()) if filnam else None
    if k is None:
        owners = [j for j, sp in enumerate(programs)
                  if labels and labels <= {f.id.upper() for f in sp.spec.features}]
        if len(owners) != 1:
            said = f"FILNAM '{filnam}'" if filnam else "no FILNAM line"
            raise ProbegenError(
                f"{path}: expected the DMIS output of one of the spec's setup programs "
                f"{_known(programs)} (its FILNAM, or feature actuals of one program only), "
                f"found {said} and the feature actuals {', '.join(sorted(labels)) or 'none'}")
        k = owners[0]
    own = {f.id.upper() for f in programs[k].spec.features}
    stray = sorted(labels - own)
    if stray:
        raise ProbegenError(f"{path}: expected the feature actuals of program "
                            f"'{programs[k].spec.program_name}' (setup {programs[k].name}: "
                            f"{' '.join(sorted(own))}), found {', '.join(stray)}: the "
                            "output of another spec or program?")
    return k


def _freeform_ids(programs: Sequence[SetupProgram]) -> set[str]:
    return {f.id.upper() for sp in programs for f in sp.spec.features
            if isinstance(f, FreeformSpec)}


def pair_outputs(paths: Sequence[str | Path], outputs: Sequence[DmisOutput],
                 programs: Sequence[SetupProgram]) -> dict[int, tuple[str | Path, DmisOutput]]:
    """Each output's program (by its index in ``programs``, :func:`output_program`).

    Raises:
        ProbegenError: as :func:`output_program`; two outputs of one program.
    """
    return pair_each(paths, outputs, programs,
                     lambda path, output: output_program(path, output, programs),
                     "DMIS output", lambda sp: f"'{sp.spec.program_name}'")


def ingest_dmis_setups(paths: Sequence[str | Path], spec: Spec, *,
                       decision_rule: str | None = None, part: Part | None = None
                       ) -> Ingested:
    """Every feature of ``spec`` from the DMIS outputs of its setup programs, in the
    part's coordinates (see the module docstring).  Each output is read once, as it is
    on disk, before anything is evaluated.

    Raises:
        ProbegenError: an output cannot be read or is not paired (:func:`pair_outputs`).
    """
    from probegen.planning import part_of
    from probegen.planning.setups import split_setups

    if part is None:
        part = part_of(spec)
    outputs = [read_dmis_output(p) for p in paths]
    programs = split_setups(spec, part)
    paired = pair_outputs(paths, outputs, programs)
    done: list[tuple[SetupProgram, Ingested]] = []
    missing: list[NotEvaluated] = []
    for k, sp in enumerate(programs):
        if k not in paired:
            missing += _not_measured(sp, "DMIS output")
            continue
        path, output = paired[k]
        done.append((sp, _one(path, output, sp, spec, decision_rule)))
    if not done:
        raise ProbegenError(f"ingest: expected a DMIS output of one of {_known(programs)}, "
                            "found none")
    return _merged(spec, done, missing)


def _one(path: str | Path, output: DmisOutput, sp: SetupProgram, spec: Spec,
         decision_rule: str | None) -> Ingested:
    """One setup program's output: its revolved features in part coordinates, its
    free-form features (the part as loaded only)."""
    nominals = _nominals(sp)
    actuals = {fa.name: fa for fa in output.features}
    notes: list[str] = []
    revolved: list[RevolvedResult] = []
    missing: list[NotEvaluated] = []
    for feature in sp.spec.features:
        if not isinstance(feature, RevolvedSpec):
            continue
        fa, nominal = actuals.get(feature.id.upper()), nominals.get(feature.id)
        if fa is None or nominal is None:
            why = (f"no feature actual FA({feature.id}) in {path}" if fa is None else
                   f"the program planned again has no feature {feature.id}")
            names = _revolved_names(feature, 0)
            missing.append(NotEvaluated(feature.id, feature.kind, why,
                                        tuple(n for n, _, _ in names),
                                        tuple((lo, hi) for _, lo, hi in names)))
            continue
        revolved.append(_result(feature, fa, nominal, sp, notes))
    freeform: tuple[object, ...] = ()
    if sp.setup is None:
        found, more = ingest_dmis_freeform(output, sp.spec, sp.part)
        freeform, notes = found, [*notes, *more]
        missing += _only(found, NotEvaluated)
    log = DprntLog(str(path), None, (), (), (), bool(output.features), 0, output.diagnostics)
    from probegen.evaluate.freeform import FreeformResult

    return Ingested(str(path), log, (), tuple(notes), revolved=tuple(revolved),
                    freeform=_only(freeform, FreeformResult),
                    not_evaluated=tuple(missing),
                    rule=decision_rule or spec.decision_rule, budget=budget_of(spec, None))


def _nominals(sp: SetupProgram) -> dict[str, ir.FeatureDef]:
    """The nominal definition of each feature of the setup's program, in the setup's
    table frame (the program planned again, each definition out of its orientation's
    frame)."""
    from probegen.planning import plan_program

    planned = plan_program(sp.spec, runtime_variables=False, check_collisions=False,
                           part=sp.part)
    return {node.feature.id: node.feature for node, _ in frames.in_work(planned.program.body)
            if isinstance(node, ir.FeatureBlock)}


def _shape(nominal: ir.FeatureDef) -> tuple[ir.Vec3, ir.Vec3, float, float]:
    """A revolved definition's point (centre; a cone's apex), axis (a sphere: +Z),
    diameter (0 for a cone) and half angle (rad; 0 but for a cone)."""
    if isinstance(nominal, ir.ConeDef):
        return nominal.apex, nominal.axis, 0.0, nominal.half_angle
    if isinstance(nominal, ir.CircleDef | ir.CylinderDef):
        return nominal.centre, nominal.axis, nominal.diameter, 0.0
    if isinstance(nominal, ir.SphereDef):
        return nominal.centre, (0.0, 0.0, 1.0), nominal.diameter, 0.0
    if isinstance(nominal, ir.TorusDef):
        return nominal.centre, nominal.axis, nominal.major_diameter, 0.0
    raise ProbegenError(f"feature {nominal.id}: expected a revolved definition, found "
                        f"{type(nominal).__name__}")


def _result(feature: RevolvedSpec, fa: FeatureActual, nominal: ir.FeatureDef,
            sp: SetupProgram, notes: list[str]) -> RevolvedResult:
    """A feature actual (``sp``'s table frame) against its nominal, in part coordinates:
    points by :meth:`~probegen.planning.setups.SetupProgram.to_part`, directions by
    ``Rᵀ``."""
    def back(v: ir.Vec3) -> np.ndarray:
        return np.asarray(sp.to_part(v), dtype=np.float64)

    def turn(v: ir.Vec3) -> np.ndarray:
        return np.asarray(frames.apply_t(sp.rotation, v), dtype=np.float64)

    point, axis, diameter, half = _shape(nominal)
    n_point, n_axis = back(point), turn(axis)
    m_point = back(fa.position)
    m_axis = turn(fa.direction) if fa.direction is not None else n_axis
    if float(m_axis @ n_axis) < 0.0:
        m_axis = -m_axis
    off = m_point - n_point
    across = off if feature.kind == "sphere" else off - (off @ n_axis) * n_axis
    pos = 2.0 * float(np.linalg.norm(across))
    t = feature.tolerance
    chars = [Characteristic(name, float(m), float(n), float(m - n))
             for name, m, n in zip("XYZ", m_point, n_point, strict=True)]
    chars.append(Characteristic("POS", pos, 0.0, pos, None, t.position))
    cone = isinstance(nominal, ir.ConeDef)
    if cone:
        measured = math.radians(fa.angle / 2.0) if fa.angle is not None else half
        lo, hi = t.angle if t.angle is not None else (None, None)
        chars.append(Characteristic("ANGLE", math.degrees(measured), math.degrees(half),
                                    math.degrees(measured - half), lo, hi))
    elif fa.diameter is not None:
        lo, hi = t.diameter if t.diameter is not None else (None, None)
        chars.append(Characteristic("D", fa.diameter, diameter, fa.diameter - diameter,
                                    lo, hi))
    asked = [n for n, v in (("FORM", t.form), ("RON", t.roundness), ("TAPER", t.taper))
             if v is not None]
    if asked:
        notes.append(f"feature {feature.id}: {', '.join(asked)} not evaluated from a DMIS "
                     "feature actual (the CMM reports them as tolerance actuals)")
    return RevolvedResult(
        feature=feature.id, kind=feature.kind, centre=sp.to_part(fa.position),
        axis=(float(m_axis[0]), float(m_axis[1]), float(m_axis[2])),
        diameter=fa.diameter if fa.diameter is not None else diameter, form=0.0,
        points=(), directions=(), residuals=(), characteristics=tuple(chars),
        half_angle=(math.radians(fa.angle / 2.0) if cone and fa.angle is not None
                    else None))
