"""Statistical process control on the history of a characteristic: capability and control charts.

Numpy only, no other probegen room: :mod:`probegen.spc.series` is the record the store
hands over, :mod:`~probegen.spc.capability` the ISO 22514-2 indices,
:mod:`~probegen.spc.control` the I-MR and X̄-R charts with their run rules,
:mod:`~probegen.spc.table` the table as CSV and text.  See ``docs/spc.md``.
"""

from __future__ import annotations

from probegen.spc.capability import Capability, capability
from probegen.spc.control import ControlChart, Signal, control_chart
from probegen.spc.series import Series, Value
from probegen.spc.table import Row, spc_csv, spc_rows, spc_table

__all__ = ["Capability", "ControlChart", "Row", "Series", "Signal", "Value", "capability",
           "control_chart", "spc_csv", "spc_rows", "spc_table"]
