"""Nodes that read and write prims of the simulated world (``ctx.world``).

* ``srr.ReadPrimPose`` (data): the live world pose of a prim, for publishers such as
  ``ROS2PublishRawTransformTree``. ``robotFront`` names the prim axis reported as +X, as
  ``IsaacComputeOdometry`` does, so a ground-truth pose of the forklift chassis (forward -X)
  faces the way it drives, like its odometry.
* ``srr.SetPrimColor`` (action): the display colour of a geom prim — the harness's
  ``UsdGeom.Mesh.GetDisplayColorAttr().Set(...)``; the alpha stays as built. It shows in the
  next render and is undone by ``World.reset``.

Neither has an Isaac Sim alias: Isaac scripts reach the stage directly, which the harness's
script nodes cannot (they see only ``db``).
"""

from __future__ import annotations

from typing import Any

from harness.errors import SimulationError
from harness.geometry import quat_wxyz_from_yaw, quat_wxyz_mul_floats, yaw_between
from harness.graph import Attr, NodeType, register
from harness.graph.errors import GraphError
from harness.sim.prims import PrimKind

__all__ = ["ReadPrimPose", "SetPrimColor"]


def _prim(db: Any, world: Any) -> str:
    value = db.inputs.prim
    prim = value[0] if value else ""
    if not prim or not world.has_prim(prim):
        raise GraphError(f"{db.node_path}.inputs:prim: no prim {prim!r} in the world")
    return str(prim)


@register("srr.ReadPrimPose")
class ReadPrimPose(NodeType):
    """``translation`` (m) and ``rotation`` (quatd, x y z w) of ``prim`` in the world."""

    kind = "data"
    inputs = (Attr("prim", "target", ()), Attr("robotFront", "double[3]", (1.0, 0.0, 0.0)))
    outputs = (
        Attr("translation", "double[3]", (0.0, 0.0, 0.0)),
        Attr("rotation", "quatd[4]", (0.0, 0.0, 0.0, 1.0)),
    )

    def initialize(self, db: Any, ctx: Any) -> None:
        self._prim = _prim(db, ctx.world)
        self._front = quat_wxyz_from_yaw(yaw_between(db.inputs.robotFront)).tolist()

    def compute(self, db: Any, ctx: Any) -> bool:
        pos, quat = ctx.world.prim_pose(self._prim)
        w, x, y, z = quat_wxyz_mul_floats(quat.tolist(), self._front)
        stored = db.stored  # tuples of floats, already in their stored form
        stored["outputs:translation"] = tuple(pos.tolist())
        stored["outputs:rotation"] = (x, y, z, w)
        return True


@register("srr.SetPrimColor")
class SetPrimColor(NodeType):
    """Sets the RGB colour (each in [0, 1]) of the geom ``prim``."""

    kind = "action"
    inputs = (
        Attr("execIn", "execution"),
        Attr("prim", "target", ()),
        Attr("color", "double[3]", (1.0, 1.0, 1.0)),
    )
    outputs = (Attr("execOut", "execution"),)

    def compute(self, db: Any, ctx: Any) -> bool:
        world = ctx.world
        prim = _prim(db, world)
        ref = world.prim_ref(prim)
        if ref.kind is not PrimKind.GEOM:
            raise GraphError(f"{db.node_path}.inputs:prim: {prim} is a {ref.kind.value}, "
                             "not a geom")
        alpha = float(world.model.geom_rgba[ref.id][3])
        try:
            world.set_geom_rgba(prim, (*db.inputs.color, alpha))
        except SimulationError as err:
            raise GraphError(f"{db.node_path}.inputs:color: {err}") from err
        return True
