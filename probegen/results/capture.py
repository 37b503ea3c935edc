"""Capture a machine's DPRNT output over RS-232 into a raw log file.

Every chunk of bytes is written to the raw log, flushed and ``os.fsync``-ed the moment
it is read, before anything looks at it, so a parse failure, a dropped cable, a stopped
program or a Ctrl-C never costs data already received.  Parsing is a separate step
(:func:`probegen.results.read_dprnt`) that can be repeated on the raw file.

The capture stops on the first of:

* ``"end-marker"``: a ``PGEND Onnnn`` line went by (then the ``%`` PCLOS sends, or
  ``linger_s`` seconds, whichever comes first, so the trailer lands in the file too);
* ``"timeout"``: no byte for ``timeout_s`` seconds once data has started (or for
  ``start_timeout_s`` before the first byte, if given);
* ``"interrupted"``: ``stop_event`` was set or the user pressed Ctrl-C;
* ``"disconnected"``: the port failed mid-stream (USB adapter pulled, pty closed).

A raw log is never overwritten: by default the file must not exist; ``append=True``
adds to it (a resumed program then reads as a restart, see ``docs/dprnt-format.md``).
"""

from __future__ import annotations

import os
import re
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO, Literal

import serial

from probegen.errors import ProbegenError
from probegen.files import OutputError, output_folder

__all__ = [
    "DEFAULT_BAUDRATE",
    "CaptureReason",
    "CaptureResult",
    "Progress",
    "capture",
    "capture_from",
]

CaptureReason = Literal["end-marker", "timeout", "interrupted", "disconnected"]

Progress = Callable[[int, bytes], None]
"""Called after each chunk is safely on disk with (bytes so far, the chunk)."""

DEFAULT_BAUDRATE = 9600
"""Fanuc I/O channel settings are usually 4800 or 9600 baud, 7E2, ISO, XON/XOFF."""

POLL_S = 0.05
"""Longest blocking read: how quickly a stop request or a timeout is noticed."""

_END_MARKER = re.compile(rb"(?<![A-Za-z0-9])PGEND[ \t]*O[0-9]+[ \t]*[\r\n]", re.IGNORECASE)
_NOISE = b"\x00\x11\x12\x13\x14"
_TAIL = 64
"""Bytes of the stream kept between chunks so a marker split across reads is found."""


@dataclass(frozen=True, slots=True)
class CaptureResult:
    """How a capture went.

    Attributes:
        path: the raw log file.
        bytes: bytes received and written by this capture.
        reason: why it stopped: ``"end-marker"``, ``"timeout"``, ``"interrupted"`` or
            ``"disconnected"``.
        offset: size of the file before this capture (non-zero only when appending).
        elapsed_s: wall time of the capture, seconds.
        detail: the port's error message when disconnected, else ``""``.
    """

    path: Path
    bytes: int
    reason: CaptureReason
    offset: int = 0
    elapsed_s: float = 0.0
    detail: str = ""


class _EndMarker:
    """Find ``PGEND Onnnn`` and the ``%`` after it in a stream read in arbitrary chunks."""

    def __init__(self) -> None:
        self._tail = b""
        self.seen_at: float | None = None
        self.trailer = False

    def feed(self, chunk: bytes, now: float) -> None:
        """Scan the next chunk of the stream."""
        clean = chunk.translate(None, _NOISE)
        if self.seen_at is not None:
            self.trailer = self.trailer or b"%" in clean
            return
        buf = self._tail + clean
        match = _END_MARKER.search(buf)
        if match is None:
            self._tail = buf[-_TAIL:]
            return
        self.seen_at = now
        self.trailer = b"%" in buf[match.end() :]


@dataclass(slots=True)
class _Limits:
    timeout_s: float
    start_timeout_s: float | None
    linger_s: float


class _Recorder:
    """Append chunks to the raw log, durably, and watch for the end marker."""

    def __init__(self, f: BinaryIO, path: Path, progress: Progress | None) -> None:
        self.f = f
        self.path = path
        self.progress = progress
        self.count = 0
        self.marker = _EndMarker()

    def write(self, chunk: bytes, now: float) -> None:
        """Write, flush and fsync ``chunk``, then scan it and report progress."""
        try:
            self.f.write(chunk)
            self.f.flush()
            os.fsync(self.f.fileno())
        except OSError as exc:
            raise ProbegenError(f"cannot write raw log '{self.path}': {exc.strerror}") from exc
        self.count += len(chunk)
        self.marker.feed(chunk, now)
        if self.progress is not None:
            self.progress(self.count, chunk)


def _read_available(port: serial.SerialBase) -> bytes:
    """Return the bytes waiting, or wait up to the port timeout for one.

    One read per call: a read that fails half way loses what it had gathered, so the
    bytes of each call go to disk before the next read is tried.
    """
    waiting = port.in_waiting
    data: bytes = port.read(waiting if waiting else 1)
    return data


def _stop_reason(
    rec: _Recorder, limits: _Limits, start: float, last: float, now: float
) -> CaptureReason | None:
    """Return why to stop after a quiet poll, or None to keep reading."""
    seen_at = rec.marker.seen_at
    if seen_at is not None and (rec.marker.trailer or now - seen_at >= limits.linger_s):
        return "end-marker"
    if rec.count:
        return "timeout" if now - last >= limits.timeout_s else None
    if limits.start_timeout_s is not None and now - start >= limits.start_timeout_s:
        return "timeout"
    return None


def _pump(
    port: serial.SerialBase, rec: _Recorder, limits: _Limits, stop_event: threading.Event | None
) -> tuple[CaptureReason, str]:
    """Read until a stop condition; return the reason and a detail message."""
    start = last = time.monotonic()
    while True:
        if stop_event is not None and stop_event.is_set():
            return "interrupted", ""
        try:
            chunk = _read_available(port)
        except (serial.SerialException, OSError) as exc:
            return "disconnected", str(exc)
        now = time.monotonic()
        if chunk:
            rec.write(chunk, now)
            last = now
        reason = _stop_reason(rec, limits, start, last, now)
        if reason is not None:
            return reason, ""


def _open_log(path: Path, append: bool) -> BinaryIO:
    """Open the raw log for appending, or create it (and its folder); never truncate."""
    _refuse_folder(path)
    output_folder(path.parent, "the raw log")
    try:
        return open(path, "ab" if append else "xb")
    except FileExistsError:
        raise _exists_error(path) from None
    except OSError as exc:
        raise OutputError(f"{path}: cannot create the raw log: {exc.strerror}") from exc


def _port_problem(exc: Exception) -> str:
    """What opening a port found, in words: ``no such file or directory`` rather than
    pyserial's ``[Errno 2] could not open port X: [Errno 2] ...``."""
    code = exc.args[0] if exc.args and isinstance(exc.args[0], int) else None
    if code is not None:
        return os.strerror(code).lower()
    return str(exc)


def _refuse_folder(path: Path) -> None:
    """A folder where the raw log's file name is meant is an error (not "it exists")."""
    if path.is_dir():
        raise OutputError(f"{path}: expected a file name for the raw log, found a folder")


def _exists_error(path: Path) -> ProbegenError:
    return ProbegenError(
        f"raw log '{path}' already exists; a capture never overwrites one: "
        "choose a new file name, or append to it (capture --append, for a resumed program)"
    )


def capture_from(
    port: serial.SerialBase,
    out_path: str | os.PathLike[str],
    *,
    timeout_s: float = 60.0,
    start_timeout_s: float | None = None,
    linger_s: float = 0.5,
    stop_event: threading.Event | None = None,
    progress: Progress | None = None,
    append: bool = False,
) -> CaptureResult:
    """Capture from a port that is already open (a real port, ``loop://``, the simulator's).

    The port's ``timeout`` is set to :data:`POLL_S`; the port is left open.
    Arguments are those of :func:`capture`.

    Raises:
        ProbegenError: the log exists (and ``append`` is false) or cannot be written.
    """
    path = Path(out_path)
    if port.timeout != POLL_S:
        port.timeout = POLL_S
    limits = _Limits(timeout_s, start_timeout_s, linger_s)
    began = time.monotonic()
    with _open_log(path, append) as f:
        offset = f.tell()
        rec = _Recorder(f, path, progress)
        try:
            reason, detail = _pump(port, rec, limits, stop_event)
        except KeyboardInterrupt:
            reason, detail = "interrupted", "keyboard interrupt"
    elapsed = time.monotonic() - began
    return CaptureResult(path, rec.count, reason, offset, elapsed, detail)


def capture(
    port_url: str,
    out_path: str | os.PathLike[str],
    *,
    baudrate: int = DEFAULT_BAUDRATE,
    bytesize: int = serial.SEVENBITS,
    parity: str = serial.PARITY_EVEN,
    stopbits: float = serial.STOPBITS_TWO,
    xonxoff: bool = True,
    timeout_s: float = 60.0,
    start_timeout_s: float | None = None,
    linger_s: float = 0.5,
    stop_event: threading.Event | None = None,
    progress: Progress | None = None,
    append: bool = False,
) -> CaptureResult:
    """Record what the machine sends on ``port_url`` into the raw log ``out_path``.

    Args:
        port_url: a device (``/dev/ttyUSB0``, ``COM3``, a pty path) or a pyserial URL
            (``loop://``, ``rfc2217://host:port``, ``socket://host:port``).
        out_path: the raw log; created, or appended to with ``append``.
        baudrate: must match the control's I/O channel (usually 4800 or 9600).
        bytesize: data bits; Fanuc ISO output is 7.
        parity: ``"E"`` (even) for Fanuc ISO output.
        stopbits: 2 on most Fanuc settings.
        xonxoff: software flow control, as the control expects from a tape punch.
        timeout_s: stop after this many seconds without a byte, once data started.
        start_timeout_s: stop if nothing arrives this long after the start (None:
            wait until the program runs, a stop request or Ctrl-C).
        linger_s: after ``PGEND``, how long to wait for the ``%`` of PCLOS.
        stop_event: set it from another thread to stop the capture.
        progress: called with (bytes so far, chunk) after each chunk is on disk.
        append: append to an existing log instead of requiring a new file.

    Returns:
        The path, the byte count and why the capture stopped.

    Raises:
        ProbegenError: the log exists (and ``append`` is false), the port cannot be
            opened or the log cannot be written.
    """
    path = Path(out_path)
    _refuse_folder(path)
    if not append and path.exists():
        raise _exists_error(path)
    try:
        port = serial.serial_for_url(
            port_url,
            baudrate=baudrate,
            bytesize=bytesize,
            parity=parity,
            stopbits=stopbits,
            xonxoff=xonxoff,
            timeout=POLL_S,
        )
    except (serial.SerialException, ValueError) as exc:
        raise ProbegenError(f"cannot open serial port '{port_url}': expected a serial device "
                            f"or a pyserial URL, found {_port_problem(exc)}") from exc
    with port:
        return capture_from(
            port,
            path,
            timeout_s=timeout_s,
            start_timeout_s=start_timeout_s,
            linger_s=linger_s,
            stop_event=stop_event,
            progress=progress,
            append=append,
        )
