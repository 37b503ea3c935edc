"""The one tolerance object and unit facts.

Numbers that decide geometry live here, with their reasoning, instead of as magic numbers
scattered through the code.
"""

from __future__ import annotations

from dataclasses import dataclass

MM_PER_INCH = 25.4


@dataclass(frozen=True, slots=True)
class Tolerances:
    """Geometric tolerances in millimetres / radians.

    Attributes:
        zero: lengths below this are zero (well below any controller increment, 1e-4 mm).
        angle: angles below this (rad) are zero; 1e-9 rad moves a point 1e-7 mm at 100 mm.
        merge: points closer than this are the same point.
        fit: convergence of iterative least-squares fits (step size, mm).
        ring: polar angles closer than this (rad) belong to one ring of a sphere layout.
        skip_check: a G31 end point and its skip position closer than this (mm) mean the
            skip signal did not fire; one least input increment of an IS-B control.
    """

    zero: float = 1e-9
    angle: float = 1e-9
    merge: float = 1e-8
    fit: float = 1e-10
    ring: float = 1e-6
    skip_check: float = 0.001


tol = Tolerances()
