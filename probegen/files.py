"""The user's files: TOML inputs read strictly, outputs written under one policy.

Reading TOML: strict reading of TOML tables into typed values, with key paths in every error.

``Table`` wraps one TOML table: each ``get_*`` call names a key, checks its type and range,
and records it as known; ``done()`` then rejects any key nobody asked for, with a
"did you mean" for misspellings.  Every error is a ``SpecError`` naming the file, the key
path (``feature[0].retract``) and the value found.

Writing outputs: one place for every output file and output folder.

The policy for existing outputs (README, "Output files"):

- an output file (program, results, report, QIF, calibration, readings, a simulated log) is
  overwritten: it is made again from its inputs;
- the raw capture log is never overwritten (:mod:`probegen.results.capture`): it is the
  only record of a measurement;
- an output is never written over one of the command's own input files (``probegen qif
  run.log -o run.log`` would destroy the log): :func:`inputs_protected`;
- an output folder is created with its parents; a file where a folder is meant, or a
  folder where a file is meant, is an error that names the path.

Every failure is an :class:`OutputError` saying which path, what was expected and what
was found, never an ``OSError`` traceback.
"""

from __future__ import annotations

import contextlib
import difflib
import math
import os
import tomllib
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from probegen.errors import ExitCode, ProbegenError, SpecError, did_you_mean


def load_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file; a missing or malformed file is a ``SpecError``."""
    p = Path(path)
    note_input(p)
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise SpecError(f"{path}: expected a TOML file, found no such file") from None
    except IsADirectoryError:
        raise SpecError(f"{path}: expected a TOML file, found a folder") from None
    except OSError as exc:
        raise SpecError(f"{path}: expected a TOML file, cannot read it: {exc.strerror}") from None
    if data.lstrip().startswith(b"ISO-10303-21;"):
        raise SpecError(f"{path}: expected a TOML file, found a STEP model (a spec names its "
                        "model in [part] model)")
    try:
        return tomllib.loads(data.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise SpecError(f"{path}: expected UTF-8 text, found the byte 0x{data[exc.start]:02x} "
                        f"at offset {exc.start}") from None
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"{path}: not valid TOML: {exc}") from None


def _kind(value: Any) -> str:
    names = {bool: "boolean", int: "integer", float: "number", str: "string",
             list: "array", dict: "table"}
    return names.get(type(value), type(value).__name__)


class Table:
    """One TOML table being read; see the module docstring."""

    def __init__(self, data: Any, file: str, path: str) -> None:
        if not isinstance(data, dict):
            raise SpecError(f"{file}: {path}: expected a table, found {_kind(data)} {data!r}")
        self.data: dict[str, Any] = data
        self.file = file
        self.path = path
        self._known: set[str] = set()

    def where(self, key: str) -> str:
        """Return ``file: path.key`` for messages."""
        dotted = f"{self.path}.{key}" if self.path else key
        return f"{self.file}: {dotted}"

    def fail(self, key: str, expected: str) -> SpecError:
        """Build the error for a bad (or missing) value under ``key``."""
        found = repr(self.data[key]) if key in self.data else "nothing (the key is missing)"
        return SpecError(f"{self.where(key)}: expected {expected}, found {found}")

    def has(self, key: str) -> bool:
        """Whether ``key`` is present (marks it as known)."""
        self._known.add(key)
        return key in self.data

    def _raw(self, key: str, default: Any, required: bool) -> Any:
        self._known.add(key)
        if key not in self.data:
            if required:
                unknown = [k for k in self.data if k not in self._known]
                close = difflib.get_close_matches(key, unknown, n=1, cutoff=0.6)
                found = f"; found {close[0]!r} instead, misspelt?" if close else ""
                raise SpecError(f"{self.where(key)}: required key is missing{found}")
            return default
        return self.data[key]

    def get_any(self, key: str, default: Any = None) -> Any:
        """The raw value (the caller checks it), or ``default`` when absent."""
        return self._raw(key, default, False)

    def get_str(self, key: str, default: str | None = None, *, required: bool = False,
                choices: Sequence[str] | None = None) -> str | None:
        """A string, optionally one of ``choices``."""
        value = self._raw(key, default, required)
        if value is None or value is default:
            return value
        if not isinstance(value, str):
            raise self.fail(key, "a string")
        if choices is not None and value not in choices:
            hint = did_you_mean(value, choices)
            raise SpecError(f"{self.where(key)}: expected one of {', '.join(choices)}, "
                            f"found {value!r}{hint}")
        return value

    def get_float(self, key: str, default: float | None = None, *, required: bool = False,
                  minimum: float | None = None, positive: bool = False,
                  maximum: float | None = None) -> float | None:
        """A finite number (integers accepted), with optional bounds."""
        value = self._raw(key, default, required)
        if value is None or value is default:
            return value
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(key, "a number")
        if not math.isfinite(value):
            raise self.fail(key, "a finite number")
        if positive and value <= 0:
            raise self.fail(key, "a positive number")
        if minimum is not None and value < minimum:
            raise self.fail(key, f"a number >= {minimum:g}")
        if maximum is not None and value > maximum:
            raise self.fail(key, f"a number <= {maximum:g}")
        return float(value)

    def get_int(self, key: str, default: int | None = None, *, required: bool = False,
                minimum: int | None = None, maximum: int | None = None) -> int | None:
        """An integer with optional bounds."""
        value = self._raw(key, default, required)
        if value is None or value is default:
            return value
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(key, "an integer")
        if minimum is not None and value < minimum:
            raise self.fail(key, f"an integer >= {minimum}")
        if maximum is not None and value > maximum:
            raise self.fail(key, f"an integer <= {maximum}")
        return value

    def get_bool(self, key: str, default: bool) -> bool:
        """A boolean."""
        value = self._raw(key, default, False)
        if not isinstance(value, bool):
            raise self.fail(key, "true or false")
        return value

    def get_vec(self, key: str, n: int = 3) -> tuple[float, ...] | None:
        """An array of ``n`` finite numbers, or None when absent."""
        value = self._raw(key, None, False)
        if value is None:
            return None
        ok = isinstance(value, list) and len(value) == n and all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            for v in value
        )
        if not ok:
            raise self.fail(key, f"an array of {n} numbers")
        return tuple(float(v) for v in value)

    def get_limits(self, key: str, scale: float = 1.0, unit: str = ""
                   ) -> tuple[float, float] | None:
        """``[lower, upper]`` deviations (lower <= upper) times ``scale``, or None when
        absent; ``unit`` (e.g. ``" in degrees"``) goes into the message."""
        value = self.get_vec(key, 2)
        if value is None:
            return None
        lo, hi = value
        if lo > hi:
            raise self.fail(key, f"[lower, upper] deviations{unit} with lower <= upper")
        return (lo * scale, hi * scale)

    def get_str_list(self, key: str, default: Sequence[str] = ()) -> tuple[str, ...]:
        """An array of strings."""
        value = self._raw(key, list(default), False)
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise self.fail(key, "an array of strings")
        return tuple(value)

    def table(self, key: str, *, required: bool = False) -> Table:
        """A sub-table (an empty one when absent and not required)."""
        value = self._raw(key, {}, required)
        return Table(value, self.file, f"{self.path}.{key}" if self.path else key)

    def tables(self, key: str) -> list[Table]:
        """An array of tables (``[[key]]``)."""
        value = self._raw(key, [], False)
        if not isinstance(value, list):
            raise self.fail(key, "an array of tables ([[" + key + "]])")
        prefix = f"{self.path}.{key}" if self.path else key
        return [Table(v, self.file, f"{prefix}[{i}]") for i, v in enumerate(value)]

    def done(self) -> None:
        """Reject keys that no ``get_*`` asked for."""
        for key in self.data:
            if key not in self._known:
                hint = did_you_mean(key, self._known)
                raise SpecError(f"{self.where(key)}: unknown key{hint}")


_PROTECTED: set[Path] = set()
"""The running command's input files (resolved); empty outside a command."""
_GUARDING = False
"""Whether a command is running (:func:`inputs_protected`): only then are inputs noted."""


class OutputError(ProbegenError):
    """An output file or folder cannot be written where it was asked for."""

    exit_code = ExitCode.OUTPUT  # 73, sysexits' EX_CANTCREAT


@contextlib.contextmanager
def inputs_protected(paths: Iterable[str | os.PathLike[str]]) -> Iterator[None]:
    """While a command runs: refuse to write an output over any of these existing files
    (the command's inputs on its line) or over any file it reads meanwhile
    (:func:`note_input`: the model, profile or calibration a spec names)."""
    global _GUARDING
    _PROTECTED.clear()
    _PROTECTED.update(Path(p).resolve() for p in paths if Path(p).is_file())
    _GUARDING = True
    try:
        yield
    finally:
        _GUARDING = False
        _PROTECTED.clear()


def note_input(path: str | os.PathLike[str]) -> None:
    """Record that the running command reads the file ``path``, so that no output of the
    command goes over it; outside a command (library use) nothing is recorded."""
    if _GUARDING and Path(path).is_file():
        _PROTECTED.add(Path(path).resolve())


@contextlib.contextmanager
def updating(path: str | os.PathLike[str]) -> Iterator[None]:
    """Read the output file ``path`` to update it (a calibration file taking another
    stylus's entry): what is read meanwhile from it is not noted as an input, so the
    command may write it; a file already protected (on the command's line, or read as
    an input before) stays protected."""
    key = Path(path).resolve()
    was = key in _PROTECTED
    try:
        yield
    finally:
        if not was:
            _PROTECTED.discard(key)


def output_folder(path: str | os.PathLike[str], what: str) -> Path:
    """Make sure ``path`` is a folder ``what`` can be written into (created with its
    parents); return it.

    Raises:
        OutputError: ``path`` or one of its parents is a file, or the folder cannot be
            created (permission, read-only file system, /proc, ...).
    """
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"{folder}: expected a folder for {what}, found a file")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        blocker = next((p for p in folder.parents if p.exists() and not p.is_dir()), folder)
        raise OutputError(f"{folder}: expected a folder for {what}, found that "
                          f"{blocker} is a file") from None
    except OSError as exc:
        raise OutputError(f"{folder}: expected a folder for {what}, "
                          f"cannot create it: {_reason(exc, folder)}") from None
    return folder


def write_file(path: str | os.PathLike[str], data: str | bytes, what: str, *,
               encoding: str = "utf-8", new: bool = False) -> Path:
    """Write ``data`` (text with ``\\n`` line ends in ``encoding``, or bytes) to the output
    file ``path`` under the module's policy, creating its folder; return the path.
    ``new``: the file must not exist yet (a file the user edits, such as the spec
    ``probegen init`` writes, is never overwritten).

    Raises:
        OutputError: ``path`` is a folder or one of the command's inputs, its folder
            cannot be made, it exists and ``new`` is set, or the file cannot be written.
    """
    target = Path(path)
    if target.is_dir():
        raise OutputError(f"{target}: expected a file name for {what}, found a folder")
    if target.resolve() in _PROTECTED:
        raise OutputError(f"{target}: expected a new file for {what}, found one of this "
                          "command's inputs (it is never overwritten); choose another -o")
    output_folder(target.parent, what)
    raw = data if isinstance(data, bytes) else data.encode(encoding)
    try:
        with open(target, "xb" if new else "wb") as handle:
            handle.write(raw)
    except FileExistsError:
        raise OutputError(f"{target}: expected a new file for {what}, found an existing "
                          "file (it is never overwritten: it may hold your edits); choose "
                          "another -o or move it away") from None
    except OSError as exc:
        raise OutputError(f"{target}: cannot write {what}: {_reason(exc, target)}") from None
    return target


def read_input(path: str | os.PathLike[str], what: str,
               error: type[ProbegenError] = ProbegenError, *, encoding: str = "utf-8") -> str:
    """The text of the input file ``path`` in ``encoding`` (undecodable bytes replaced; the
    reader of the text names what it cannot parse).

    Raises:
        ``error``: the file is missing, is a folder or cannot be read.
    """
    source = Path(path)
    note_input(source)
    if source.is_dir():
        raise error(f"{source}: expected {what}, found a folder")
    try:
        return source.read_text(encoding=encoding, errors="replace")
    except OSError as exc:
        raise error(f"{source}: expected {what}, cannot read it: {_reason(exc)}") from None


def _reason(exc: OSError, path: Path | None = None) -> str:
    """``exc``'s reason in words (``strerror``, lower-case like the rest of a message); "no
    such file" for a path whose folder exists means the folder takes no new entries."""
    if isinstance(exc, FileNotFoundError) and path is not None and path.parent.is_dir():
        return f"{path.parent} does not accept new files or folders (a virtual file system?)"
    text = exc.strerror or str(exc)
    return text[:1].lower() + text[1:]
