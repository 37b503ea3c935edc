"""The feature spec: TOML in, frozen dataclasses out, validated with key paths.

Schema (lengths in ``[part] units``, converted to mm on load; see ``docs/spec.md``)::

    [part]
    model = "sphere25.step"        # relative to this file; optional when features give
    units = "mm"                   # their geometry explicitly ("mm" | "inch")
    number = "4711-020-A"          # optional: the part number (results, QIF, report, store)
    name = "Bearing block"         # optional: the part's name
    raised = 0.0                   # optional: its lowest point above the machine table
                                   # (a fixture, parallels), mm; 0: on the table

    [machine]
    profile = "../machines/vmc-fanuc.toml"   # relative to this file
    dialect = "fanuc"              # optional: overrides the profile's dialect
    clearance_z = 120.0            # optional: overrides the profile's clearance plane
    calibration = "probe.cal.toml" # optional: the probe calibration the in-process
                                   # actions are compiled with (relative to this file)

    [program]
    number = 1001                  # O-number (Fanuc) / program id
    name = "SPHERE TEST"

    [evaluation]                   # optional
    decision_rule = "simple"       # simple | guard_band (ISO 14253-1, docs/results.md)
    form_method = "minimum_zone"   # minimum_zone (ISO 1101) | least_squares

    [[feature]]
    id = "SPH1"                    # [A-Z][A-Z0-9]{0,11}, unique
    kind = "sphere_test"
    face = 1                       # or at = [x, y, z], or centre = [x, y, z] + diameter
    diameter = 25.0                # calibrated diameter (default: the model's)
    layout = "octahedral"          # iso | octahedral | cap
    points = 25                    # cap only
    max_polar_angle = 90.0         # cap only, degrees from the pole
    retract = 5.0                  # optional; must be >= the safe minimum (M1)
    locate = true                  # find the real centre first (machine tools)
    locate_uncertainty = 2.0       # how far the real centre may be from nominal
    tolerance = { form = 0.004, size = 0.004, position = 0.05 }   # optional limits, mm

    [[feature]]                    # a revolved feature (method M2)
    id = "BORE"
    kind = "cylinder"              # circle | cylinder | cone | sphere | torus
    face = 8                       # or at = [x, y, z]: a face of the recognised feature
    sections = [10.0, 40.0]        # depths below the feature's top end (default: recognised)
    points = 8                     # per section
    retract = 2.0                  # optional; the M2 safe distance
    stylus = "D2"                  # optional: the rack's stylus to use (default: the
                                   # largest that plans it; also on lines, planes, freeform)
    setup = "FLIPPED"              # optional: the profile's [[setup]] to measure it in
                                   # (default: as loaded, else the first that reaches it)
    tolerance = { diameter = [0.0, 0.025], position = 0.05, form = 0.01 }
    # position: the zone diameter; form_method = "least_squares" in the tolerance
    # table overrides [evaluation] for this feature

    [[feature]]                    # a free-form face (method M3)
    id = "SURF"
    kind = "freeform"
    face = 6                       # or at = [x, y, z]
    grid = "uv"                    # uv | xy
    points = [5, 4]                # grid points per direction, or spacing = 5.0 (mm)
    margin = 3.0                   # least distance from every edge of the face
    direction = [0, 0, 1]          # guide direction (default +Z, within 60 deg of it)
    method = "vector"              # vector | microplane | vertical2d | vertical
    extra_spacing = 0.5            # extra touches, 0.05-0.5 mm from the guide point
    retract = 2.0                  # optional; approach distance of every touch
    tolerance = { deviation = [-0.05, 0.05] }   # along the nominal normal

Every problem is a ``SpecError`` naming the file, the key path and the value found.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from pathlib import Path

from probegen.constants import MM_PER_INCH
from probegen.errors import ProbegenError, SpecError, did_you_mean
from probegen.files import Table, load_toml
from probegen.geometry.uncertainty import DECISION_RULES
from probegen.machine.profile import MachineProfile, load_profile
from probegen.machine.rack import dialect_problem, star_refusal
from probegen.spec.actions import (
    FORM_METHODS,
    PLANAR_KINDS,
    Actions,
    PlanarSpec,
    read_actions,
    read_planar,
)

Vec3 = tuple[float, float, float]

REVOLVED_KINDS = ("circle", "cylinder", "cone", "sphere", "torus")
"""Revolved feature kinds (method M2), measured in sections of a model's surface."""
FEATURE_KINDS = ("sphere_test", *REVOLVED_KINDS, *PLANAR_KINDS, "freeform")
"""Feature kinds this version plans (method M1: sphere_test; method M2: the revolved
kinds; ``line``/``plane``: touches at given points of a planar face, spec_actions;
method M3: freeform)."""
FREEFORM_METHODS = ("vector", "microplane", "vertical2d", "vertical")
"""How a free-form point is probed and compensated (method M3): along the nominal
normal; vertically with three extra touches on a circle (micro-plane normal); vertically
with two extra touches (2-D profile normal); vertically alone (naive, ``r·ẑ``)."""
FREEFORM_EXTRA = {"vector": 0, "microplane": 3, "vertical2d": 2, "vertical": 0}
"""Extra touches per guide point of each method (for the normal estimate)."""
FREEFORM_STRIDE = 10
"""Touch ``j`` (0 = the guide line's own, 1-3 the extra ones) of guide point ``g`` has
index ``FREEFORM_STRIDE · g + j``: a log line names its guide point and role."""
FREEFORM_GRIDS = ("uv", "xy")
"""Guide-point grids: in the face's parameter space, or an XY grid projected onto it."""
EXTRA_SPACING = (0.05, 0.5)
"""Allowed distance (mm) of the extra touches from the guide point (methods.md, M3)."""
DEFAULT_POINTS = 8
"""Default touches per section of a revolved feature."""

SPHERE_LAYOUTS = ("iso", "octahedral", "cap")
_ID = re.compile(r"[A-Z][A-Z0-9]{0,11}\Z")


@dataclass(frozen=True, slots=True)
class SphereTolerance:
    """Limits for the sphere test (ISO 10360-5 style MPEs), mm; None = not checked.

    Attributes:
        form: limit of the probing form error P_FTU (range of radial residuals).
        size: limit of |P_STU|, the fitted diameter's deviation from the calibrated one.
        position: the diameter of the position zone about the nominal centre (ISO 1101:
            the fitted centre may lie ``position / 2`` from it).
    """

    form: float | None = None
    size: float | None = None
    position: float | None = None


@dataclass(frozen=True, slots=True)
class SphereTest:
    """A 25-point (or n-point) probing test on a reference sphere (method M1).

    Attributes:
        id: feature id, printed in the DPRNT log and used as the DMIS label.
        where: ``file: feature[i]`` for error messages.
        face: model face id of the sphere, or None.
        at: a point near the sphere face, or None.
        centre: explicit nominal centre (mm), or None.
        diameter: calibrated diameter (mm), or None to take the model's.
        layout: ``iso``, ``octahedral`` or ``cap``.
        points: number of points.
        max_polar_angle: largest polar angle from the pole, degrees.
        retract: user retract distance (mm), or None for the safe minimum plus margin.
        locate: whether the program first finds the real centre.
        locate_uncertainty: how far the real centre may be from nominal (mm).
        tolerance: limits for pass/fail.
        actions: ``set_work_offset`` from the located centre (``spec_actions``).
        stylus: the label of the rack's stylus the test is run with (``stylus = "D2"``:
            the program takes it for the test and the calibration it gives is that
            stylus's), or None for the ``[probe]`` stylus.
    """

    id: str
    where: str
    face: int | None
    at: Vec3 | None
    centre: Vec3 | None
    diameter: float | None
    layout: str
    points: int
    max_polar_angle: float
    retract: float | None
    locate: bool
    locate_uncertainty: float
    tolerance: SphereTolerance = SphereTolerance()
    actions: Actions = Actions()
    stylus: str | None = None


@dataclass(frozen=True, slots=True)
class RevolvedTolerance:
    """Limits for a revolved feature, mm; None = not checked.

    Attributes:
        diameter: lowest and highest allowed deviation of the fitted diameter.
        position: diameter of the position zone about the nominal axis (ISO 1101: the
            fitted centre may lie ``position / 2`` from nominal, measured square to
            the axis).
        form: limit of the form error (roundness for a circle, cylindricity for a
            cylinder: the range of the radial residuals).
        roundness: limit of the roundness of each section (cylinder, cone).
        taper: limit of the taper, ``|D(top) − D(bottom)|`` over the measured
            sections (cylinder).
        angle: lowest and highest allowed deviation of a cone's half angle, degrees
            (never scaled by the spec's units).
        form_method: how form (``form``, ``roundness``) is evaluated: ``minimum_zone``
            (ISO 1101, the default) or ``least_squares`` (the range of the residuals
            about the least-squares fit); the feature's ``form_method`` key, else
            ``[evaluation] form_method``.
    """

    diameter: tuple[float, float] | None = None
    position: float | None = None
    form: float | None = None
    roundness: float | None = None
    taper: float | None = None
    angle: tuple[float, float] | None = None
    form_method: str = "minimum_zone"


@dataclass(frozen=True, slots=True)
class RevolvedSpec:
    """A revolved feature of the model measured in sections (method M2).

    Attributes:
        id: feature id.
        where: ``file: feature[i]`` for error messages.
        kind: ``circle``, ``cylinder``, ``cone``, ``sphere`` or ``torus`` (``tolerance``:
            ``diameter`` is the tube diameter of a torus).
        face: a model face id of the feature, or None.
        at: a point near one of its faces, or None.
        sections: depths (mm) of the sections below the feature's top end, measured
            along Z (the feature's axis is vertical), or None for the default sections.
        points: touches per section.
        retract: the M2 safe distance ``d`` (mm), or None for the probe's approach.
        tolerance: limits for pass/fail.
        actions: run-time decisions (``spec_actions``; circles and cylinders).
        stylus: the label of the rack's stylus the spec forces (``stylus = "D2"``), or
            None: the planner picks (``planning.styli``).
        setup: the name of the machine profile's ``[[setup]]`` the spec forces
            (``setup = "FLIPPED"``), or None: the first setup that reaches the feature
            (``planning.setups``).
    """

    id: str
    where: str
    kind: str
    face: int | None
    at: Vec3 | None
    sections: tuple[float, ...] | None
    points: int
    retract: float | None
    tolerance: RevolvedTolerance = RevolvedTolerance()
    actions: Actions = Actions()
    stylus: str | None = None
    setup: str | None = None


@dataclass(frozen=True, slots=True)
class FreeformSpec:
    """A free-form face measured at guide points (method M3).

    Attributes:
        id: feature id.
        where: ``file: feature[i]`` for error messages.
        face: the model face id, or None.
        at: a point near the face, or None.
        grid: ``uv`` or ``xy`` (see :data:`FREEFORM_GRIDS`).
        counts: grid points in u and v (x and y), or None with ``spacing``.
        spacing: grid pitch, mm, or None with ``counts``.
        margin: least distance of a guide point from every edge of the face, mm.
        direction: unit guide direction, out of the material (the probe comes down
            along ``-direction`` for the vertical methods).
        method: one of :data:`FREEFORM_METHODS`.
        extra_spacing: distance of the extra touches from the guide point, mm.
        retract: approach distance of every touch, mm, or None for the probe's.
        deviation: lowest and highest allowed deviation along the nominal normal
            (+ = material added), mm, or None.
        stylus: the label of the rack's stylus the spec forces, or None.
    """

    id: str
    where: str
    face: int | None
    at: Vec3 | None
    grid: str
    counts: tuple[int, int] | None
    spacing: float | None
    margin: float
    direction: Vec3
    method: str
    extra_spacing: float
    retract: float | None
    deviation: tuple[float, float] | None = None
    stylus: str | None = None


Feature = SphereTest | RevolvedSpec | PlanarSpec | FreeformSpec


@dataclass(frozen=True, slots=True)
class Spec:
    """A validated feature spec.

    Attributes:
        source: the spec file as given.
        model: the part model path (resolved against the spec's folder), or None.
        machine: the machine profile.
        dialect: the dialect to emit.
        clearance_z: the clearance plane in work coordinates, mm.
        program_number: O-number / program id.
        program_name: a short upper-case name.
        features: what to measure, in the order given.
        decision_rule: ISO 14253-1 decision rule of the results (``[evaluation]
            decision_rule``): ``simple`` acceptance or ``guard_band``.
        part_number: the part number (``[part] number``), or None.
        part_name: the part's name (``[part] name``), or None.
        raised: how far the part's lowest point stands above the machine table
            (``[part] raised``, mm; :attr:`probegen.cad.Part.raised`).
    """

    source: str
    model: Path | None
    machine: MachineProfile
    dialect: str
    clearance_z: float
    program_number: int
    program_name: str
    features: tuple[Feature, ...]
    decision_rule: str = "simple"
    part_number: str | None = None
    part_name: str | None = None
    raised: float = 0.0


def load_spec(path: str | Path) -> Spec:
    """Load and validate a feature spec (see the module docstring for the schema)."""
    file = str(path)
    base = Path(path).parent
    root = Table(load_toml(path), file, "")
    part = root.table("part")
    units = part.get_str("units", "mm", choices=("mm", "inch")) or "mm"
    k = MM_PER_INCH if units == "inch" else 1.0
    model_name = part.get_str("model")
    number, name = _label(part, "number", 40), _label(part, "name", 80)
    raised = k * (part.get_float("raised", 0.0, minimum=0.0) or 0.0)
    part.done()
    m = root.table("machine", required=True)
    machine = _machine(m, base)
    prog = root.table("program")
    evaluation = _evaluation(root.table("evaluation"))
    spec = Spec(
        source=file,
        model=base / model_name if model_name else None,
        machine=machine,
        dialect=_dialect(m, machine),
        clearance_z=_clearance(m, machine, k),
        program_number=prog.get_int("number", 1001, minimum=1, maximum=9999) or 1001,
        program_name=_program_name(prog),
        features=_features(root, k, evaluation[1], machine),
        decision_rule=evaluation[0],
        part_number=number,
        part_name=name,
        raised=raised,
    )
    m.done()
    prog.done()
    root.done()
    return spec


def _label(t: Table, key: str, longest: int) -> str | None:
    """An optional one-line label (``[part] number``, ``name``): 1 to ``longest``
    printable characters, blanks at either end removed."""
    value = t.get_str(key)
    if value is None:
        return None
    text = value.strip()
    if not 1 <= len(text) <= longest or not text.isprintable():
        raise t.fail(key, f"1-{longest} printable characters on one line")
    return text


def _evaluation(t: Table) -> tuple[str, str]:
    """``[evaluation]``: the decision rule (ISO 14253-1) and the default form method of
    every feature (minimum zone, ISO 1101)."""
    rule = t.get_str("decision_rule", "simple", choices=DECISION_RULES) or "simple"
    method = t.get_str("form_method", "minimum_zone", choices=FORM_METHODS) or "minimum_zone"
    t.done()
    return rule, method


def _machine(t: Table, base: Path) -> MachineProfile:
    name = t.get_str("profile", required=True) or ""
    try:
        profile = load_profile(base / name)
    except SpecError as exc:
        raise SpecError(f"{t.where('profile')}: in the machine profile: {exc}") from None
    cal = t.get_str("calibration")
    if not cal:
        return profile
    from probegen.machine.calibration import load_calibration, stylus_calibration

    try:
        calibration = load_calibration(base / cal)
    except (SpecError, ProbegenError) as exc:
        raise SpecError(f"{t.where('calibration')}: in the probe calibration: {exc}") from None
    chosen = stylus_calibration(calibration, profile.stylus.label, profile.probe.ball_radius,
                                "", t.where("calibration"))
    return dataclasses.replace(profile, calibration=chosen)


def _dialect(t: Table, machine: MachineProfile) -> str:
    """``[machine] dialect``: the profile's, or another its rack, head and tilt allow."""
    dialect = t.get_str("dialect", machine.dialect) or machine.dialect
    problem = dialect_problem(machine.rack, machine.head, machine.tilt, dialect)
    if problem:
        raise SpecError(f"{t.where('dialect')}: expected a dialect the machine profile "
                        f"({machine.source}, dialect {machine.dialect}) can drive, found "
                        f"{dialect!r}: {problem}")
    return dialect


def _clearance(t: Table, machine: MachineProfile, k: float) -> float:
    z = t.get_float("clearance_z")
    return machine.clearance_z if z is None else k * z


def _program_name(t: Table) -> str:
    name = t.get_str("name", "PROBEGEN") or "PROBEGEN"
    if not re.fullmatch(r"[A-Z0-9 ._-]{1,24}", name):
        raise t.fail("name", "1-24 upper-case letters, digits, blanks or . _ -")
    return name


def _features(root: Table, k: float, form_method: str,
              machine: MachineProfile | None = None) -> tuple[Feature, ...]:
    tables = root.tables("feature")
    if not tables:
        raise SpecError(f"{root.file}: feature: expected at least one [[feature]], found none")
    features = tuple(_feature(t, k, form_method, machine) for t in tables)
    seen: set[str] = set()
    for t, f in zip(tables, features, strict=True):
        if f.id in seen:
            raise SpecError(f"{t.where('id')}: expected a unique id, found {f.id!r} again")
        seen.add(f.id)
    return features


def _feature(t: Table, k: float, form_method: str = "minimum_zone",
             machine: MachineProfile | None = None) -> Feature:
    fid = t.get_str("id", required=True) or ""
    if not _ID.match(fid):
        raise t.fail("id", "an id of 1-12 upper-case letters and digits, starting with a letter")
    kind = t.get_str("kind", required=True) or ""
    if kind not in FEATURE_KINDS:
        raise SpecError(f"{t.where('kind')}: expected one of {', '.join(FEATURE_KINDS)}, "
                        f"found {kind!r}{did_you_mean(kind, FEATURE_KINDS)}")
    feature: Feature
    if kind == "sphere_test":
        feature = _sphere_test(t, fid, k)
    elif kind == "freeform":
        feature = _freeform(t, fid, k)
    elif kind in PLANAR_KINDS:
        feature = read_planar(t, fid, kind, k, form_method)
    else:
        feature = _revolved(t, fid, kind, k, form_method)
    feature = dataclasses.replace(feature, stylus=_stylus(t, machine))
    if isinstance(feature, RevolvedSpec):
        feature = dataclasses.replace(feature, setup=_setup(t, machine))
    t.done()
    return feature


def _stylus(t: Table, machine: MachineProfile | None) -> str | None:
    """``stylus = "D2"``: a label of the machine's rack (checked when the machine is
    known), or None."""
    label = t.get_str("stylus")
    if label is None or machine is None:
        return label
    star = star_refusal(machine.styli(), label, machine.source)
    if star is not None:
        raise SpecError(f"{t.where('stylus')}: {star}")
    labels = [s.label for s in machine.styli()]
    if label not in labels:
        raise SpecError(f"{t.where('stylus')}: expected a stylus of the machine's rack "
                        f"({', '.join(labels)}; {machine.source}: [[probe.stylus]]), found "
                        f"{label!r}{did_you_mean(label, labels)}")
    return label


def _setup(t: Table, machine: MachineProfile | None) -> str | None:
    """``setup = "FLIPPED"``: the name of one of the machine profile's ``[[setup]]``
    (checked when the machine is known), or None."""
    name = t.get_str("setup")
    if name is None or machine is None:
        return name
    names = [s.name for s in machine.setups]
    if name not in names:
        known = ", ".join(names) if names else "none"
        raise SpecError(f"{t.where('setup')}: expected a setup of the machine profile "
                        f"({known}; {machine.source}: [[setup]]), found "
                        f"{name!r}{did_you_mean(name, names)}")
    return name


def _scaled(v: tuple[float, ...] | None, k: float) -> Vec3 | None:
    return None if v is None else (v[0] * k, v[1] * k, v[2] * k)


def _sphere_test(t: Table, fid: str, k: float) -> SphereTest:
    face = t.get_int("face", minimum=1)
    at = _scaled(t.get_vec("at"), k)
    centre = _scaled(t.get_vec("centre"), k)
    given = [key for key, v in (("face", face), ("at", at), ("centre", centre)) if v is not None]
    if len(given) != 1:
        raise SpecError(f"{t.where('face')}: expected exactly one of face, at, centre, "
                        f"found {', '.join(given) or 'none'}")
    diameter = t.get_float("diameter", positive=True)
    if centre is not None and diameter is None:
        raise SpecError(f"{t.where('diameter')}: required with centre, found none")
    layout = t.get_str("layout", "octahedral", choices=SPHERE_LAYOUTS) or "octahedral"
    points = t.get_int("points", 25, minimum=3, maximum=500) or 25
    if layout != "cap" and points != 25:
        raise t.fail("points", f"25 for the {layout} layout (use layout = \"cap\" for others)")
    polar = t.get_float("max_polar_angle", 90.0, positive=True, maximum=150.0) or 90.0
    if layout != "cap" and polar != 90.0:
        raise t.fail("max_polar_angle", f"90 for the {layout} layout")
    retract = t.get_float("retract", positive=True)
    uncertainty = t.get_float("locate_uncertainty", 2.0, minimum=0.0) or 0.0
    return SphereTest(
        id=fid, where=f"{t.file}: {t.path}", face=face, at=at, centre=centre,
        diameter=None if diameter is None else diameter * k, layout=layout, points=points,
        max_polar_angle=polar, retract=None if retract is None else retract * k,
        locate=t.get_bool("locate", True), locate_uncertainty=uncertainty * k,
        tolerance=_sphere_tolerance(t.table("tolerance"), k),
        actions=_sphere_actions(t, k),
    )


def _sphere_actions(t: Table, k: float) -> Actions:
    """A sphere test's actions: only ``set_work_offset`` from the located centre."""
    actions = read_actions(t, k, "XYZ")
    other = [key for key, v in (("update_tool", actions.tool), ("align", actions.align),
                                ("on_out_of_tolerance", actions.checked or None)) if v]
    if other:
        raise SpecError(f"{t.where(other[0])}: a sphere_test takes only set_work_offset "
                        f"(from its located centre), found {', '.join(other)}")
    if actions.work_offset is not None and not t.get_bool("locate", True):
        raise SpecError(f"{t.where('locate')}: set_work_offset on a sphere_test needs "
                        f"locate = true (the control computes the centre), found false")
    return actions


def _sphere_tolerance(t: Table, k: float) -> SphereTolerance:
    values = {key: t.get_float(key, positive=True) for key in ("form", "size", "position")}
    t.done()
    return SphereTolerance(**{key: None if v is None else v * k for key, v in values.items()})


def _face_or_at(t: Table, k: float) -> tuple[int | None, Vec3 | None]:
    """The ``face`` id or the ``at`` point (exactly one)."""
    face = t.get_int("face", minimum=1)
    at = _scaled(t.get_vec("at"), k)
    given = [key for key, v in (("face", face), ("at", at)) if v is not None]
    if len(given) != 1:
        raise SpecError(f"{t.where('face')}: expected exactly one of face, at, "
                        f"found {', '.join(given) or 'none'}")
    return face, at


def _revolved(t: Table, fid: str, kind: str, k: float, form_method: str) -> RevolvedSpec:
    face, at = _face_or_at(t, k)
    sections = _depths(t, k)
    if kind == "circle" and sections is not None and len(sections) != 1:
        raise t.fail("sections", "one depth for a circle (use kind = \"cylinder\" for more)")
    points = t.get_int("points", DEFAULT_POINTS, minimum=3, maximum=500) or DEFAULT_POINTS
    retract = t.get_float("retract", positive=True)
    return RevolvedSpec(
        id=fid, where=f"{t.file}: {t.path}", kind=kind, face=face, at=at, sections=sections,
        points=points, retract=None if retract is None else retract * k,
        tolerance=_revolved_tolerance(t.table("tolerance"), k, form_method),
        actions=read_actions(t, k, "XY"),
    )


def _depths(t: Table, k: float) -> tuple[float, ...] | None:
    value = t.get_any("sections")
    if value is None:
        return None
    ok = isinstance(value, list) and 1 <= len(value) <= 50 and all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
        and v >= 0.0 for v in value)
    if not ok:
        raise t.fail("sections", "an array of 1-50 depths >= 0 (mm below the feature's top)")
    return tuple(float(v) * k for v in value)


def _revolved_tolerance(t: Table, k: float, form_method: str) -> RevolvedTolerance:
    diameter = t.get_limits("diameter", k)
    angle = t.get_limits("angle", unit=" in degrees")
    values = {key: t.get_float(key, positive=True)
              for key in ("position", "form", "roundness", "taper")}
    method = t.get_str("form_method", form_method, choices=FORM_METHODS) or form_method
    t.done()
    return RevolvedTolerance(diameter, angle=angle, form_method=method,
                             **{key: None if v is None else v * k for key, v in values.items()})


def _freeform(t: Table, fid: str, k: float) -> FreeformSpec:
    face, at = _face_or_at(t, k)
    grid = t.get_str("grid", "uv", choices=FREEFORM_GRIDS) or "uv"
    counts = _grid_counts(t)
    spacing = t.get_float("spacing", positive=True)
    if (counts is None) == (spacing is None):
        raise SpecError(f"{t.where('points')}: expected exactly one of points, spacing, "
                        f"found {'both' if counts else 'none'}")
    margin = t.get_float("margin", 1.0 / k, minimum=0.0)
    method = t.get_str("method", "vector", choices=FREEFORM_METHODS) or "vector"
    lo, hi = EXTRA_SPACING
    extra = t.get_float("extra_spacing", 0.5 / k, minimum=lo / k, maximum=hi / k)
    retract = t.get_float("retract", positive=True)
    return FreeformSpec(
        id=fid, where=f"{t.file}: {t.path}", face=face, at=at, grid=grid, counts=counts,
        spacing=None if spacing is None else spacing * k, margin=(margin or 0.0) * k,
        direction=_direction(t), method=method, extra_spacing=(extra or 0.0) * k,
        retract=None if retract is None else retract * k,
        deviation=_deviation(t.table("tolerance"), k),
    )


def _grid_counts(t: Table) -> tuple[int, int] | None:
    value = t.get_any("points")
    if value is None:
        return None
    ok = isinstance(value, list) and len(value) == 2 and all(
        isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= 1000 for v in value)
    if not ok:
        raise t.fail("points", "[n_u, n_v]: two integers from 1 to 1000 (grid points per "
                               "direction)")
    return (value[0], value[1])


def _direction(t: Table) -> Vec3:
    d = t.get_vec("direction") or (0.0, 0.0, 1.0)
    size = math.sqrt(sum(v * v for v in d))
    if size == 0.0 or d[2] / size < math.cos(math.radians(60.0)):
        raise t.fail("direction", "a vector out of the material within 60 deg of +Z "
                                  "(the probe comes down along it)")
    return (d[0] / size, d[1] / size, d[2] / size)


def _deviation(t: Table, k: float) -> tuple[float, float] | None:
    value = t.get_limits("deviation", k)
    t.done()
    return value
