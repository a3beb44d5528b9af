"""Import shims for graph builders written for Isaac Sim: change the imports, keep the code.

==========================================================  ===================================
Isaac Sim                                                   srr
==========================================================  ===================================
``import omni.graph.core as og``                            ``from harness.isaac import og``
``import usdrt.Sdf``                                        ``from harness.isaac import usdrt``
``from omni.isaac.core.utils.extensions import``            ``from harness.isaac import
``enable_extension``                                        enable_extension``
``from omni.isaac.core.utils.prims import``                 ``from harness.isaac import
``get_prim_at_path, is_prim_path_valid``                    get_prim_at_path, is_prim_path_valid``
==========================================================  ===================================

``og`` is :mod:`harness.graph` (``og.Controller``, ``og.Controller.Keys``, ``og.Graph``,
``og.GraphPipelineStage``); its node types are the real ones of the registry under their
Isaac names (``omni.isaac.ros_bridge.ROS1CameraHelper``, ``isaacsim.ros2.bridge.…``), so what
the builder wires publishes on the run's bus and is recorded. ``usdrt.Sdf.Path`` is a path
value that target attributes accept. The prim helpers read the world of the scenario whose
``graphs:`` builder is running (:func:`harness.builders.custom.current_build`).
"""

from __future__ import annotations

from dataclasses import dataclass

from harness import graph as og
from harness.builders.custom import current_build
from harness.graph import GraphStage, usdrt

__all__ = ["Prim", "enable_extension", "get_prim_at_path", "is_prim_path_valid", "og",
           "usdrt"]


def enable_extension(name: str) -> bool:
    """Isaac's extension switch; every srr node type is registered on import, so there is
    nothing to enable. Returns True, as Isaac does for an extension that loaded."""
    return True


@dataclass(frozen=True)
class Prim:
    """The part of ``Usd.Prim`` graph builders use: its path and whether it exists."""

    path: str

    def GetPrimPath(self) -> usdrt.SdfPath:  # Isaac's spelling
        return usdrt.Sdf.Path(self.path)

    def GetPath(self) -> usdrt.SdfPath:
        return self.GetPrimPath()

    def GetName(self) -> str:
        return self.path.rstrip("/").rsplit("/", 1)[-1]

    def IsValid(self) -> bool:
        return is_prim_path_valid(self.path)


def is_prim_path_valid(path: str) -> bool:
    """Whether ``path`` is a prim of the world being built, or a graph on the stage."""
    text = str(path)
    return current_build().has_prim(text) or GraphStage.current().has_graph(text)


def get_prim_at_path(path: str) -> Prim:
    """The prim at ``path`` (check :meth:`Prim.IsValid`, as with USD)."""
    current_build()
    return Prim(str(path))
