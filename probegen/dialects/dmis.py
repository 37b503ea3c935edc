"""DMIS 5 (Dimensional Measuring Interface Standard) for CMMs.

Conventions (see ``docs/dialects.md``):

* ``GOTO`` positions the sensor's tip centre; every planned positioning move becomes one.
* A touch becomes ``PTMEAS/CART,x,y,z,i,j,k`` with the nominal contact point and the
  outward surface normal; the CMM approaches and retracts along the normal by the
  ``SNSET/APPRCH`` and ``SNSET/RETRCT`` distances, which are set before each measurement
  to the planned approach distance, so the planned retract moves are implicit.
* ``SNSET/SEARCH`` is the planned overtravel.
* A free-form feature (``ir.FreeformDef``, method M3) is measured point by point: touch
  ``k`` becomes ``F(<id>_<k>)=FEAT/POINT,CART,x,y,z,i,j,k`` (the touch's nominal point
  and vector: for a vertical touch the point ``r`` below the theoretical ball centre and
  the guide direction), ``MEAS/POINT,...,1``, one ``PTMEAS``, ``ENDMES`` and
  ``OUTPUT/FA(<id>_<k>)``; the moves between become ``GOTO``.
* A ``LocalFrame`` becomes ``D(name)=TRANS/XORIG,FA(f),YORIG,FA(f),ZORIG,FA(f)``; the frame in
  force at the start is saved as ``D(PCS)`` and recalled by ``RestoreFrame``.
* Orientations and stylus changes (issue 17): every coordinate is written in work
  coordinates (the nodes after an ``ir.Orient`` are in its frame: they are mapped back
  with :func:`probegen.ir.frames.in_work`, the feature nominals ``F(..)=FEAT/...`` too),
  and the moves around an orientation change are the IR's ``GOTO``s.  One sensor is
  declared in the header per stylus and head orientation the program uses:
  ``S(<label>)=SNSDEF/PROBE,INDEX,POL,a,b,0,0,-1,<length>,<ball>``, the start stylus at
  A0 B0 keeping its own label (its rack label, ``ir.Setup.stylus``; ``PRB<tool>`` for a
  probe without a rack), every other ``<stylus>_A<a>B<b>`` (``-`` written
  ``M``, a decimal point ``P``: ``D2_A90BM90``).  Each ``Orient`` and ``SelectStylus``
  selects the sensor of the stylus and head angles then in force: ``SNSLCT/S(...)``.
  ``a`` and ``b`` are the head angles the ``Orient`` carries (``ir.Orient.head``),
  written as they are: DMIS 5 ``SNSDEF/PROBE,INDEX,POL,tilt,rotation,i,j,k,len,diam``
  (the probe head's A angle, the tilt of the stylus away from the head's mounting axis,
  and its B angle, the rotation about that axis, as CMM software names them
  ``T1A90B90``; ``0,0,-1`` the mounting direction, the stylus straight down at A0 B0;
  ``len`` from the head's centre of rotation to the ball centre).  Which way B0 points
  when tilted is the CMM's own convention: the planner chooses the angles
  (``planning/orient.py``), the virtual CMM reads them back (``sim/cmm/sensors.py``).
  A tilted ``Orient`` without head angles is refused (a CMM turns its probe only through
  the head).
* DMIS has no run-time arithmetic: ``ir.Var``, ``Assign`` and ``ReportCentre`` are
  unsupported.
* The in-process decisions (``ir_actions``): tolerances and the part frame, see
  ``dialects/dmis_actions.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

from probegen import ir
from probegen.dialects.base import Dialect
from probegen.dialects.dmis_actions import check_lines, frame_lines
from probegen.errors import UnsupportedError
from probegen.ir import frames


@dataclass(frozen=True, slots=True)
class Sensor:
    """A stylus as a DMIS sensor: its label, length (head centre to ball centre) and ball
    diameter, mm."""

    label: str
    length: float
    ball: float


def label_angle(text: str) -> str:
    """A head angle as label characters: ``-`` as ``M``, the decimal point as ``P``."""
    return text.replace("-", "M").replace(".", "P")


class Dmis(Dialect):
    """DMIS 5.x part program."""

    NAME: ClassVar[str] = "dmis"
    EXTENSION: ClassVar[str] = ".dmi"
    LINE_LENGTH: ClassVar[int] = 256
    PROFILE_LIMITS: ClassVar[bool] = False
    LOCAL_FRAMES: ClassVar[bool] = True
    FREE_FIT: ClassVar[bool] = True
    UNITS_WORD: ClassVar[dict[str, str]] = {"mm": "MM", "inch": "INCH"}
    """The DMIS length unit word for each unit system."""
    FEED_UNIT: ClassVar[dict[str, tuple[str, float]]] = {"mm": ("MPM", 1e-3),
                                                         "inch": ("IPM", 1.0)}
    """Feed unit word and factor from program units per minute."""

    def point(self, p: ir.Point, node: object) -> list[str]:
        """A point as three numbers; run-time values are not expressible."""
        out = []
        for c in p:
            if isinstance(c, ir.Var):
                raise self.unsupported(node, "DMIS has no run-time variables")
            out.append(self.length(c))
        return out

    def feed(self, mm_per_min: float) -> str:
        word, k = self.FEED_UNIT[self.units]
        return f"{word},{self.num(self.scale(mm_per_min) * k, 3)}"

    def lower(self, program: ir.Program) -> dict[str, Any]:
        s = program.setup
        final = (ir.SetWorkOffset, ir.Align, ir.UpdateTool)
        self.directions = {n.feature: n.direction for n in program.body
                           if isinstance(n, ir.Check) and n.fit == "line"}
        self.start = Sensor(s.stylus or f"PRB{s.tool_number}", s.probe_length,
                            s.ball_diameter)
        self.sensors: dict[str, dict[str, str]] = {}
        self.stylus, self.head = self.start, (0.0, 0.0)
        self.sensor_label()
        body = [self.block(node) for node in self.in_work(program.body)
                if not isinstance(node, final)]
        frame = frame_lines(self, [n for n in program.body if isinstance(n, final)],
                            [n.feature for n in program.body if isinstance(n, ir.Check)],
                            self.directions)
        if frame:
            body.append({"kind": "lines", "lines": frame})
        local = any(isinstance(n, ir.LocalFrame) for n in ir.walk(program.body))
        return {"s": s, "start": self.start.label, "units": self.UNITS_WORD[s.units],
                "body": body, "frames": local,
                "sensors": list(self.sensors.values()),
                "posvel": self.feed(s.position_feed), "mesvel": self.feed(s.probe_feed)}

    def in_work(self, body: tuple[ir.Node, ...]) -> list[ir.Node]:
        """The top-level nodes in work coordinates (:func:`probegen.ir.frames.in_work`).

        Raises:
            UnsupportedError: a local frame inside a tilted orientation (its coordinates
                are relative to a measured centre, not to the orientation's frame).
        """
        out: list[ir.Node] = []
        for node, orient in frames.in_work(body):
            turned = orient is not None and not isinstance(node, ir.Orient) and (
                not frames.is_identity(orient.rotation) or any(orient.origin))
            if turned and isinstance(node, ir.LocalFrame | ir.RestoreFrame):
                raise self.unsupported(node, f"a local frame inside orientation "
                                             f"{orient.name}")  # type: ignore[union-attr]
            out.append(node)
        return out

    def sensor_label(self) -> str:
        """The label of the sensor for the stylus and head angles in force, declared on
        first use (the start stylus at A0 B0 keeps its own label, module docstring)."""
        a, b = self.head
        st = self.stylus
        label = st.label if st == self.start and a == 0.0 and b == 0.0 else \
            f"{st.label}_A{label_angle(self.angle(a))}B{label_angle(self.angle(b))}"
        if label not in self.sensors:
            self.sensors[label] = {"label": label, "a": self.angle(a), "b": self.angle(b),
                                   "length": self.length(st.length),
                                   "ball": self.length(st.ball)}
        return label

    def angle(self, value: float) -> str:
        """A head angle, deg, with the digits it needs (``90``, ``-172.5``)."""
        return self.num(value, 4).rstrip("0").rstrip(".")

    def select(self, comment: str) -> dict[str, Any]:
        """``SNSLCT`` of the sensor now in force, after a comment."""
        return {"kind": "lines", "lines": [f"$$ {comment}", f"SNSLCT/S({self.sensor_label()})"]}

    def orient(self, node: ir.Orient) -> dict[str, Any]:
        """An orientation: the head angles it carries (A0 B0 for the identity).

        Raises:
            UnsupportedError: a turned frame without head angles.
        """
        if node.head is not None:
            self.head = (float(node.head[0]), float(node.head[1]))
        elif frames.is_identity(node.rotation):
            self.head = (0.0, 0.0)
        else:
            raise UnsupportedError(
                f"dialect {self.NAME!r}: orientation {node.name} turns the probe but gives no "
                "head angles (ir.Orient.head): a CMM turns its stylus with the indexable "
                "head; give the machine profile a [head]")
        return self.select(f"ORIENT {node.name}")

    def select_stylus(self, node: ir.SelectStylus) -> dict[str, Any]:
        """Another stylus of the rack, at the head angles in force."""
        start = self.start
        same = node.label == start.label
        self.stylus = start if same else Sensor(node.label, node.length, node.ball_diameter)
        return self.select(f"STYLUS {node.label}")

    def block(self, node: ir.Node) -> dict[str, Any]:
        """One top-level IR node as the values its template macro prints."""
        if isinstance(node, ir.Rotary | ir.WorkOffsetShift):
            raise self.unsupported(node, "a CMM program has no rotary axes or machine work "
                                         "offsets; method M4 emits Fanuc Macro B and LinuxCNC")
        if isinstance(node, ir.Comment):
            return {"kind": "comment", "text": node.text}
        if isinstance(node, ir.Move):
            return self.move(node)
        if isinstance(node, ir.FeatureBlock) and isinstance(node.feature, ir.FreeformDef):
            return self.freeform(node, node.feature)
        if isinstance(node, ir.FeatureBlock):
            return self.feature(node)
        if isinstance(node, ir.LocalFrame):
            return {"kind": "frame", "name": node.name, "feature": node.feature}
        if isinstance(node, ir.RestoreFrame):
            return {"kind": "restore"}
        if isinstance(node, ir.Check):
            return {"kind": "lines", "lines": check_lines(self, node)}
        if isinstance(node, ir.Orient):
            return self.orient(node)
        if isinstance(node, ir.SelectStylus):
            return self.select_stylus(node)
        raise self.unsupported(node, "DMIS has no run-time arithmetic")

    def move(self, node: ir.Move) -> dict[str, Any]:
        return {"kind": "goto", "xyz": self.point(node.target, node)}

    def feature(self, node: ir.FeatureBlock) -> dict[str, Any]:
        f = node.feature
        steps: list[dict[str, Any]] = []
        touches = [n for n in node.body if isinstance(n, ir.Touch)]
        approaches = {n.approach for n in touches}
        overtravels = {n.overtravel for n in touches}
        if len(approaches) > 1 or len(overtravels) > 1:
            raise self.unsupported(node, "one approach and search distance per measurement")
        for n in node.body:
            if isinstance(n, ir.Touch):
                steps.append({"kind": "ptmeas", "xyz": self.point(n.contact, n),
                              "ijk": [self.num(v, 6) for v in n.normal]})
            elif isinstance(n, ir.Move) and n.mode is not ir.MoveMode.RETRACT:
                steps.append(self.move(n))
            elif isinstance(n, ir.Comment):
                steps.append({"kind": "comment", "text": n.text})
            elif not isinstance(n, ir.Move):
                raise self.unsupported(n, "not inside a DMIS measurement")
        word, feat = self.definition(f, node)
        return {
            "kind": "feature", "id": f.id, "n": len(touches), "word": word, "feat": feat,
            "approach": self.length(approaches.pop()) if approaches else None,
            "search": self.length(overtravels.pop()) if overtravels else None,
            "steps": steps,
        }

    def freeform(self, node: ir.FeatureBlock, f: ir.FreeformDef) -> dict[str, Any]:
        """A free-form feature: each touch ``k`` a ``FEAT/POINT`` ``<id>_<k>`` (nominal
        point and vector of the touch) measured by one PTMEAS; moves between as GOTO."""
        items: list[dict[str, Any]] = []
        for n in node.body:
            if isinstance(n, ir.Touch):
                xyz = self.point(n.contact, n)
                ijk = [self.num(v, 6) for v in n.normal]
                items.append({
                    "kind": "feature", "id": f"{f.id}_{n.index}", "n": 1, "word": "POINT",
                    "feat": ",".join(["POINT", "CART", *xyz, *ijk]),
                    "approach": self.length(n.approach), "search": self.length(n.overtravel),
                    "steps": [{"kind": "ptmeas", "xyz": xyz, "ijk": ijk}]})
            elif isinstance(n, ir.Move) and n.mode is not ir.MoveMode.RETRACT:
                items.append(self.move(n))
            elif isinstance(n, ir.Comment):
                items.append({"kind": "comment", "text": n.text})
            elif not isinstance(n, ir.Move):
                raise self.unsupported(n, "not inside a DMIS free-form measurement")
        return {"kind": "freeform", "title": self.feature_title(f), "entries": items}

    def definition(self, f: ir.FeatureDef, node: object) -> tuple[str, str]:
        """The MEAS word and the ``FEAT/`` text of a nominal feature."""
        side = "INNER" if f.inner else "OUTER"
        if isinstance(f, ir.PlaneDef):
            values = [*self.point(f.point, node), *(self.num(v, 6) for v in f.normal)]
            return "PLANE", ",".join(["PLANE", "CART", *values])
        if isinstance(f, ir.LineDef):
            values = [*self.point(f.start, node), *self.point(f.end, node),
                      *(self.num(v, 6) for v in f.normal)]
            return "LINE", ",".join(["LINE", "BND", "CART", *values])
        if isinstance(f, ir.SphereDef):
            values = [*self.point(f.centre, node), self.length(f.diameter)]
            return "SPHERE", ",".join(["SPHERE", side, "CART", *values])
        if isinstance(f, ir.ConeDef):
            ijk = [self.num(v, 6) for v in f.axis]
            values = [*self.point(f.apex, node), *ijk,
                      self.num(2.0 * math.degrees(f.half_angle), 6)]
            return "CONE", ",".join(["CONE", side, "CART", *values])
        if isinstance(f, ir.FreeformDef):
            raise self.unsupported(node, "a free-form feature is measured point by point")
        ijk = [self.num(v, 6) for v in f.axis]
        if isinstance(f, ir.TorusDef):
            values = [*self.point(f.centre, node), *ijk, self.length(f.major_diameter),
                      self.length(f.minor_diameter)]
            tube = "INNER" if f.concave else "OUTER"
            return "TORUS", ",".join(["TORUS", tube, "CART", *values])
        values = [*self.point(f.centre, node), *ijk, self.length(f.diameter)]
        if isinstance(f, ir.CylinderDef):
            return "CYLNDR", ",".join(["CYLNDR", side, "CART", *values, self.length(f.length)])
        return "CIRCLE", ",".join(["CIRCLE", side, "CART", *values])
