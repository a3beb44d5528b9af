"""Compressed camera streams: into the bag (``CompressedCameraHelper``) and over RTSP
(``RTSPCameraHelper``, seed 002's node).

* ``CompressedCameraHelper`` publishes a render product's ``type`` (``rgb`` or ``depth``)
  in ``format``:

  ====== ====== ================================== =====================================
  type   format message                            content
  ====== ====== ================================== =====================================
  rgb    h264   foxglove_msgs/CompressedVideo      one Annex B access unit per frame, a
                                                   keyframe (with SPS/PPS) first and every
                                                   ``keyframeInterval`` frames, no B-frames
  rgb    jpeg   sensor_msgs/CompressedImage        ``format: jpeg``
  rgb    png    sensor_msgs/CompressedImage        ``format: png`` (lossless)
  depth  png    sensor_msgs/CompressedImage        ``format: "16UC1; png"``: 16-bit grey,
                                                   millimetres, 0 = no return
  ====== ====== ================================== =====================================

  Stamps are the tick's simulation time; the h264 access units also carry it as SEI
  (:mod:`harness.video.sei`). It shares its camera's render with the raw helpers.
* ``RTSPCameraHelper`` serves a render product as h264 at ``rtsp://<host>:<port><mountPath>``
  (:mod:`harness.video.rtsp`; the run's servers live on ``ctx.extras["rtsp"]``). It publishes
  nothing on the bus. While a stream has no client nothing is rendered or encoded for it; a
  client that arrives gets a keyframe at the next frame. Each gated execution is one frame
  on the wire, so a ``SimulationGate`` upstream sets the stream's rate.

Encoder inputs (both nodes): ``encoder`` (``x264`` | ``nvenc``), ``keyframeInterval``,
``crf``, ``bitrateKbps`` (0: constant quality), ``threads``, ``preset`` ("" = default),
``fps`` (the stream's nominal rate, for the encoder's rate control and timing info).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from harness.bus.endpoints import Endpoint, TfEdge
from harness.camera_topics import COMPRESSED_FORMATS
from harness.graph import Attr, NodeType, register
from harness.graph.errors import GraphError
from harness.graph.nodes.camera import render_products
from harness.graph.nodes.ros_bridge import BRIDGE_INPUTS, topic_of
from harness.scenario.prims import frame_of
from harness.serde.messages import header, make, msg_type, time_msg
from harness.video.codec import (
    DEPTH_PNG_FORMAT,
    H264Encoder,
    H264Settings,
    encode_depth_png,
    encode_jpeg,
    encode_png,
    reformatter,
)
from harness.video.errors import VideoError

__all__ = ["COMPRESSED_FORMATS", "RTSP_HUB", "CompressedCameraHelper", "RTSPCameraHelper",
           "compressed_image_message", "compressed_video_message", "rtsp_hub"]

#: Key of the run's RTSP servers in ``ctx.extras``.
RTSP_HUB = "rtsp"


_ENCODER_INPUTS = (
    Attr("encoder", "token", "x264"),
    Attr("keyframeInterval", "uint", 30),
    Attr("crf", "uint", 23),
    Attr("bitrateKbps", "uint", 0),
    Attr("threads", "uint", 1),
    Attr("preset", "token", ""),
    Attr("fps", "double", 30.0),
)


def compressed_video_message(ns: int, frame_id: str, data: bytes, fmt: str = "h264") -> Any:
    """``foxglove_msgs/CompressedVideo`` of one encoded frame."""
    return msg_type("foxglove_msgs/msg/CompressedVideo")(
        timestamp=time_msg(ns), frame_id=frame_id,
        data=np.frombuffer(data, dtype=np.uint8), format=fmt)


def compressed_image_message(ns: int, frame_id: str, data: bytes, fmt: str) -> Any:
    """``sensor_msgs/CompressedImage`` with ``format`` ``fmt``."""
    return make("sensor_msgs/msg/CompressedImage", header=header(ns, frame_id), format=fmt,
                data=np.frombuffer(data, dtype=np.uint8))


def _settings(db: Any) -> H264Settings:
    i = db.inputs
    encoder = str(i.encoder)
    if encoder not in ("x264", "nvenc"):
        raise GraphError(f"{db.node_path}.inputs:encoder: expected 'x264' or 'nvenc', got "
                         f"{encoder!r}")
    if int(i.keyframeInterval) < 1:
        raise GraphError(f"{db.node_path}.inputs:keyframeInterval: must be >= 1")
    if not 0 <= int(i.crf) <= 51:
        raise GraphError(f"{db.node_path}.inputs:crf: must be within 0..51, got {i.crf}")
    return H264Settings(encoder=encoder,  # type: ignore[arg-type]
                        keyframe_interval=int(i.keyframeInterval), crf=int(i.crf),
                        bitrate_kbps=int(i.bitrateKbps) or None,
                        threads=max(1, int(i.threads)), preset=str(i.preset) or None)


def _fps(db: Any) -> float:
    fps = float(db.inputs.fps)
    if not fps > 0:
        raise GraphError(f"{db.node_path}.inputs:fps: must be > 0, got {fps}")
    return fps


@register("srr.CompressedCameraHelper")
class CompressedCameraHelper(NodeType):
    """Publishes a render product's ``type`` stream compressed as ``format`` on
    ``topicName`` (see the module's table)."""

    kind = "action"
    inputs = (
        *BRIDGE_INPUTS,
        Attr("renderProductPath", "token", ""),
        Attr("frameId", "string", ""),
        Attr("type", "token", "rgb"),
        Attr("format", "token", "h264"),
        Attr("topicName", "string", "rgb/h264"),
        Attr("jpegQscale", "uint", 3),
        Attr("enabled", "bool", True),
        *_ENCODER_INPUTS,
    )
    outputs = (Attr("execOut", "execution"),)

    @staticmethod
    def _kind(stream: str, fmt: str, where: str) -> str:
        msgtype = COMPRESSED_FORMATS.get((stream, fmt))
        if msgtype is None:
            known = ", ".join(f"{t} as {f}" for t, f in COMPRESSED_FORMATS)
            raise GraphError(f"{where}: {stream} as {fmt} is not supported (supported: "
                             f"{known})")
        return msgtype

    def endpoints(self, value: Callable[[str], Any]) -> Sequence[Endpoint | TfEdge]:
        msgtype = self._kind(str(value("type")), str(value("format")), "type/format")
        return (Endpoint("pub", str(value("topicName")), msgtype,
                         str(value("nodeNamespace"))),)

    def initialize(self, db: Any, ctx: Any) -> None:
        self._stream, self._format = str(db.inputs.type), str(db.inputs.format)
        msgtype = self._kind(self._stream, self._format, f"{db.node_path}.inputs:format")
        if not 2 <= int(db.inputs.jpegQscale) <= 31:
            raise GraphError(f"{db.node_path}.inputs:jpegQscale: must be within 2..31, got "
                             f"{db.inputs.jpegQscale}")
        self._settings = _settings(db) if self._format == "h264" else None
        self._encoder: H264Encoder | None = None
        self._reformat: Any = None
        self._pub = ctx.bus.advertise(topic_of(db), msgtype)

    def reset(self) -> None:
        self._encoder = None

    def compute(self, db: Any, ctx: Any) -> bool:
        if not db.inputs.enabled:
            return True
        table = render_products(ctx)
        product = table.product(str(db.inputs.renderProductPath), db.node_path)
        frame_id = str(db.inputs.frameId) or frame_of(product.camera_prim)
        frame = table.frame(product, int(ctx.tick), db.node_path)
        ns = int(ctx.time_ns)
        try:
            if self._format == "h264":
                assert self._settings is not None
                if self._encoder is None:
                    self._encoder = H264Encoder(product.width, product.height, _fps(db),
                                                self._settings, db.node_path)
                for au in self._encoder.encode(frame.rgb, ns):
                    self._pub.publish(compressed_video_message(au.time_ns, frame_id,
                                                               au.data))
                return True
            if self._stream == "depth":
                data, fmt = encode_depth_png(frame.depth), DEPTH_PNG_FORMAT
            elif self._format == "jpeg":
                if self._reformat is None:
                    self._reformat = reformatter()
                data = encode_jpeg(frame.rgb, int(db.inputs.jpegQscale), self._reformat)
                fmt = "jpeg"
            else:
                data, fmt = encode_png(frame.rgb), "png"
        except VideoError as err:
            raise GraphError(f"{db.node_path}: {err}") from err
        self._pub.publish(compressed_image_message(ns, frame_id, data, fmt))
        return True


def rtsp_hub(ctx: Any, rate: float | None = None) -> Any:
    """The run's RTSP servers on ``ctx.extras`` (started on first use)."""
    from harness.video.rtsp import RtspHub

    hub = ctx.extras.get(RTSP_HUB)
    if not isinstance(hub, RtspHub):
        hub = RtspHub(rate=rate)
        ctx.extras[RTSP_HUB] = hub
    return hub


@register("srr.RTSPCameraHelper", aliases=("RTSPCameraHelper",))
class RTSPCameraHelper(NodeType):
    """Serves a render product as an h264 RTSP stream at ``rtsp://host:port/mountPath``."""

    kind = "action"
    inputs = (
        Attr("execIn", "execution"),
        Attr("renderProductPath", "token", ""),
        Attr("port", "uint", 8554),
        Attr("mountPath", "string", "/camera"),
        Attr("host", "string", "127.0.0.1"),
        Attr("enabled", "bool", True),
        *_ENCODER_INPUTS,
    )
    outputs = (Attr("execOut", "execution"),)

    def initialize(self, db: Any, ctx: Any) -> None:
        from harness.video.rtsp import StreamConfig

        port = int(db.inputs.port)
        if not 1 <= port <= 65535:
            raise GraphError(f"{db.node_path}.inputs:port: must be within 1..65535, got {port}")
        self._settings = _settings(db)
        self._fps = _fps(db)
        self._stream = rtsp_hub(ctx).stream(StreamConfig(
            port, str(db.inputs.mountPath), str(db.inputs.host) or "127.0.0.1",
            where=f"{db.node_path}.inputs:port"))
        self._encoder: H264Encoder | None = None
        self._index = 0

    def reset(self) -> None:
        self._encoder = None
        self._index = 0

    def compute(self, db: Any, ctx: Any) -> bool:
        index = self._index
        self._index += 1
        stream = self._stream
        stream.hub.pace(int(ctx.time_ns))
        if not db.inputs.enabled or stream.clients == 0:
            return True  # nobody watches: nothing rendered, nothing encoded
        table = render_products(ctx)
        product = table.product(str(db.inputs.renderProductPath), db.node_path)
        if self._encoder is None:
            self._encoder = H264Encoder(product.width, product.height, self._fps,
                                        self._settings, db.node_path)
        frame = table.frame(product, int(ctx.tick), db.node_path)
        try:
            units = self._encoder.encode(frame.rgb, int(ctx.time_ns),
                                         keyframe=stream.wants_keyframe(), index=index)
        except VideoError as err:
            raise GraphError(f"{db.node_path}: {err}") from err
        for au in units:
            stream.push(au)
        return True
