"""The geometric errors of a machine: 21 terms of the linear axes, rotary axis locations.

Every error is **actual − nominal** of the motion of the **tool relative to the
workpiece** (the motion a laser, a grating or a ball bar between spindle and table
sees), in the machine's right-handed X, Y, Z frame (ISO 841).  So a table axis and a
head axis read alike: ``δ_xx > 0`` means the tool ends up farther along +X on the part
than commanded, whichever body moves.

Linear axis ``j`` in X, Y, Z has six error motions, each a polynomial in the axis
position ``q`` (mm): ``f(q) = Σ c_k·(q / scale)^k``.  Names: ``δ_ij`` is the
translation along ``i`` and ``ε_ij`` the rotation (right-hand, about ``i``) during the
motion of ``j``; ISO 230-1:2012 writes them ``E_IJ`` with A, B, C for rotations about
X, Y, Z:

====  ===========  ===========================  ============  =========
axis  positioning  straightness                roll          pitch, yaw
====  ===========  ===========================  ============  =========
X     δxx = EXX    δyx = EYX, δzx = EZX         εxx = EAX     εyx = EBX, εzx = ECX
Y     δyy = EYY    δxy = EXY, δzy = EZY         εyy = EBY     εxy = EAY, εzy = ECY
Z     δzz = EZZ    δxz = EXZ, δyz = EYZ         εzz = ECZ     εxz = EAZ, εyz = EBZ
====  ===========  ===========================  ============  =========

Linear errors are those of the axis' reference point (the tool point with the other
axes at zero and no tool offset); the angular errors turn everything that the axis
carries (the rest of the chain towards the tool, see :mod:`probegen.machine.kinematics`)
about that point, so their Abbe offsets are the positions of the later axes plus the
tool offset.

Squareness (X is the reference axis; radians, constant):

- ``S_xy``: Y moves along ``(S_xy, 1, 0)``: commanding ``y`` also moves x by
  ``S_xy·y``.  Positive when the angle between +X and +Y is below 90°.
  ISO 230-1: ``E_C0Y = −S_xy``.
- ``S_xz``: Z moves along ``(S_xz, S_yz, 1)``: x moves by ``S_xz·z``; ``E_B0Z = S_xz``.
- ``S_yz``: y moves by ``S_yz·z``; ``E_A0Z = −S_yz``.

Rotary axes (five-axis machine, ISO 230-7 location errors, position independent, mm and
rad): the actual axis line passes ``position`` away from the nominal one and its
direction is the nominal one turned by the small rotation vector ``tilt``.  C (nominal
axis +Z): ``position = (EX0C, EY0C, 0)``, ``tilt = (EA0C, EB0C, 0)``.  B (nominal axis
+Y, through the pivot point the X, Y, Z positions command): ``position = (EX0B, 0,
EZ0B)``, ``tilt = (EA0B, 0, EC0B)``.  Method M4's installation offset ``δ`` is the x of
the B-axis centre (at X = 0) less the x of the C-axis centre, so ``δ = −EX0C``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.polynomial import polynomial as npoly
from numpy.typing import ArrayLike, NDArray

from probegen.errors import ProbegenError, SpecError
from probegen.files import Table, load_toml

FloatArray = NDArray[np.float64]

LINEAR_AXES = ("X", "Y", "Z")
ROTARY_AXES = ("B", "C")
DEFAULT_SCALE = 1000.0
"""Default polynomial variable scale, mm: coefficients are per (q / 1 m)^k, so every
coefficient of a realistic error is of the size of the error itself."""

#: ISO 230-1 names of each linear axis' terms: (translations x, y, z), (rotations x, y, z).
ISO_NAMES: dict[str, tuple[tuple[str, str, str], tuple[str, str, str]]] = {
    j: ((f"EX{j}", f"EY{j}", f"EZ{j}"), (f"EA{j}", f"EB{j}", f"EC{j}")) for j in LINEAR_AXES
}
#: ISO 230-7 names of each rotary axis' location errors: (position), (tilt) components.
ROTARY_NAMES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "B": (("EX0B", "", "EZ0B"), ("EA0B", "", "EC0B")),
    "C": (("EX0C", "EY0C", ""), ("EA0C", "EB0C", "")),
}
LENGTH_UNITS = {"mm": 1.0, "um": 1e-3}
ANGLE_UNITS = {"rad": 1.0, "urad": 1e-6, "arcsec": np.pi / 648000.0}


def _zeros() -> FloatArray:
    """Coefficients of three zero polynomials, (3, 1)."""
    return np.zeros((3, 1))


@dataclass(frozen=True)
class AxisErrors:
    """The six error motions of one linear axis.

    Attributes:
        linear: (3, m) float: rows are the polynomial coefficients of the translation
            errors along x, y, z (mm), lowest power first.
        angular: (3, m) float: the rotation errors about x, y, z (rad), likewise.
    """

    linear: FloatArray = field(default_factory=_zeros)
    angular: FloatArray = field(default_factory=_zeros)

    def __post_init__(self) -> None:
        for name in ("linear", "angular"):
            value = np.asarray(getattr(self, name), dtype=np.float64)
            if value.ndim != 2 or value.shape[0] != 3 or value.shape[1] == 0:
                raise ProbegenError(f"axis errors: expected {name} coefficients of shape "
                                    f"(3, m), found shape {value.shape}")
            object.__setattr__(self, name, value)

    def evaluate(self, q: ArrayLike, scale: float) -> tuple[FloatArray, FloatArray]:
        """The errors at axis positions ``q``.

        Args:
            q: (n,) float, axis positions, mm.
            scale: the polynomial variable is ``q / scale``.

        Returns:
            Translations (n, 3) mm and rotation vectors (n, 3) rad.
        """
        x = np.asanyarray(q, dtype=np.float64) / scale
        d = npoly.polyval(x, self.linear.T)
        e = npoly.polyval(x, self.angular.T)
        return np.asarray(d.T), np.asarray(e.T)


@dataclass(frozen=True)
class RotaryErrors:
    """Location errors of one rotary axis (see the module docstring).

    Attributes:
        position: (3,) float, mm: offset of the actual axis line from the nominal one.
        tilt: (3,) float, rad: small rotation taking the nominal direction to the actual.
    """

    position: FloatArray = field(default_factory=lambda: np.zeros(3))
    tilt: FloatArray = field(default_factory=lambda: np.zeros(3))


@dataclass(frozen=True)
class ErrorModel:
    """All geometric errors of a machine.

    Attributes:
        x, y, z: error motions of the linear axes.
        sxy, sxz, syz: squareness errors, rad (signs in the module docstring).
        b, c: location errors of the rotary axes (unused by a 3-axis machine).
        scale: polynomial variable scale, mm.
    """

    x: AxisErrors = field(default_factory=AxisErrors)
    y: AxisErrors = field(default_factory=AxisErrors)
    z: AxisErrors = field(default_factory=AxisErrors)
    sxy: float = 0.0
    sxz: float = 0.0
    syz: float = 0.0
    b: RotaryErrors = field(default_factory=RotaryErrors)
    c: RotaryErrors = field(default_factory=RotaryErrors)
    scale: float = DEFAULT_SCALE

    @classmethod
    def zero(cls) -> ErrorModel:
        """A perfect machine."""
        return cls()

    def axis(self, name: str) -> AxisErrors:
        """The error motions of linear axis ``name`` (``"X"``, ``"Y"`` or ``"Z"``)."""
        return {"X": self.x, "Y": self.y, "Z": self.z}[name]

    def rotary(self, name: str) -> RotaryErrors:
        """The location errors of rotary axis ``name`` (``"B"`` or ``"C"``)."""
        return {"B": self.b, "C": self.c}[name]

    def direction(self, name: str) -> FloatArray:
        """Actual (first-order) direction of linear axis ``name``, (3,) float."""
        return {"X": np.array([1.0, 0.0, 0.0]), "Y": np.array([self.sxy, 1.0, 0.0]),
                "Z": np.array([self.sxz, self.syz, 1.0])}[name]

    @property
    def delta(self) -> float:
        """Method M4's installation offset ``δ`` of the C-axis centre along X, mm."""
        return float(-self.c.position[0])

    def with_delta(self, delta: float) -> ErrorModel:
        """A copy with the C-axis centre ``delta`` mm off the B-axis centre (M4)."""
        position = np.array(self.c.position, dtype=np.float64)
        position[0] = -delta
        return replace(self, c=replace(self.c, position=position))


# ------------------------------------------------------------------------ loading


def load_errors(path: str | Path) -> ErrorModel:
    """Load an error model from the ``[errors]`` table of a TOML file.

    See ``samples/machines/errors-example.toml`` for the format.  Values are in
    ``length_unit`` (``mm`` or ``um``) and ``angle_unit`` (``rad``, ``urad`` or
    ``arcsec``); linear-axis terms are arrays of polynomial coefficients in
    ``q / position_scale`` (mm), lowest power first; absent terms are zero.

    Raises:
        SpecError: the file is missing or malformed; the message names the key path.
    """
    root = Table(load_toml(path), str(path), "")
    root.table("kinematics")  # read by load_machine; allowed here
    model = read_errors(root.table("errors", required=True))
    root.done()
    return model


def read_errors(t: Table) -> ErrorModel:
    """Read an ``[errors]`` table (see :func:`load_errors`)."""
    length = LENGTH_UNITS[t.get_str("length_unit", "um", choices=tuple(LENGTH_UNITS)) or "um"]
    angle = ANGLE_UNITS[t.get_str("angle_unit", "urad", choices=tuple(ANGLE_UNITS)) or "urad"]
    scale = t.get_float("position_scale", DEFAULT_SCALE, positive=True) or DEFAULT_SCALE
    axes = {j: _axis(t.table(j), j, length, angle) for j in LINEAR_AXES}
    sq = t.table("squareness")
    s = [angle * (sq.get_float(k, 0.0) or 0.0) for k in ("S_xy", "S_xz", "S_yz")]
    sq.done()
    rotary = {j: _rotary(t.table(j), j, length, angle) for j in ROTARY_AXES}
    t.done()
    return ErrorModel(axes["X"], axes["Y"], axes["Z"], s[0], s[1], s[2],
                      rotary["B"], rotary["C"], scale)


def _coefficients(t: Table, key: str) -> list[float]:
    """The coefficient array under ``key`` (``[0.0]`` when absent)."""
    if not t.has(key):
        return [0.0]
    value = t.data[key]
    numbers = isinstance(value, list) and len(value) > 0 and all(
        isinstance(v, int | float) and not isinstance(v, bool) and np.isfinite(v)
        for v in value)
    if not numbers:
        raise t.fail(key, "an array of polynomial coefficients (numbers), lowest power first")
    return [float(v) for v in value]


def _stack(rows: Sequence[list[float]], unit: float) -> FloatArray:
    """Rows of coefficients padded with zeros to one length, times ``unit``: (3, m)."""
    width = max(len(r) for r in rows)
    return unit * np.array([r + [0.0] * (width - len(r)) for r in rows])


def _axis(t: Table, name: str, length: float, angle: float) -> AxisErrors:
    """Read the table of linear axis ``name`` (ISO 230-1 keys)."""
    moves, turns = ISO_NAMES[name]
    linear = _stack([_coefficients(t, k) for k in moves], length)
    angular = _stack([_coefficients(t, k) for k in turns], angle)
    t.done()
    return AxisErrors(linear, angular)


def _rotary(t: Table, name: str, length: float, angle: float) -> RotaryErrors:
    """Read the table of rotary axis ``name`` (ISO 230-7 keys; C also takes ``delta``)."""
    moves, turns = ROTARY_NAMES[name]
    position = np.array([length * (t.get_float(k, 0.0) or 0.0) if k else 0.0 for k in moves])
    tilt = np.array([angle * (t.get_float(k, 0.0) or 0.0) if k else 0.0 for k in turns])
    if name == "C" and t.has("delta"):
        if "EX0C" in t.data:
            raise SpecError(f"{t.where('delta')}: give delta or EX0C, not both "
                            f"(delta = -EX0C)")
        position[0] = -length * (t.get_float("delta", 0.0) or 0.0)
    t.done()
    return RotaryErrors(position, tilt)
