"""The part: a STEP model loaded once, with everything derived from it built once.

Owns :class:`Part` and :func:`load_part`.  A command (or a public entry such as
``planning.plan_program``) loads the part once and hands the object down to planning,
the collision check, post and the virtual machine; each of them asks the part for what
it needs (face records, a mesh at a chordal tolerance, exact face queries) and the part
builds it on first use and keeps it.  Values only one consumer needs (planning's
collision obstacle, its plans, the recognised revolved features) are kept with
:meth:`Part.memo`, so that no module keeps a cache of its own: what is derived from a part
lives and dies with the part.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, TypeVar, cast

import trimesh

from probegen.cad.exact import ExactFaces
from probegen.cad.faces import FaceRecord, Model, Vec3
from probegen.cad.loading import load_step
from probegen.cad.mesh import CHORDAL_TOLERANCE, tessellate

T = TypeVar("T")


@dataclass(frozen=True, eq=False)
class Part:
    """A loaded part model and what is derived from it, each built once on first use.

    Build it with :func:`load_part` (or ``Part(model)`` around a model already loaded).
    Equality and hashing are by identity: two loads of one file are two parts.

    Attributes:
        model: the loaded model (face records and the private shape handle).
    """

    model: Model
    _memo: dict[Hashable, Any] = field(default_factory=dict, init=False, repr=False)

    @property
    def path(self) -> str:
        """The file path as the caller gave it (quoted in messages)."""
        return self.model.path

    @property
    def faces(self) -> tuple[FaceRecord, ...]:
        """The face records, ``faces[i].id == i + 1``."""
        return self.model.faces

    @property
    def bbox_min(self) -> Vec3:
        """Lower corner of the box around the faces, mm."""
        return self.model.bbox_min

    @property
    def bbox_max(self) -> Vec3:
        """Upper corner of the box around the faces, mm."""
        return self.model.bbox_max

    @property
    def warnings(self) -> tuple[str, ...]:
        """What was ignored while loading (:attr:`Model.warnings`)."""
        return self.model.warnings

    @cached_property
    def exact(self) -> ExactFaces:
        """Exact queries on the trimmed faces (in-face test, distance, boundary, inside)."""
        return ExactFaces(self.model)

    def mesh(self, tolerance: float = CHORDAL_TOLERANCE) -> trimesh.Trimesh:
        """The triangle mesh at chordal ``tolerance`` (mm), tessellated once per tolerance
        (:func:`probegen.cad.tessellate`).  Shared: copy it before changing it."""
        return self.memo(("mesh", tolerance), lambda: tessellate(self.model, tolerance))

    def memo(self, key: Hashable, build: Callable[[], T]) -> T:
        """The value kept under ``key``, built by ``build()`` the first time.

        For values derived from this part alone (plus the hashable inputs in ``key``):
        the consumer names its values by a key of its own (a tuple beginning with a
        name), the part keeps them as long as it lives.
        """
        if key not in self._memo:
            self._memo[key] = build()
        return cast(T, self._memo[key])


def load_part(path: str | os.PathLike[str]) -> Part:
    """Read the STEP file ``path`` into a :class:`Part` (:func:`probegen.cad.load_step`).

    Load it once, at the top (the command, or a public entry given a spec), and hand the
    part down.

    Raises:
        ModelError: the file is missing, not STEP, corrupt or holds no faces.
    """
    return Part(load_step(path))
