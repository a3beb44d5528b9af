"""Prim paths: the USD-like names the rest of srr uses to address things in the MuJoCo model.

While a model is being built, builders *declare* prims (path → kind and MuJoCo name); after
compilation :meth:`PrimTable.resolve` turns the declarations into a frozen path → :class:`PrimRef`
mapping with MuJoCo ids. One prim path names exactly one MuJoCo object; several paths may name
the same object (an alias such as the robot root prim for its chassis body).
"""

from __future__ import annotations

import enum
import types
from collections.abc import Mapping
from dataclasses import dataclass

import mujoco

from harness.errors import SimulationError
from harness.scenario.prims import check_prim_path

__all__ = ["PrimKind", "PrimRef", "PrimTable", "check_prim_path"]

class PrimKind(enum.Enum):
    """What a prim is in MuJoCo terms."""

    BODY = "body"
    SITE = "site"
    CAMERA = "camera"
    GEOM = "geom"

    @property
    def objtype(self) -> mujoco.mjtObj:
        return {
            PrimKind.BODY: mujoco.mjtObj.mjOBJ_BODY,
            PrimKind.SITE: mujoco.mjtObj.mjOBJ_SITE,
            PrimKind.CAMERA: mujoco.mjtObj.mjOBJ_CAMERA,
            PrimKind.GEOM: mujoco.mjtObj.mjOBJ_GEOM,
        }[self]


@dataclass(frozen=True)
class PrimRef:
    """A resolved prim: its kind, MuJoCo id and MuJoCo name."""

    kind: PrimKind
    id: int
    name: str


class PrimTable:
    """Build-time registry of prim declarations; :meth:`resolve` freezes it after compile."""

    def __init__(self) -> None:
        self._decl: dict[str, tuple[PrimKind, str]] = {}

    def declare(self, path: str, kind: PrimKind, mj_name: str) -> str:
        """Declare ``path`` as the MuJoCo object ``mj_name`` of ``kind``; duplicates refused."""
        check_prim_path(path)
        if path in self._decl:
            raise SimulationError(f"prim {path} is declared twice")
        self._decl[path] = (kind, mj_name)
        return path

    def __contains__(self, path: object) -> bool:
        return path in self._decl

    def resolve(self, model: mujoco.MjModel) -> Mapping[str, PrimRef]:
        """Look every declaration up in the compiled ``model``; a missing name is a bug."""
        out: dict[str, PrimRef] = {}
        for path in sorted(self._decl):
            kind, name = self._decl[path]
            idx = mujoco.mj_name2id(model, kind.objtype, name)
            if idx < 0:
                raise SimulationError(f"prim {path}: no {kind.value} named {name!r} in the model")
            out[path] = PrimRef(kind, int(idx), name)
        return types.MappingProxyType(out)
