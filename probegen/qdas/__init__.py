"""Q-DAS AQDEF (.dfq): the exchange format SPC systems import; writer and reader; and the
CSV export of the same history (docs/exports.md)."""

from probegen.qdas.dfq import DFQ_ENCODING, to_dfq
from probegen.qdas.reader import Dfq, decode_dfq, dfq_series, read_dfq
from probegen.qdas.table import to_csv

__all__ = ["DFQ_ENCODING", "Dfq", "decode_dfq", "dfq_series", "read_dfq", "to_csv",
           "to_dfq"]
