"""Play what the virtual machine sends over a pseudo-terminal, like a control's RS-232.

``PtyLink(link)`` opens a pty pair and points the symlink ``link`` at its slave device, so
``probegen capture --port LINK`` can open it with pyserial; ``play(data)`` then waits for
the reader to open the port (pyserial drops input that arrived before it opened) and
writes ``data`` in small chunks at roughly the given baud rate.
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from types import TracebackType

from probegen.errors import ProbegenError
from probegen.files import OutputError


class PtyLink:
    """A pseudo-terminal whose slave device is reachable at ``link``."""

    def __init__(self, link: str | Path) -> None:
        if not hasattr(os, "openpty"):
            raise ProbegenError("sim --pty: this platform has no pseudo-terminals")
        self.link = Path(link)
        if self.link.exists() and not self.link.is_symlink():
            raise OutputError(f"sim --pty {self.link}: expected a new name for the serial "
                                "port's link (or an old link), found an existing "
                                f"{'folder' if self.link.is_dir() else 'file'}")
        self.master, self.slave = os.openpty()
        try:
            if self.link.is_symlink():
                self.link.unlink()
            self.link.symlink_to(os.ttyname(self.slave))
        except OSError as exc:
            os.close(self.master)
            os.close(self.slave)
            raise OutputError(f"sim --pty {self.link}: cannot make the serial port's link "
                                f"there: {exc.strerror}") from None

    def play(self, data: bytes, *, delay: float = 1.0, baud: int = 9600, chunk: int = 64,
             linger: float = 0.5) -> None:
        """Wait ``delay`` s, send ``data`` at about ``baud``, wait ``linger`` s."""
        time.sleep(delay)
        pause = chunk * 10.0 / baud
        try:
            for k in range(0, len(data), chunk):
                os.write(self.master, data[k:k + chunk])
                time.sleep(pause)
        except OSError as exc:
            raise ProbegenError(f"sim --pty {self.link}: {exc.strerror}") from None
        time.sleep(linger)

    def close(self) -> None:
        """Close both ends and remove the link."""
        os.close(self.master)
        os.close(self.slave)
        if self.link.is_symlink():
            self.link.unlink()

    def __enter__(self) -> PtyLink:
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()
