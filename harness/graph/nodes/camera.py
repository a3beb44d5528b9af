"""Camera nodes: render products and the ROS camera helpers (Isaac Sim names as aliases).

* ``CreateRenderProduct`` (``IsaacCreateRenderProduct``) registers a *render product* — a
  prim plus an image size — in the run's :class:`RenderProductTable` (kept on
  ``ctx.extras["render_products"]``, never global) and outputs its handle
  ``renderProductPath`` (``/Render<node path>``). The prim is usually a camera; the lidar
  helper also takes its lidar prim from a render product, as in Isaac.
* ``CameraHelper`` (``ROS2CameraHelper`` / ``ROS1CameraHelper``) publishes one stream of a
  render product, chosen by ``inputs:type``:

  ============== ============================ ==============================================
  type           message                      content
  ============== ============================ ==============================================
  rgb            sensor_msgs/Image ``rgb8``   colour, top row first
  depth          sensor_msgs/Image ``32FC1``  metres along the optical axis; ``+inf`` where
                                              nothing was hit (see :mod:`harness.sim.render`)
  depth_pcl,     sensor_msgs/PointCloud2      x, y, z float32 in the optical frame, from the
  pointcloud                                  depth image and the intrinsics; pixels without
                                              depth are dropped (``height = 1``,
                                              ``is_dense = true``), row-major pixel order
  camera_info    sensor_msgs/CameraInfo       ``plumb_bob`` with zero distortion, ``K``,
                                              ``R = I``, ``P = [K | 0]``
  ============== ============================ ==============================================

* ``CameraInfoHelper`` (``ROS2CameraInfoHelper``) is the ``camera_info`` stream on its own.

Intrinsics are MuJoCo's pinhole: ``fy = fx = h / (2 tan(fovy / 2))``, ``cx = (w - 1) / 2``,
``cy = (h - 1) / 2`` (ROS pixel coordinates, integers at pixel centres); the point cloud uses
the same numbers, so re-projecting a point gives back its pixel. Stamps are the tick's
simulation time. ``frameId`` defaults to the last component of the camera prim's path (what
the TF publishers name the camera's optical frame). ``useSystemTime`` must stay false (the
harness has only simulation time); ``frameSkipCount = n`` publishes every (n+1)-th execution.
``qosProfile``, ``queueSize`` and ``resetSimulationTimeOnStop`` are accepted for
compatibility and change nothing.

Rendering happens only when a helper that needs pixels executes (so a SimulationGate upstream
sets the cost), and at most once per camera, size and tick however many helpers publish it.
With ``render.overlap`` (``auto``: with a GPU) the frame renders on a background thread
(:mod:`harness.sim.render_pipeline`) and the helpers publish :class:`~harness.bus.Deferred`
messages built from it when it is needed: by a subscriber (in the same tick, as always) or by
the recorder (on its own threads). The bytes are the same either way.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any, Protocol

import numpy as np

from harness.bus.bus import Deferred
from harness.bus.endpoints import Endpoint, TfEdge
from harness.errors import SimulationError
from harness.graph import Attr, NodeType, register
from harness.graph.errors import GraphError
from harness.graph.nodes.ros_bridge import BRIDGE_INPUTS, aliases, topic_of
from harness.scenario.prims import frame_of
from harness.serde.messages import header, msg_type
from harness.sim.prims import PrimKind
from harness.sim.render import (
    CameraFrame,
    Intrinsics,
    Renderer,
    is_software_renderer,
    points_from_depth,
)
from harness.sim.render_pipeline import RenderThread

__all__ = [
    "CAMERA_TYPES",
    "RENDER_PRODUCTS",
    "CameraHelper",
    "CameraInfoHelper",
    "CreateRenderProduct",
    "FrameSource",
    "RenderProduct",
    "RenderProductTable",
    "camera_info_message",
    "depth_image_message",
    "image_message",
    "point_cloud_message",
    "render_products",
    "rgb_image_message",
]

#: Key of the run's render-product table in ``ctx.extras``.
RENDER_PRODUCTS = "render_products"

#: ``inputs:type`` of CameraHelper → message type.
CAMERA_TYPES: Mapping[str, str] = {
    "rgb": "sensor_msgs/msg/Image",
    "depth": "sensor_msgs/msg/Image",
    "depth_pcl": "sensor_msgs/msg/PointCloud2",
    "pointcloud": "sensor_msgs/msg/PointCloud2",
    "camera_info": "sensor_msgs/msg/CameraInfo",
}


# ----------------------------------------------------------------------------- messages

def rgb_image_message(ns: int, frame_id: str, rgb: np.ndarray) -> Any:
    """``sensor_msgs/Image`` ``rgb8`` from a ``(h, w, 3)`` uint8 array, top row first."""
    h, w, _ = rgb.shape
    data = np.ascontiguousarray(rgb, dtype=np.uint8).reshape(-1)
    return msg_type("sensor_msgs/msg/Image")(
        header=header(ns, frame_id), height=h, width=w, encoding="rgb8", is_bigendian=0,
        step=3 * w, data=data)


def depth_image_message(ns: int, frame_id: str, depth: np.ndarray) -> Any:
    """``sensor_msgs/Image`` ``32FC1`` (little-endian float32 metres) from ``(h, w)``."""
    h, w = depth.shape
    data = np.ascontiguousarray(depth, dtype="<f4").view(np.uint8).reshape(-1)
    return msg_type("sensor_msgs/msg/Image")(
        header=header(ns, frame_id), height=h, width=w, encoding="32FC1", is_bigendian=0,
        step=4 * w, data=data)


def point_cloud_message(ns: int, frame_id: str, points: np.ndarray) -> Any:
    """Unorganised ``sensor_msgs/PointCloud2``: x, y, z float32, ``height = 1``."""
    pts = np.ascontiguousarray(points, dtype="<f4").reshape(-1, 3)
    field = msg_type("sensor_msgs/msg/PointField")
    fields = [field(name=name, offset=4 * k, datatype=field.FLOAT32, count=1)
              for k, name in enumerate("xyz")]
    return msg_type("sensor_msgs/msg/PointCloud2")(
        header=header(ns, frame_id), height=1, width=len(pts), fields=fields,
        is_bigendian=False, point_step=12, row_step=12 * len(pts),
        data=pts.view(np.uint8).reshape(-1), is_dense=True)


def image_message(stream: str, ns: int, frame_id: str, src: FrameSource) -> Any:
    """The ``rgb``, ``depth`` or ``depth_pcl`` message of a frame (waits for it)."""
    if stream == "rgb":
        return rgb_image_message(ns, frame_id, src.rgb())
    if stream == "depth":
        return depth_image_message(ns, frame_id, src.depth())
    return point_cloud_message(ns, frame_id, points_from_depth(src.depth(), src.intrinsics))


def camera_info_message(ns: int, frame_id: str, intr: Intrinsics) -> Any:
    """``sensor_msgs/CameraInfo`` of an undistorted pinhole (``plumb_bob``, D = 0)."""
    roi = msg_type("sensor_msgs/msg/RegionOfInterest")(
        x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
    return msg_type("sensor_msgs/msg/CameraInfo")(
        header=header(ns, frame_id), height=intr.height, width=intr.width,
        distortion_model="plumb_bob", d=np.zeros(5, dtype=np.float64),
        k=np.array(intr.k, dtype=np.float64),
        r=np.eye(3, dtype=np.float64).reshape(-1),
        p=np.array(intr.p, dtype=np.float64),
        binning_x=0, binning_y=0, roi=roi)


# ----------------------------------------------------------------------------- products

@dataclass(frozen=True)
class RenderProduct:
    """What ``renderProductPath`` names: a prim rendered at ``width`` x ``height``."""

    path: str
    camera_prim: str
    width: int
    height: int


class FrameSource(Protocol):
    """A frame being rendered or rendered: its arrays, waited for on first use."""

    intrinsics: Intrinsics

    def rgb(self) -> np.ndarray: ...

    def depth(self) -> np.ndarray: ...

    def frame(self) -> CameraFrame: ...


class _Ready:
    """A frame rendered on the loop's thread, as a :class:`FrameSource`."""

    __slots__ = ("_frame", "intrinsics")

    def __init__(self, frame: CameraFrame) -> None:
        self._frame = frame
        self.intrinsics = frame.intrinsics

    def rgb(self) -> np.ndarray:
        return self._frame.rgb

    def depth(self) -> np.ndarray:
        return self._frame.depth

    def frame(self) -> CameraFrame:
        return self._frame


class RenderProductTable(Mapping[str, RenderProduct]):
    """The render products of one run (handle → product) and the frames rendered this tick.

    It owns the run's :class:`~harness.sim.render.Renderer`, created on the first frame
    requested (with ``render.overlap``, on a :class:`~harness.sim.render_pipeline.RenderThread`),
    and caches frames by (camera, size) for one tick, so helpers publishing rgb, depth and a
    point cloud of the same camera share one render.
    """

    def __init__(self, world: Any) -> None:
        self.world = world
        self._products: dict[str, RenderProduct] = {}
        self._renderer: Renderer | None = None
        self._thread: RenderThread | None = None
        self._frames: dict[tuple[int, int, int], FrameSource] = {}
        self._frames_tick: int | None = None
        render = getattr(getattr(world, "scenario", None), "render", None)
        setting = getattr(render, "overlap", False)
        self._auto = setting == "auto"
        #: Render on a background thread (``render.overlap``; ``auto`` is decided at the first
        #: frame, from the OpenGL renderer); helpers then publish Deferred messages.
        self.overlap = False if self._auto else bool(setting)

    def __getitem__(self, path: str) -> RenderProduct:
        return self._products[path]

    def __iter__(self) -> Iterator[str]:
        return iter(self._products)

    def __len__(self) -> int:
        return len(self._products)

    @property
    def renderer(self) -> Renderer | None:
        """The renderer, once a frame has been rendered."""
        return self._renderer

    def register(self, path: str, camera_prim: str, width: int, height: int) -> RenderProduct:
        """Add (or update) the product at ``path``."""
        product = RenderProduct(path, camera_prim, int(width), int(height))
        self._products[path] = product
        return product

    def product(self, path: str, where: str) -> RenderProduct:
        """The product at ``path``; unknown handles raise GraphError naming ``where``."""
        product = self._products.get(path)
        if product is None:
            known = ", ".join(sorted(self._products)) or "none"
            raise GraphError(f"{where}.inputs:renderProductPath: no render product {path!r} "
                             f"(created: {known}); connect it to "
                             "CreateRenderProduct.outputs:renderProductPath")
        return product

    def camera_id(self, product: RenderProduct, where: str) -> int:
        """MuJoCo camera id of the product's prim; a prim that is no camera is a GraphError."""
        try:
            ref = self.world.prim_ref(product.camera_prim)
        except SimulationError as err:
            raise GraphError(f"{where}: {err}") from err
        if ref.kind is not PrimKind.CAMERA:
            raise GraphError(f"{where}: render product {product.path!r} renders "
                             f"{product.camera_prim}, a {ref.kind.value}, not a camera")
        return int(ref.id)

    def intrinsics(self, product: RenderProduct, where: str) -> Intrinsics:
        """Intrinsics of the product (no rendering)."""
        cam = self.camera_id(product, where)
        fovy = float(self.world.model.cam_fovy[cam])
        return Intrinsics.from_fovy(product.width, product.height, fovy)

    def source(self, product: RenderProduct, tick: int, where: str) -> FrameSource:
        """The product's frame for ``tick``, rendered (or submitted, with :attr:`overlap`) on
        the first request of the tick."""
        cam = self.camera_id(product, where)
        if self._frames_tick != tick:
            self._frames.clear()
            self._frames_tick = tick
        key = (cam, product.width, product.height)
        src = self._frames.get(key)
        if src is None:
            try:
                if self._renderer is None:
                    self._renderer = self._first_renderer()
                if self.overlap:
                    if self._thread is None:
                        self._thread = RenderThread(self._renderer)
                    src = self._thread.submit(cam, product.width, product.height)
                else:
                    src = _Ready(self._renderer.render(cam, product.width, product.height))
            except SimulationError as err:
                raise GraphError(f"{where}: {err}") from err
            self._frames[key] = src
        return src

    def _first_renderer(self) -> Renderer:
        """The run's renderer; with ``overlap: auto`` it also decides :attr:`overlap`: off
        for a software renderer, on otherwise (the render thread makes its own context)."""
        renderer = Renderer(self.world.model, self.world.data)
        if self._auto:
            self._auto = False
            self.overlap = not is_software_renderer(renderer.gl_renderer())
            if self.overlap:  # the context belongs to the render thread: start afresh there
                renderer.close()
                renderer = Renderer(self.world.model, self.world.data)
        return renderer

    def frame(self, product: RenderProduct, tick: int, where: str) -> CameraFrame:
        """The product's frame for ``tick`` (waits for it with :attr:`overlap`)."""
        src = self.source(product, tick, where)
        try:
            return src.frame()
        except SimulationError as err:
            raise GraphError(f"{where}: {err}") from err

    def close(self) -> None:
        """Draw what is queued, then free the renderer's GL resources (idempotent)."""
        self._frames.clear()
        if self._thread is not None:
            self._thread.close()  # closes the renderer on its thread
            self._thread = None
        elif self._renderer is not None:
            self._renderer.close()
        self._renderer = None


def render_products(ctx: Any) -> RenderProductTable:
    """The run's render-product table on ``ctx.extras`` (created on first use)."""
    table = ctx.extras.get(RENDER_PRODUCTS)
    if not isinstance(table, RenderProductTable) or table.world is not ctx.world:
        table = RenderProductTable(ctx.world)
        ctx.extras[RENDER_PRODUCTS] = table
    return table


def _first(value: Any) -> str:
    if isinstance(value, str):
        return value
    return str(value[0]) if value else ""


# ----------------------------------------------------------------------------- nodes

def _core(name: str) -> tuple[str, ...]:
    return (f"omni.isaac.core_nodes.{name}", f"isaacsim.core.nodes.{name}")


@register("srr.CreateRenderProduct", aliases=_core("IsaacCreateRenderProduct"))
class CreateRenderProduct(NodeType):
    """Registers ``cameraPrim`` at ``width`` x ``height`` and outputs the product's handle.

    ``enabled = false`` stops execution here (nothing downstream renders or publishes).
    """

    kind = "action"
    inputs = (
        Attr("execIn", "execution"),
        Attr("cameraPrim", "target", ()),
        Attr("width", "uint", 1280),
        Attr("height", "uint", 720),
        Attr("enabled", "bool", True),
    )
    outputs = (Attr("execOut", "execution"), Attr("renderProductPath", "token", ""))

    def initialize(self, db: Any, ctx: Any) -> None:
        self._handle = f"/Render{db.node_path}"

    def compute(self, db: Any, ctx: Any) -> bool:
        prim = _first(db.inputs.cameraPrim)
        if not prim:
            raise GraphError(f"{db.node_path}.inputs:cameraPrim: no prim set")
        if not ctx.world.has_prim(prim):
            raise GraphError(f"{db.node_path}.inputs:cameraPrim: prim {prim!r} does not exist")
        width, height = int(db.inputs.width), int(db.inputs.height)
        if width < 1 or height < 1:
            raise GraphError(f"{db.node_path}: width and height must be >= 1, "
                             f"got {width}x{height}")
        render_products(ctx).register(self._handle, prim, width, height)
        db.outputs.renderProductPath = self._handle
        return bool(db.inputs.enabled)


_HELPER_INPUTS = (
    *BRIDGE_INPUTS,
    Attr("renderProductPath", "token", ""),
    Attr("frameId", "string", ""),
    Attr("frameSkipCount", "uint", 0),
    Attr("resetSimulationTimeOnStop", "bool", False),
    Attr("useSystemTime", "bool", False),
    Attr("enabled", "bool", True),
)


class _CameraPublisher(NodeType):
    """Shared logic of the camera helpers: checks, frame skipping, publishing."""

    kind = "action"
    outputs = (Attr("execOut", "execution"),)

    def stream(self, db: Any) -> str:
        raise NotImplementedError

    def initialize(self, db: Any, ctx: Any) -> None:
        stream = self.stream(db)
        if stream not in CAMERA_TYPES:
            raise GraphError(f"{db.node_path}.inputs:type: {stream!r} is not supported "
                             f"(supported: {', '.join(CAMERA_TYPES)})")
        if db.inputs.useSystemTime:
            raise GraphError(f"{db.node_path}.inputs:useSystemTime: must be false; srr "
                             "stamps every message with simulation time")
        self._stream = stream
        self._pub = ctx.bus.advertise(topic_of(db), CAMERA_TYPES[stream])
        self._count = 0

    def reset(self) -> None:
        self._count = 0

    def endpoints(self, value: Callable[[str], Any]) -> Sequence[Endpoint | TfEdge]:
        stream = self.stream_of(value)
        if stream not in CAMERA_TYPES:
            raise GraphError(f"type {stream!r} is not supported (supported: "
                             f"{', '.join(CAMERA_TYPES)})")
        return (Endpoint("pub", str(value("topicName")), CAMERA_TYPES[stream],
                         str(value("nodeNamespace"))),)

    def stream_of(self, value: Callable[[str], Any]) -> str:
        raise NotImplementedError

    def compute(self, db: Any, ctx: Any) -> bool:
        if db.inputs.useSystemTime:
            raise GraphError(f"{db.node_path}.inputs:useSystemTime: must be false; srr "
                             "stamps every message with simulation time")
        count = self._count
        self._count += 1
        if not db.inputs.enabled or count % (int(db.inputs.frameSkipCount) + 1):
            return True
        table = render_products(ctx)
        product = table.product(str(db.inputs.renderProductPath), db.node_path)
        frame_id = str(db.inputs.frameId) or frame_of(product.camera_prim)
        ns = int(ctx.time_ns)
        stream = self._stream
        if stream == "camera_info":
            msg = camera_info_message(ns, frame_id, table.intrinsics(product, db.node_path))
        else:
            build = partial(image_message, stream, ns, frame_id,
                            table.source(product, int(ctx.tick), db.node_path))
            msg = Deferred(build) if table.overlap else build()
        self._pub.publish(msg)
        return True


@register("srr.CameraHelper", aliases=aliases("CameraHelper"))
class CameraHelper(_CameraPublisher):
    """Publishes the ``type`` stream of a render product on ``topicName``."""

    inputs = (
        *_HELPER_INPUTS,
        Attr("type", "token", "rgb"),
        Attr("topicName", "string", "rgb"),
    )

    def stream(self, db: Any) -> str:
        return str(db.inputs.type)

    def stream_of(self, value: Callable[[str], Any]) -> str:
        return str(value("type"))


@register("srr.CameraInfoHelper", aliases=aliases("CameraInfoHelper"))
class CameraInfoHelper(_CameraPublisher):
    """Publishes a render product's ``sensor_msgs/CameraInfo`` on ``topicName``."""

    inputs = (*_HELPER_INPUTS, Attr("topicName", "string", "camera_info"))

    def stream(self, db: Any) -> str:
        return "camera_info"

    def stream_of(self, value: Callable[[str], Any]) -> str:
        return "camera_info"
