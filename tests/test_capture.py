"""Serial capture end to end: a thread plays the machine over a pty pair and loop://."""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import serial

from probegen.errors import ProbegenError
from probegen.results import CaptureResult, capture, capture_from, read_dprnt

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="needs POSIX pseudo-terminals")

LOG = (
    b"\x12%\n"
    b"PGSTART O1001 V1\n"
    b"LOC SPH1 1 X-12.3456 Y0.0000 Z5.0000\n"
    b"PT SPH1 1 X-  12.3456 Y    .0000 Z   5.0000\n"
    b"PT SPH1 2 X   12.3456 Y    .0000 Z   5.0000\n"
    b"PGEND O1001\n"
    b"%\x14"
)

# PGEND split mid-word and mid-number: the capture must not stop before the line ends.
CHUNKS = [LOG[:30], LOG[30:70], LOG[70:-20], LOG[-20:-12], LOG[-12:-8], LOG[-8:]]

QUICK: dict[str, Any] = {"timeout_s": 1.0, "start_timeout_s": 2.0, "linger_s": 0.3}


class Received:
    """Progress callback that lets the machine thread wait for the capture."""

    def __init__(self) -> None:
        self.count = 0
        self._cond = threading.Condition()

    def __call__(self, count: int, chunk: bytes) -> None:
        with self._cond:
            self.count = count
            self._cond.notify_all()

    def wait_for(self, count: int, timeout: float = 3.0) -> None:
        with self._cond:
            self._cond.wait_for(lambda: self.count >= count, timeout)


class Link:
    """One side plays the machine (``write``), the other is captured."""

    name = ""

    def wait_open(self) -> None:
        """Return once the capture side has opened the port."""

    def write(self, data: bytes) -> None:
        raise NotImplementedError

    def capture(self, path: Path, **kw: Any) -> CaptureResult:
        raise NotImplementedError


class PtyLink(Link):
    """A pseudo-terminal pair: the machine writes the master, capture opens the slave path."""

    name = "pty"

    def __init__(self) -> None:
        import tty

        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)

    def wait_open(self) -> None:
        """Wait until pyserial has configured the slave (xonxoff sets IXON; raw mode cleared it).

        pyserial discards pending input when it opens a port, as a real port would
        lose bytes sent before anyone listened; so the machine waits for the capture.
        """
        import termios

        deadline = time.monotonic() + 3.0
        while time.monotonic() < deadline:
            if termios.tcgetattr(self.slave)[0] & termios.IXON:
                break
            time.sleep(0.005)
        time.sleep(0.05)

    def write(self, data: bytes) -> None:
        os.write(self.master, data)

    def hang_up(self) -> None:
        master, self.master = self.master, -1
        os.close(master)

    def capture(self, path: Path, **kw: Any) -> CaptureResult:
        return capture(self.path, path, **kw)

    def close(self) -> None:
        fds, self.master, self.slave = (self.master, self.slave), -1, -1
        for fd in fds:
            if fd >= 0:
                os.close(fd)


class LoopLink(Link):
    """pyserial's loop:// port, shared by the machine thread and the capture."""

    name = "loop"

    def __init__(self) -> None:
        self.port = serial.serial_for_url("loop://", timeout=0.05)

    def write(self, data: bytes) -> None:
        self.port.write(data)

    def capture(self, path: Path, **kw: Any) -> CaptureResult:
        return capture_from(self.port, path, **kw)

    def close(self) -> None:
        self.port.close()


@pytest.fixture
def pty_link() -> Iterator[PtyLink]:
    link = PtyLink()
    yield link
    link.close()


@pytest.fixture(params=["pty", "loop"])
def link(request: pytest.FixtureRequest) -> Iterator[Link]:
    made: PtyLink | LoopLink = PtyLink() if request.param == "pty" else LoopLink()
    yield made
    made.close()


def play(
    link: Link, chunks: list[bytes], then: Callable[[], None] | None = None, pause: float = 0.08
) -> threading.Thread:
    """Start a thread that sends ``chunks`` with pauses (longer than a poll), then ``then``."""

    def run() -> None:
        link.wait_open()
        for chunk in chunks:
            link.write(chunk)
            time.sleep(pause)
        if then is not None:
            then()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread


def test_full_log_stops_at_end_marker(link: Link, tmp_path: Path) -> None:
    out = tmp_path / "run.log"
    machine = play(link, CHUNKS)
    result = link.capture(out, **QUICK)
    machine.join()
    assert result.reason == "end-marker"
    assert result.bytes == len(LOG) and result.offset == 0 and result.detail == ""
    assert out.read_bytes() == LOG
    log = read_dprnt(out, strict=True)
    assert log.complete and log.program == 1001
    assert [(t.kind, t.index, t.xyz) for t in log.touches] == [
        ("LOC", 1, (-12.3456, 0.0, 5.0)),
        ("PT", 1, (-12.3456, 0.0, 5.0)),
        ("PT", 2, (12.3456, 0.0, 5.0)),
    ]


def test_end_marker_without_pclos_trailer(link: Link, tmp_path: Path) -> None:
    out = tmp_path / "run.log"
    sent = LOG[: LOG.index(b"%\x14")]
    play(link, [sent])
    result = link.capture(out, **(QUICK | {"timeout_s": 5.0}))
    assert result.reason == "end-marker"  # after linger_s without the '%', not timeout_s
    assert out.read_bytes() == sent
    assert result.elapsed_s < 2.0


def test_writer_stops_sending_times_out(link: Link, tmp_path: Path) -> None:
    out = tmp_path / "run.log"
    sent = CHUNKS[:3]
    play(link, sent)
    result = link.capture(out, **(QUICK | {"timeout_s": 0.3}))
    assert result.reason == "timeout"
    assert out.read_bytes() == b"".join(sent)
    log = read_dprnt(out)
    assert not log.complete and len(log.touches) == 3


def test_garbage_is_kept_raw_and_diagnosed(link: Link, tmp_path: Path) -> None:
    out = tmp_path / "run.log"
    garbage = b"\xff\xfe\x07#!"
    if isinstance(link, LoopLink):  # a tty driver with IXON eats XON/XOFF itself
        garbage += b"\x11\x13"
    lines = LOG.split(b"\n")
    lines.insert(3, b"PT SPH1 9 X1." + garbage + b" Y2. Z3.")
    lines.insert(2, garbage)
    sent = b"\n".join(lines)
    play(link, [sent[:50], sent[50:]])
    result = link.capture(out, **QUICK)
    assert result.reason == "end-marker"
    assert out.read_bytes() == sent
    log = read_dprnt(out)
    assert [d.line for d in log.diagnostics] == [3, 5]
    assert log.diagnostics[0].message.startswith("expected a record (PGSTART")
    assert log.diagnostics[0].message.endswith(
        "found undecodable byte 0xFF "
        "(not 7-bit ASCII: check the port is set "
        "to 7 data bits, even parity)"
    )
    assert [t.index for t in log.touches] == [1, 1, 2]


def test_stop_event_interrupts(link: Link, tmp_path: Path) -> None:
    out = tmp_path / "run.log"
    stop = threading.Event()
    seen = Received()
    sent = CHUNKS[:2]

    def stop_after_delivery() -> None:
        seen.wait_for(len(b"".join(sent)))
        stop.set()

    machine = play(link, sent, then=stop_after_delivery)
    result = link.capture(out, stop_event=stop, progress=seen, timeout_s=5.0)
    machine.join()
    assert result.reason == "interrupted"
    assert out.read_bytes() == b"".join(sent)


def test_cable_pulled_mid_stream(pty_link: PtyLink, tmp_path: Path) -> None:
    out = tmp_path / "run.log"
    seen = Received()
    sent = CHUNKS[:3]

    def hang_up() -> None:
        seen.wait_for(len(b"".join(sent)))
        pty_link.hang_up()

    machine = play(pty_link, sent, then=hang_up)
    result = pty_link.capture(out, progress=seen, **QUICK)
    machine.join()
    assert result.reason in ("disconnected", "timeout")
    if result.reason == "disconnected":
        assert result.detail
    assert out.read_bytes() == b"".join(sent)
    assert len(read_dprnt(out).touches) == 3


def test_ctrl_c_returns_interrupted_with_data_on_disk(link: Link, tmp_path: Path) -> None:
    out = tmp_path / "run.log"

    def press_ctrl_c(count: int, chunk: bytes) -> None:
        raise KeyboardInterrupt

    play(link, [LOG])
    result = link.capture(out, progress=press_ctrl_c, **QUICK)
    assert result.reason == "interrupted"
    assert result.bytes > 0 and out.read_bytes() == LOG[: result.bytes]


def test_nothing_sent_start_timeout(tmp_path: Path) -> None:
    out = tmp_path / "run.log"
    result = capture("loop://", out, start_timeout_s=0.2, timeout_s=0.2)
    assert (result.reason, result.bytes) == ("timeout", 0)
    assert out.read_bytes() == b""


def test_never_overwrites_a_log(link: Link, tmp_path: Path) -> None:
    out = tmp_path / "run.log"
    out.write_bytes(b"earlier run\n")
    with pytest.raises(ProbegenError, match="already exists; a capture never overwrites"):
        link.capture(out, **QUICK)
    assert out.read_bytes() == b"earlier run\n"


def test_append_resumed_program(link: Link, tmp_path: Path) -> None:
    out = tmp_path / "run.log"
    first = LOG[: LOG.index(b"PT SPH1 2")]
    out.write_bytes(first)
    play(link, [LOG])
    result = link.capture(out, append=True, **QUICK)
    assert (result.reason, result.offset, result.bytes) == ("end-marker", len(first), len(LOG))
    assert out.read_bytes() == first + LOG
    log = read_dprnt(out, strict=True)
    assert log.restarts == 1 and log.complete
    assert [(t.index, t.run) for t in log.latest_touches() if t.kind == "PT"] == [(1, 1), (2, 1)]


def test_unknown_port_is_a_clear_error(tmp_path: Path) -> None:
    out = tmp_path / "run.log"
    with pytest.raises(ProbegenError, match="cannot open serial port '/nonexistent/ttyS9'"):
        capture("/nonexistent/ttyS9", out, **QUICK)
    assert not out.exists()


def test_unwritable_log_is_a_clear_error(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("a file where the log's folder is meant\n")
    with pytest.raises(ProbegenError, match="file: expected a folder for the raw log, found a "
                                            "file"):
        capture("loop://", tmp_path / "file" / "run.log", **QUICK)


def test_log_folder_is_created(tmp_path: Path) -> None:
    """Like every output folder, the raw log's is created (the log itself is never
    overwritten)."""
    out = tmp_path / "new-dir" / "run.log"
    capture("loop://", out, **QUICK)
    assert out.is_file()
