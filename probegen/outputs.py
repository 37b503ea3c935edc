"""Where the command line writes: one place for every output file and output folder.

The policy for existing outputs (README, "Output files"):

- an output file (program, results, report, QIF, calibration, readings, a simulated log) is
  overwritten: it is made again from its inputs;
- the raw capture log is never overwritten (:mod:`probegen.results.capture`): it is the
  only record of a measurement;
- an output is never written over one of the command's own input files (``probegen qif
  run.log -o run.log`` would destroy the log): :func:`protect_inputs`;
- an output folder is created with its parents; a file where a folder is meant, or a
  folder where a file is meant, is an error that names the path.

Every failure is an :class:`OutputError` saying which path, what was expected and what
was found, never an ``OSError`` traceback.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from probegen.cli_exit import ExitCode
from probegen.errors import ProbegenError

_PROTECTED: set[Path] = set()


class OutputError(ProbegenError):
    """An output file or folder cannot be written where it was asked for."""

    exit_code = ExitCode.OUTPUT  # 73, sysexits' EX_CANTCREAT


def protect_inputs(paths: Iterable[str | os.PathLike[str]]) -> None:
    """Refuse, from now on, to write an output over any of these existing files (the
    command's inputs); replaces the previous set."""
    _PROTECTED.clear()
    _PROTECTED.update(Path(p).resolve() for p in paths if Path(p).is_file())


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
               encoding: str = "utf-8") -> Path:
    """Write ``data`` (text with ``\\n`` line ends in ``encoding``, or bytes) to the output
    file ``path`` under the module's policy, creating its folder; return the path.

    Raises:
        OutputError: ``path`` is a folder or one of the command's inputs, its folder
            cannot be made, or the file cannot be written.
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
        with open(target, "wb") as handle:
            handle.write(raw)
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
