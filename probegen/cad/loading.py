"""STEP loading: checks on the file, then OCCT's reader in a forked child process.

Owns :func:`load_step`: the file is checked (exists, not empty, STEP header and
terminator) before OCCT sees it; the reader runs in a child process where ``os.fork``
exists, so that a file that crashes OCCT ends in a :class:`~probegen.errors.ModelError`,
not a dead process; every reader status and entity check is turned into a clear
message.  The child sends back the shape as BRep bytes and the face records built by
:mod:`probegen.cad.faces`.

A colour or style entity that does not parse (an unset field in a surface-style record,
as Inventor and NX write them; a dangling style reference) does not refuse the file: the
reader transfers geometry only, so such an entity is ignored and named in a
:class:`~probegen.errors.ModelWarning` (``#id`` and STEP type).  Anything else that does
not parse is a :class:`~probegen.errors.ModelError`.
"""

from __future__ import annotations

import faulthandler
import io
import os
import pickle
import re
import signal
import traceback
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
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
from probegen.errors import ModelError, ModelWarning
from probegen.files import note_input

STEP_HEADER = "ISO-10303-21;"
STEP_TERMINATOR = "END-ISO-10303-21;"

_UNIT_ENTITY = re.compile(r"StepBasic_\w*Unit\w*")
_PRESENTATION = re.compile(r"StepVisual_(?!\w*(?:Tessellated|Triangulated|Coordinates))\w+")
"""OCCT's classes of colour, style, layer and annotation entities (presentation only:
the tessellated geometry OCCT also keeps in ``StepVisual`` is not among them)."""
_UNRESOLVED = re.compile(r"Unresolved Reference, Ent\.Id\.#(-?\d+)")
_MISSING = re.compile(r"\(Id\.#(\d+)\)")
_ENTITY_START = re.compile(rb"(?:^|;)\s*#(\d+)\s*=\s*(\(|[A-Za-z_][A-Za-z0-9_]*)", re.M)
WARNINGS_SHOWN = 5
"""At most this many ignored entities are warned of one by one; one more line counts
the rest (all of them are in :attr:`Model.warnings`)."""


# --------------------------------------------------------------------------- loading


def load_step(path: str | os.PathLike[str]) -> Model:
    """Read a STEP file into a :class:`Model` in millimetres.

    Where ``os.fork`` exists the OCCT reader runs in a child process: some corrupt
    files (a 2-D CARTESIAN_POINT used as a vertex) crash OCCT outright, and that must
    end in a :class:`ModelError`, not end the program.

    Args:
        path: the STEP file; messages quote it exactly as given.

    Returns:
        The model, one :class:`FaceRecord` per face, in a stable face order; each
        colour or style entity ignored is in ``warnings`` and is also issued as a
        :class:`~probegen.errors.ModelWarning`.

    Raises:
        ModelError: the file is missing, empty, not STEP, truncated, corrupt, crashes
            the reader, or holds no faces.
    """
    name = os.fspath(path)
    note_input(name)  # no output of the running command goes over the model
    _check_file(name)
    brep, records, ignored = _isolated(name)
    shape = TopoDS_Shape()
    BinTools.Read_s(shape, io.BytesIO(brep))
    faces = tuple(_unique_faces(shape))
    if len(faces) != len(records):
        raise RuntimeError(f"{name}: {len(records)} faces read, {len(faces)} after the copy")
    corners = np.array([(*r.bbox_min, *r.bbox_max) for r in records])
    lo, hi = _vec3(corners[:, :3].min(axis=0)), _vec3(corners[:, 3:].max(axis=0))
    _warn(ignored)
    return Model(name, records, lo, hi, Compound(shape), faces, ignored)


def _warn(ignored: tuple[str, ...]) -> None:
    """Issue the first :data:`WARNINGS_SHOWN` of ``ignored`` as warnings, then a count."""
    for text in ignored[:WARNINGS_SHOWN]:
        warnings.warn(ModelWarning(text), stacklevel=3)
    if len(ignored) > WARNINGS_SHOWN:
        first = ignored[0].split(": ", 1)[0]
        warnings.warn(ModelWarning(f"{first}: {len(ignored) - WARNINGS_SHOWN} more colour "
                                   "or style entities ignored likewise"), stacklevel=3)


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


_Loaded = tuple[bytes, tuple[FaceRecord, ...], tuple[str, ...]]


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
    """Read and transfer the model; return its BRep bytes, its face records and the
    warnings of the colour or style entities ignored."""
    shape, ignored = _read_shape(name)
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
    return brep.getvalue(), tuple(records), ignored


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


def _read_shape(name: str) -> tuple[TopoDS_Shape, tuple[str, ...]]:
    """Run OCCT's STEP reader and check every status it returns; the shape and the
    warnings of :func:`_check_parsed`."""
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
            ignored = _check_parsed(name, reader)
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
    return shape, ignored


def _check_parsed(name: str, reader: STEPControl_Reader) -> tuple[str, ...]:
    """Refuse syntax errors, dangling ``#`` references and ill-typed parameters; return
    a warning for each colour or style entity that fails (it is ignored).

    OCCT transfers such data regardless and crashes on the null reference left behind
    (seen with a deleted ORIENTED_EDGE and with ``(65)`` for ``(#65)``).  Failures on
    unit entities are let through: real files carry them (NIST CTC 2, 5 and FTC 9
    write ``*`` for derived unit dimensions) and the reader falls back safely.  Failures
    on presentation entities (:data:`_PRESENTATION`: colours, styles, layers), and a
    dangling reference from one, are warnings: the geometry reader never follows them
    (the Prusa MINI heatsink, written by Inventor, has a style with an unset rendering
    method).
    """
    model = reader.StepModel()
    failed = _entity_failures(reader)
    entities = _Entities.read(name, model.NbEntities()) if failed else None
    ignored: dict[str, tuple[str, str]] = {}  # "#id" -> ("#id (TYPE)", the failure)
    found: list[str] = []
    for number, kind, fail in failed:
        entity = _entity_name(entities, number, kind)
        if _PRESENTATION.fullmatch(kind):
            ignored[entity.split(" ", 1)[0]] = (entity, fail)
        else:
            found.append(f"DATA entity {entity}: {fail}")
    check = model.GlobalCheck()
    unresolved = []
    for fail in (" ".join(check.CFail(i).split()) for i in range(1, check.NbFails() + 1)):
        owners = _owners(fail, entities)
        if owners and owners <= ignored.keys():
            for owner in owners:  # the dangling #ref says more than OCCT's entity check
                ignored[owner] = (ignored[owner][0], fail)
        else:
            unresolved.append(fail)
    found[:0] = unresolved
    if found:
        raise ModelError(
            f"{name}: corrupt STEP data: expected every entity to parse, with every "
            "#reference resolved to an entity of the right type, found "
            f"{len(found)} error(s), the first: {found[0]}"
        )
    return tuple(f"{name}: STEP entity {entity} ignored: a colour or style record that does "
                 f"not parse ({fail}); the geometry does not depend on it"
                 for entity, fail in ignored.values())


def _entity_failures(reader: STEPControl_Reader) -> list[tuple[int, str, str]]:
    """The entities that fail OCCT's check, but units: the reader's number, OCCT class
    and first failure of each."""
    model = reader.StepModel()
    failed = []
    checks = reader.WS().ModelCheckList()
    checks.Start()
    while checks.More():
        number = checks.Number()  # 0 is the global check, read by the caller
        kind = model.Value(number).DynamicType().Name() if number > 0 else ""
        if number > 0 and checks.Value().NbFails() and not _UNIT_ENTITY.fullmatch(kind):
            failed.append((number, kind, " ".join(checks.Value().CFail(1).split())))
        checks.Next()
    return failed


@dataclass(frozen=True)
class _Entities:
    """The entity records of a file's DATA section in file order (OCCT numbers the
    entities so): each one's ``#id``, STEP type (``"(complex)"`` for a complex entity)
    and byte offset."""

    data: bytes
    ids: tuple[int, ...]
    types: tuple[str, ...]
    starts: tuple[int, ...]

    @classmethod
    def read(cls, name: str, count: int) -> _Entities | None:
        """The records of ``name``; None when their count differs from ``count`` (the
        reader's) and the reader's numbers cannot be matched to them."""
        text = Path(name).read_bytes()
        data = text[max(text.find(b"DATA;"), 0):]
        found = list(_ENTITY_START.finditer(data))
        if len(found) != count:
            return None
        return cls(data, tuple(int(m[1]) for m in found),
                   tuple("(complex)" if m[2] == b"(" else m[2].decode().upper() for m in found),
                   tuple(m.start(1) for m in found))

    def referring(self, ident: int) -> set[str]:
        """The ``#id`` of every entity whose record refers to ``#ident``."""
        pattern = re.compile(rb"#%d(?![0-9])(?!\s*=)" % ident)
        ends = (*self.starts[1:], len(self.data))
        return {f"#{i}" for i, a, b in zip(self.ids, self.starts, ends, strict=True)
                if pattern.search(self.data, a + 1, b)}


def _owners(fail: str, entities: _Entities | None) -> set[str]:
    """The ``#id`` of the entities an unresolved-reference failure is in: the one OCCT
    names, or (a reference inside a list, which OCCT numbers negatively) every entity
    that refers to the missing ``#id``; empty for any other failure."""
    source, missing = _UNRESOLVED.search(fail), _MISSING.search(fail)
    if source is None or missing is None or entities is None:
        return set()
    if not source[1].startswith("-"):
        return {f"#{source[1]}"}
    return entities.referring(int(missing[1]))


def _entity_name(entities: _Entities | None, number: int, kind: str) -> str:
    """``#id (TYPE)`` of the entity the reader numbers ``number``, or ``number (class)``
    when the file's numbering is unknown."""
    if entities is None:
        return f"{number} ({kind})"
    return f"#{entities.ids[number - 1]} ({entities.types[number - 1]})"


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

