"""Progress bars on standard error, for anything that can take more than a second.

A bar draws only when it is enabled (the CLI's ``--quiet`` turns it off) and standard
error is a terminal, so logs, pipes and CI output never get carriage-return noise.  The
library code reports progress through plain callables (``Callable[[int], None]``), so it
never depends on this module's state.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

ENABLED = True
"""Process-wide switch; the CLI sets it from ``--quiet``."""


class Bar:
    """A text progress bar: ``label [#####.....] 45/100``, redrawn at most 10 times a second.

    Args:
        label: what is progressing.
        total: the number of steps, or None when unknown (a counter is shown instead).
        unit: what a step is (``touches``, ``bytes``, ...).
        stream: where to draw (standard error by default).
    """

    WIDTH = 30

    def __init__(self, label: str, total: int | None = None, *, unit: str = "",
                 stream: TextIO | None = None) -> None:
        self.label = label
        self.total = total
        self.unit = unit
        self.stream = stream if stream is not None else sys.stderr
        self.count = 0
        self._last = 0.0
        self.active = ENABLED and self.stream.isatty()

    def __call__(self, step: int = 1) -> None:
        """Advance by ``step`` and redraw when due."""
        self.count += step
        now = time.monotonic()
        if self.active and now - self._last >= 0.1:
            self._last = now
            self._draw()

    def _draw(self) -> None:
        if self.total:
            done = min(self.count / self.total, 1.0)
            fill = int(done * self.WIDTH)
            bar = "#" * fill + "." * (self.WIDTH - fill)
            text = f"\r{self.label} [{bar}] {self.count}/{self.total} {self.unit}"
        else:
            text = f"\r{self.label} {self.count} {self.unit}"
        self.stream.write(text)
        self.stream.flush()

    def close(self) -> None:
        """Draw the final state and end the line."""
        if self.active:
            self._draw()
            self.stream.write("\n")
            self.stream.flush()

    def __enter__(self) -> Bar:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
