"""STEP loading: checks on the file, then OCCT's reader in a forked child process.

Owns :func:`load_step`: the file is checked (exists, not empty, STEP header and
terminator) before OCCT sees it; the reader runs in a child process where ``os.fork``
exists, so that a file that crashes OCCT ends in a :class:`~probegen.errors.ModelError`,
not a dead process; every reader status and entity check is turned into a clear
message.  The child sends back the shape as BRep bytes and the face records built by
:mod:`probegen.cad.faces`.
"""

from __future__ import annotations

import faulthandler
import io
import os
import pickle
import re
import signal
import traceback
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import NoReturn, cast

import numpy as np
from build123d import Compound
from OCP.BinTools import BinTools
from OCP.IFSelect import IFSelect_ReturnStatus
from OCP.Message import Message
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_FACE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shape

from probegen.cad.faces import FaceRecord, Model, _record, _vec3
from probegen.errors import ModelError
from probegen.files import note_input

STEP_HEADER = "ISO-10303-21;"
STEP_TERMINATOR = "END-ISO-10303-21;"

_UNIT_ENTITY = re.compile(r"StepBasic_\w*Unit\w*")


# --------------------------------------------------------------------------- loading


def load_step(path: str | os.PathLike[str]) -> Model:
    """Read a STEP file into a :class:`Model` in millimetres.

    Where ``os.fork`` exists the OCCT reader runs in a child process: some corrupt
    files (a 2-D CARTESIAN_POINT used as a vertex) crash OCCT outright, and that must
    end in a :class:`ModelError`, not end the program.

    Args:
        path: the STEP file; messages quote it exactly as given.

    Returns:
        The model, one :class:`FaceRecord` per face, in a stable face order.

    Raises:
        ModelError: the file is missing, empty, not STEP, truncated, corrupt, crashes
            the reader, or holds no faces.
    """
    name = os.fspath(path)
    note_input(name)  # no output of the running command goes over the model
    _check_file(name)
    brep, records = _isolated(name)
    shape = TopoDS_Shape()
    BinTools.Read_s(shape, io.BytesIO(brep))
    faces = tuple(_unique_faces(shape))
    if len(faces) != len(records):
        raise RuntimeError(f"{name}: {len(records)} faces read, {len(faces)} after the copy")
    corners = np.array([(*r.bbox_min, *r.bbox_max) for r in records])
    lo, hi = _vec3(corners[:, :3].min(axis=0)), _vec3(corners[:, 3:].max(axis=0))
    return Model(name, records, lo, hi, Compound(shape), faces)


def _check_file(name: str) -> None:
    """Check existence, size, header and terminator of a STEP file before OCCT sees it."""
    file = Path(name)
    if not file.exists():
        raise ModelError(f"{name}: expected a STEP file, found no such file")
    if not file.is_file():
        raise ModelError(f"{name}: expected a STEP file, found "
                         f"{'a folder' if file.is_dir() else 'something else (not a file)'}")
    try:
        size = file.stat().st_size
        with file.open("rb") as stream:
            head = stream.read(256)
            stream.seek(max(size - 256, 0))
            tail = stream.read()
    except OSError as exc:
        raise ModelError(f"{name}: cannot read file ({exc.strerror})") from None
    if size == 0:
        raise ModelError(f"{name}: expected a STEP file, found an empty file (0 bytes)")
    first = head.removeprefix(b"\xef\xbb\xbf").lstrip().split(b"\n", 1)[0].strip()
    if not first.startswith(STEP_HEADER.encode()):
        raise ModelError(
            f"{name}: not a STEP file: expected '{STEP_HEADER}' on the first line, "
            f"found '{_show(first[:40])}'"
        )
    last = tail.rstrip(b" \t\r\n\x00\x1a")
    if not last.endswith(STEP_TERMINATOR.encode()):
        raise ModelError(
            f"{name}: truncated STEP file ({size} bytes): expected '{STEP_TERMINATOR}' "
            f"at the end, found '{_show(last[-40:])}'"
        )


def _show(raw: bytes) -> str:
    """Bytes as printable ASCII, anything else escaped as ``\\xNN``."""
    return "".join(ch if " " <= ch <= "~" else f"\\x{ord(ch):02x}" for ch in raw.decode("latin-1"))


_Loaded = tuple[bytes, tuple[FaceRecord, ...]]


def _isolated(name: str) -> _Loaded:
    """Run :func:`_load` in a forked child; a child killed by a signal is a ModelError."""
    if not hasattr(os, "fork"):
        return _load(name)
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child never returns and never runs the parent's exit handlers
        os.close(read_end)
        faulthandler.disable()  # a crash here is reported by the parent, not dumped
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.dup2(null, 2)
        try:
            reply: tuple[str, object] = ("ok", _load(name))
        except ModelError as exc:
            reply = ("error", str(exc))
        except BaseException:
            reply = ("bug", traceback.format_exc())
        with os.fdopen(write_end, "wb") as pipe:
            pickle.dump(reply, pipe)
        os._exit(0)
    os.close(write_end)
    with os.fdopen(read_end, "rb") as pipe:
        data = pipe.read()
    _, status = os.waitpid(pid, 0)
    if not data:
        how = signal.Signals(os.WTERMSIG(status)).name if os.WIFSIGNALED(status) else "exit"
        raise ModelError(
            f"{name}: the STEP reader crashed ({how}): expected STEP data OCCT can transfer,"
            " found data that kills it (check the file with a STEP validator)"
        )
    kind, value = pickle.loads(data)
    if kind == "error":
        raise ModelError(value)
    if kind == "bug":
        raise RuntimeError(f"loading {name} failed in the reader process:\n{value}")
    return cast(_Loaded, value)


def _load(name: str) -> _Loaded:
    """Read and transfer the model; return its BRep bytes and its face records."""
    shape = _read_shape(name)
    faces = _unique_faces(shape)
    if not faces:
        raise ModelError(f"{name}: empty shape: expected at least one face, found none")
    records = []
    for index, face in enumerate(faces, start=1):
        try:
            records.append(_record(index, face))
        except Exception as exc:
            _reraise_occt(f"{name}: face {index}", exc)
    brep = io.BytesIO()
    BinTools.Write_s(shape, brep)
    return brep.getvalue(), tuple(records)


def _reraise_occt(where: str, exc: Exception) -> NoReturn:
    """Turn an OCCT exception (geometry OCCT refuses) into a ModelError; re-raise others."""
    if isinstance(exc, ModelError):
        raise ModelError(f"{where}: {exc}") from None
    if not type(exc).__module__.startswith("OCP"):
        raise exc
    raise ModelError(
        f"{where}: OCCT raised {type(exc).__name__}: expected consistent STEP geometry, "
        f"found '{' '.join(str(exc).split())}'"
    ) from None


@contextmanager
def _quiet_occt() -> Iterator[None]:
    """Keep OCCT's reader chatter off stdout; the messages we raise say it better."""
    messenger = Message.DefaultMessenger_s()
    printers = list(messenger.Printers())
    for printer in printers:
        messenger.RemovePrinter(printer)
    try:
        yield
    finally:
        for printer in printers:
            messenger.AddPrinter(printer)


def _read_shape(name: str) -> TopoDS_Shape:
    """Run OCCT's STEP reader and check every status it returns."""
    reader = STEPControl_Reader()
    reader.SetSystemLengthUnit(1.0)  # OCCT scales lengths to this unit: 1.0 = mm
    try:
        with _quiet_occt():
            status = reader.ReadFile(name)
            if status != IFSelect_ReturnStatus.IFSelect_RetDone:
                raise ModelError(
                    f"{name}: the STEP reader failed ({status.name}): expected a readable "
                    "ISO-10303-21 exchange structure"
                )
            _check_parsed(name, reader)
            if (roots := reader.NbRootsForTransfer()) == 0:
                raise ModelError(
                    f"{name}: no shape to transfer: expected at least one product or shape "
                    f"representation, found none among {reader.StepModel().NbEntities()} "
                    "entities"
                )
            transferred = reader.TransferRoots()
            shape = reader.OneShape()
    except ModelError:
        raise
    except Exception as exc:
        _reraise_occt(name, exc)
    if transferred == 0 or shape.IsNull():
        raise ModelError(
            f"{name}: transfer failed: expected a shape from {roots} root entities, found none"
        )
    return shape


def _check_parsed(name: str, reader: STEPControl_Reader) -> None:
    """Refuse syntax errors, dangling ``#`` references and ill-typed parameters.

    OCCT transfers such data regardless and crashes on the null reference left behind
    (seen with a deleted ORIENTED_EDGE and with ``(65)`` for ``(#65)``).  Failures on
    unit entities are let through: real files carry them (NIST CTC 2, 5 and FTC 9
    write ``*`` for derived unit dimensions) and the reader falls back safely.
    """
    model = reader.StepModel()
    check = model.GlobalCheck()
    found = [" ".join(check.CFail(i).split()) for i in range(1, check.NbFails() + 1)]
    checks = reader.WS().ModelCheckList()
    checks.Start()
    while checks.More():
        number = checks.Number()  # 0 is the global check, already counted
        kind = model.Value(number).DynamicType().Name() if number > 0 else ""
        if number > 0 and checks.Value().NbFails() and not _UNIT_ENTITY.fullmatch(kind):
            found.append(f"DATA entity {number} ({kind}): {checks.Value().CFail(1)}")
        checks.Next()
    if found:
        raise ModelError(
            f"{name}: corrupt STEP data: expected every entity to parse, with every "
            "#reference resolved to an entity of the right type, found "
            f"{len(found)} error(s), the first: {found[0]}"
        )


def _unique_faces(shape: TopoDS_Shape) -> list[TopoDS_Face]:
    """Faces of ``shape`` in explorer order, each shared face once."""
    seen: dict[int, list[TopoDS_Shape]] = {}
    faces: list[TopoDS_Face] = []
    explorer = TopExp_Explorer(shape, TopAbs_FACE)
    while explorer.More():
        item = explorer.Current()
        same = seen.setdefault(hash(item), [])
        if not any(item.IsSame(other) for other in same):
            same.append(item)
            faces.append(TopoDS.Face(item))
        explorer.Next()
    return faces

