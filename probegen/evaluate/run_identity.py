"""Which run a set of results belongs to: part, serial, operator, machine, program, time.

A run's identity is what a customer's inspection report and an SPC system ask for beside
the numbers.  It is gathered from four places, the first that has a value winning:

* the options of ``probegen ingest`` (:class:`IdentityOptions`: ``--part-number``,
  ``--serial``, ``--operator``, ``--time``, ``--batch``);
* the log: the serial a ``PGSERIAL`` line printed (``docs/dprnt-format.md``), the program
  number and identity token its ``PGSTART`` printed;
* the spec (``[part] number``, ``name``) and its machine profile (``[machine] name``);
* the log file's modification time (in UTC) for the time: never the clock, so the same
  files give the same outputs.

The program is not planned again here: the identity token is the one the log printed
(for a DMIS output, which prints none, the spec's program number alone).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from probegen.errors import ProbegenError


@dataclass(frozen=True, slots=True)
class RunIdentity:
    """The identity of one measured run.

    Attributes:
        part_number: the part number, or None when neither the spec nor ``--part-number``
            gives one.
        part_name: the part's name (the spec's ``[part] name``), or None.
        serial: the part's serial number (``--serial``, else the log's ``PGSERIAL``), or
            None.
        operator: who ran the measurement (``--operator``), or None.
        machine: the machine profile's name, or None.
        program: the program as the log printed it, ``O1001 H2DAFDB55`` (number and
            identity token; the number alone where the log printed no token).
        time: when the part was measured, ISO 8601 with its UTC offset, to the second
            (``2026-11-26T13:48:53+00:00``).
        batch: the batch or subgroup the part belongs to (``--batch``), or None.
        calibration: the fingerprint of the probe calibration the results were
            compensated with (``C61E692BB``), or None for the nominal ball radius.
    """

    part_number: str | None
    part_name: str | None
    serial: str | None
    operator: str | None
    machine: str | None
    program: str
    time: str
    batch: str | None = None
    calibration: str | None = None

    def to_json(self) -> dict[str, Any]:
        """The ``run`` block of ``results.json`` (``docs/results.md``)."""
        return {"part_number": self.part_number, "part_name": self.part_name,
                "serial": self.serial, "operator": self.operator, "machine": self.machine,
                "program": self.program, "time": self.time, "batch": self.batch,
                "calibration": self.calibration}

    @classmethod
    def from_json(cls, doc: dict[str, Any]) -> RunIdentity:
        """Read back :meth:`to_json`'s block (missing keys are None)."""
        def text(key: str) -> str | None:
            value = doc.get(key)
            return None if value is None else str(value)

        return cls(text("part_number"), text("part_name"), text("serial"), text("operator"),
                   text("machine"), text("program") or "", text("time") or "",
                   text("batch"), text("calibration"))


@dataclass(frozen=True, slots=True)
class IdentityOptions:
    """What the command line says about a run; None: take it from the log, spec or file.

    Attributes:
        part_number: overrides the spec's ``[part] number``.
        serial: overrides the log's ``PGSERIAL``.
        operator: who measured.
        time: ISO 8601 with a UTC offset (``2026-11-26T13:48:53+01:00``, ``...Z``);
            overrides the log file's modification time.
        batch: the batch or subgroup.
    """

    part_number: str | None = None
    serial: str | None = None
    operator: str | None = None
    time: str | None = None
    batch: str | None = None


def iso_time(text: str, where: str = "--time") -> str:
    """``text`` as ISO 8601 with its UTC offset, to the second.

    Raises:
        ProbegenError: not an ISO 8601 date and time, or one without a UTC offset (a
            local time without its offset names no instant).
    """
    try:
        when = datetime.fromisoformat(text.strip())
    except ValueError:
        raise ProbegenError(f"{where}: expected an ISO 8601 date and time with its UTC "
                            f"offset (2026-11-26T13:48:53+01:00), found {text!r}") from None
    if when.tzinfo is None:
        raise ProbegenError(f"{where}: expected a UTC offset (+01:00, Z) after the time, "
                            f"found {text!r} without one")
    return when.isoformat(timespec="seconds")


def file_time(path: str | os.PathLike[str]) -> str:
    """The modification time of ``path`` in UTC, ISO 8601, to the second.

    Raises:
        ProbegenError: the file cannot be read.
    """
    try:
        stamp = os.stat(path).st_mtime
    except OSError as exc:
        raise ProbegenError(f"cannot read the time of '{os.fspath(path)}': "
                            f"{exc.strerror}") from exc
    return datetime.fromtimestamp(int(stamp), UTC).isoformat(timespec="seconds")


def program_label(number: int | None, token: str | None) -> str:
    """``O1001 H2DAFDB55``: the program number and identity token (either may be absent)."""
    return " ".join(p for p in (None if number is None else f"O{number}", token) if p)


def _clean(value: str | None, what: str) -> str | None:
    """An option's text, blanks at either end removed; None when absent or empty.

    Raises:
        ProbegenError: the text holds a line break or a control character.
    """
    if value is None or not value.strip():
        return None
    if not value.isprintable():
        raise ProbegenError(f"{what}: expected printable text on one line, found {value!r}")
    return value.strip()


def run_identity(*, source: str, options: IdentityOptions, part_number: str | None,
                 part_name: str | None, machine: str | None, program: str,
                 log_serial: str | None, calibration: str | None) -> RunIdentity:
    """Gather a run's identity (the module docstring says from where).

    Args:
        source: the log or DMIS output file (its modification time is the default time).
        options: the command line's values.
        part_number: the spec's ``[part] number``.
        part_name: the spec's ``[part] name``.
        machine: the machine profile's name.
        program: :func:`program_label` of what the log printed.
        log_serial: the serial the log printed (``PGSERIAL``), or None.
        calibration: the fingerprint of the calibration used, or None.

    Raises:
        ProbegenError: a bad ``--time`` or option text, or the log's time cannot be read.
    """
    time = iso_time(options.time) if options.time else file_time(source)
    return RunIdentity(
        part_number=_clean(options.part_number, "--part-number") or part_number,
        part_name=part_name,
        serial=_clean(options.serial, "--serial") or log_serial,
        operator=_clean(options.operator, "--operator"),
        machine=machine or None,
        program=program,
        time=time,
        batch=_clean(options.batch, "--batch"),
        calibration=calibration,
    )
