"""DPRNT number formatting, as a Fanuc control prints ``#n[ab]``.

``a`` integer digits and ``b`` fraction digits (``a + b`` from 1 to 8):

* the value is rounded half away from zero to ``b`` fraction digits;
* a decimal point and ``b`` digits follow the integer part when ``b > 0``; with
  ``b = 0`` no point is printed;
* only the lowest ``a`` digits of the integer part are printed: a value too large
  for its field loses its high digits (``#1[20]`` of 123.456 prints ``23``), as in the
  Fanuc manual's example;
* a minus sign precedes negative values, positive values get no sign, and a value
  that rounds to zero never prints ``-``;
* leading zeros are suppressed (parameter PRT = 1, the default here): 0.5 prints
  ``.500`` with ``[53]`` and 0 prints ``.000``; an integer field that would print
  nothing prints ``0``.  With ``blanks`` (PRT = 0) they print as blanks instead, the
  sign standing just before the first digit: ``[53]`` of -0.5 prints ``     -.500``.
* a vacant variable prints as 0.
"""

from __future__ import annotations

from decimal import ROUND_HALF_UP, Context, Decimal

_CONTEXT = Context(prec=80)
"""Enough digits for any value the control holds (below 1e47) with 8 fraction digits."""


def format_value(value: float | None, digits: int, decimals: int, *, blanks: bool = False) -> str:
    """Return ``value`` as DPRNT prints it with the format ``[digits decimals]``."""
    exact = Decimal(repr(float(value or 0.0)))
    number = exact.quantize(Decimal(1).scaleb(-decimals), ROUND_HALF_UP, _CONTEXT)
    negative = number < 0
    whole, _, fraction = f"{abs(number):f}".partition(".")
    whole = whole[-digits:].lstrip("0") if digits else ""
    if not decimals and not whole:
        whole = "0"
    if negative and not (whole.strip("0") or fraction.strip("0")):
        negative = False
    sign = "-" if negative else ""
    head = (sign + whole).rjust(digits + 1) if blanks else sign + whole
    return f"{head}.{fraction}" if decimals else head
