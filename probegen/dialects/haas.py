"""Haas (classic and Next Generation Control): Fanuc Macro B with a few differences.

A Haas mill runs the Fanuc dialect's program text as it is: ``G31`` with the skip
position in ``#5061-#5063``, ``IF [...] GOTO``, ``#3000`` alarms, ``POPEN``/``DPRNT``/
``PCLOS``, ``G43 H``.  This class overrides only what differs for our programs; each
override names the Haas fact behind it (``docs/dialects.md`` says which were checked
against a published copy of the Haas manual and which are from its G-code list as we
know it: G100, G15).
"""

from __future__ import annotations

from typing import Any, ClassVar

from probegen import ir
from probegen.dialects.fanuc import Fanuc
from probegen.errors import UnsupportedError
from probegen.ir.actions import describe


class Haas(Fanuc):
    """Haas mill G-code (Fanuc Macro B compatible)."""

    NAME: ClassVar[str] = "haas"
    EXTENSION: ClassVar[str] = ".haas.nc"
    """Haas reads ``.nc`` files; the inner suffix keeps them apart from Fanuc output."""
    TEMPLATES: ClassVar[str] = "fanuc"
    """The program text is Fanuc Macro B: the templates are Fanuc's."""
    EXTENDED_OFFSET: ClassVar[str] = "G154"
    """Haas mill G-code list: G154 P1-P99 selects the additional work offsets (Fanuc's
    G54.1 Pn, the same variables #7001-/#14001-, written with G10 L20 Pn)."""
    RESET_CODES: ClassVar[dict[str, str | None]] = {"G15": None, "G50.1": "G100"}
    """Haas mill G-code list: no polar-coordinate mode (G15/G16), and mirror image is
    cancelled with G100 (G101 sets it), not G50.1."""
    RESERVED_VARIABLES: ClassVar[tuple[tuple[int, int, str], ...]] = (
        (550, 599, "probe calibration data"), (700, 749, "hidden, for internal use"))
    """Haas macro variable table: ranges a program must not write (calibration of the
    WIPS probe; #709 is the fixture-clamp input).  #150-#199 hold probe results when a
    probe is installed: writing them only overwrites the last results."""

    TILT_REFUSAL: ClassVar[str] = (
        "probegen writes no Haas tilted plane yet: the Haas manual pages at hand state "
        "G254 DWO (whose coordinates are those of the turned part along the machine axes, "
        "which need the machine's rotary kinematics) but not the angle convention of "
        "G268 I J K Q, and a wrong convention turns the frame the wrong way; measure this "
        "feature in a setup of its own ([[setup]]), or post with -d fanuc if the control "
        "runs G68.2/G53.1")
    """Why a tilted ``ir.Orient`` is refused (``docs/dialects.md``: what was checked)."""

    # ALARM_TEXT_LENGTH: Fanuc's 26 characters, inherited: not checked against a Haas
    # manual; a message that short shows whole on any Macro B control.

    RADIUS_WEAR_FACTOR: ClassVar[float] = 2.0
    """Haas G10 L12/L13 write the tool *diameter* geometry/wear (with Setting 40, Tool
    Offset Measure, at its default Diameter): a radius correction is doubled."""

    def lower(self, program: ir.Program) -> dict[str, Any]:
        self.check_variables(program.setup.variable_base)
        for node in program.body:
            self.check_action_variable(node)
        context = super().lower(program)
        context["reset_codes"] = self.reset_codes(context["reset_codes"])
        return context

    def reset_codes(self, codes: tuple[str, ...]) -> tuple[str, ...]:
        """The profile's reset codes in Haas words (see ``RESET_CODES``)."""
        words = (self.RESET_CODES.get(code, code) for code in codes)
        return tuple(word for word in words if word is not None)

    def check_action_variable(self, node: ir.Node) -> None:
        """Refuse a flag or angle variable Haas reserves (``RESERVED_VARIABLES``).

        Raises:
            UnsupportedError: ``flag`` or ``align.variable`` is reserved.
        """
        if not isinstance(node, ir.Check | ir.Align):
            return
        number = node.flag if isinstance(node, ir.Check) else node.variable
        for first, last, what in self.RESERVED_VARIABLES:
            if number is not None and first <= number <= last:
                raise UnsupportedError(
                    f"dialect {self.NAME!r} cannot write #{number} ({describe(node)}): Haas "
                    f"keeps #{first}-#{last} for {what}")

    def check_variables(self, base: int) -> None:
        """Refuse a variable range that overlaps one Haas reserves.

        Raises:
            UnsupportedError: the range ``#base`` to :meth:`last_variable` meets
                ``RESERVED_VARIABLES``.
        """
        last = self.last_variable(base)
        for first_reserved, last_reserved, what in self.RESERVED_VARIABLES:
            if base <= last_reserved and first_reserved <= last:
                raise UnsupportedError(
                    f"dialect {self.NAME!r} cannot use variables #{base}-#{last}: Haas keeps "
                    f"#{first_reserved}-#{last_reserved} for {what}; set [controller] "
                    f"variable_base to 100, 600 or 800")
