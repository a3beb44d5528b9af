"""A tiny stand-in for ``usdrt`` so builder code can keep ``usdrt.Sdf.Path("/World/x")``.

Port ``import usdrt.Sdf`` to ``from harness.graph import usdrt``. A path is an immutable value
whose ``str()`` (and ``pathString``) is the path text; ``target`` attributes accept it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

__all__ = ["Sdf", "SdfPath"]


@dataclass(frozen=True)
class SdfPath:
    """A prim path such as ``/World/floating_camera``."""

    pathString: str  # the usdrt / pxr spelling

    def __post_init__(self) -> None:
        if not isinstance(self.pathString, str):
            raise TypeError(f"Sdf.Path takes a string, got {self.pathString!r}")

    def __str__(self) -> str:
        return self.pathString

    @property
    def name(self) -> str:
        """The last element of the path."""
        return self.pathString.rstrip("/").rsplit("/", 1)[-1]

    @property
    def isEmpty(self) -> bool:
        return not self.pathString

    def GetString(self) -> str:
        return self.pathString

    def GetParentPath(self) -> SdfPath:
        parent = self.pathString.rstrip("/").rsplit("/", 1)[0]
        return SdfPath(parent or "/")


class Sdf:
    """Namespace mirroring ``usdrt.Sdf``: only ``Sdf.Path``."""

    Path: ClassVar[type[SdfPath]] = SdfPath
