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
* DMIS has no run-time arithmetic: ``ir.Var``, ``Assign`` and ``ReportCentre`` are
  unsupported.
* The in-process decisions (``ir_actions``): tolerances and the part frame, see
  ``dialects/dmis_actions.py``.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

from probegen import ir
from probegen.dialects.base import Dialect
from probegen.dialects.dmis_actions import check_lines, frame_lines


class Dmis(Dialect):
    """DMIS 5.x part program."""

    NAME: ClassVar[str] = "dmis"
    EXTENSION: ClassVar[str] = ".dmi"
    LINE_LENGTH: ClassVar[int] = 256
    PROFILE_LIMITS: ClassVar[bool] = False
    LOCAL_FRAMES: ClassVar[bool] = True
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
        body = [self.block(node) for node in program.body if not isinstance(node, final)]
        frame = frame_lines(self, [n for n in program.body if isinstance(n, final)],
                            [n.feature for n in program.body if isinstance(n, ir.Check)],
                            self.directions)
        if frame:
            body.append({"kind": "lines", "lines": frame})
        frames = any(isinstance(n, ir.LocalFrame) for n in ir.walk(program.body))
        return {"s": s, "units": self.UNITS_WORD[s.units], "body": body, "frames": frames,
                "length": self.length(s.probe_length), "ball": self.length(s.ball_diameter),
                "posvel": self.feed(s.position_feed), "mesvel": self.feed(s.probe_feed)}

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
