"""How long the property-based tests run.

``make test`` loads the hypothesis profile ``ci`` (tests/conftest.py): derandomised (the
same commit always draws the same examples), no per-example deadline (a busy machine must
not fail a test), no example database.  ``make fuzz`` loads ``fuzz``: random draws and
``PROBEGEN_FUZZ_FACTOR`` (default 20 there) times as many examples per test.
"""

from __future__ import annotations

import os


def examples(n: int) -> int:
    """The number of examples a property test draws: ``n`` times the fuzz factor."""
    return n * max(1, int(os.environ.get("PROBEGEN_FUZZ_FACTOR", "1")))
