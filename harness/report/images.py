"""Camera keyframes for the report: the recorded frame nearest a moment, as an inline PNG.

Raw images (``sensor_msgs/Image``) and compressed ones — ``sensor_msgs/CompressedImage`` in
JPEG or PNG, ``foxglove_msgs/CompressedVideo`` in h264, decoded from the keyframe before the
frame — are shown; depth images are not. The PNG writer is the format's minimum (IHDR, one
IDAT of zlib-compressed scanlines with filter type 0, IEND), enough for 8-bit RGB and grey
images.
"""

from __future__ import annotations

import base64
import struct
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from harness.recording.bagread import Recording, open_indexed
from harness.video.codec import H264Decoder, decode_rgb
from harness.video.errors import VideoError
from harness.video.sei import nal_units

__all__ = ["IMAGE_TYPE", "IMAGE_TYPES", "Keyframe", "data_uri", "encode_png", "image_array",
           "keyframes",
           "nearest_images"]

IMAGE_TYPE = "sensor_msgs/msg/Image"
COMPRESSED_TYPE = "sensor_msgs/msg/CompressedImage"
VIDEO_TYPE = "foxglove_msgs/msg/CompressedVideo"
#: Every camera image type a keyframe can be taken from.
IMAGE_TYPES = (IMAGE_TYPE, COMPRESSED_TYPE, VIDEO_TYPE)
MAX_WIDTH = 320  # keyframes wider than this are shrunk by an integer factor

_CHANNELS = {"rgb8": 3, "bgr8": 3, "rgba8": 4, "bgra8": 4, "mono8": 1}


@dataclass(frozen=True)
class Keyframe:
    """One camera image near a moment: ``t_ns`` is the image's log time."""

    topic: str
    t_ns: int
    target_ns: int
    width: int
    height: int
    png: bytes

    @property
    def uri(self) -> str:
        return data_uri(self.png)


def _chunk(kind: bytes, data: bytes) -> bytes:
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def encode_png(pixels: np.ndarray, level: int = 6) -> bytes:
    """PNG bytes of an ``(h, w, 3)`` RGB or ``(h, w)`` grey ``uint8`` array."""
    a = np.ascontiguousarray(pixels, dtype=np.uint8)
    if a.ndim == 2:
        color = 0
    elif a.ndim == 3 and a.shape[2] == 3:
        color = 2
    else:
        raise ValueError(f"expected (h, w) or (h, w, 3) pixels, got shape {a.shape}")
    h, w = a.shape[:2]
    rows = a.reshape(h, -1)
    raw = np.concatenate((np.zeros((h, 1), dtype=np.uint8), rows), axis=1).tobytes()
    ihdr = struct.pack(">IIBBBBB", w, h, 8, color, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", ihdr)
            + _chunk(b"IDAT", zlib.compress(raw, level)) + _chunk(b"IEND", b""))


def data_uri(png: bytes) -> str:
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def _shrink(a: np.ndarray, max_width: int | None = MAX_WIDTH) -> np.ndarray:
    if max_width is None:
        return a
    factor = -(-a.shape[1] // max_width)
    return a[::factor, ::factor] if factor > 1 else a


def image_array(msg: object, max_width: int | None = MAX_WIDTH) -> np.ndarray | None:
    """An ``(h, w, 3)`` RGB or ``(h, w)`` grey array of a ``sensor_msgs/Image`` (or of a
    JPEG or PNG ``sensor_msgs/CompressedImage``), or None for encodings that are not colour or
    8-bit grey (depth images). Wider than ``max_width``: shrunk by an integer factor (None:
    full size)."""
    if getattr(msg, "__msgtype__", "") == COMPRESSED_TYPE:
        fmt = str(getattr(msg, "format", "")).lower()
        if ";" in fmt or not ("jpeg" in fmt or "png" in fmt):  # "16UC1; png": depth
            return None
        blob = bytes(msg.data)  # type: ignore[attr-defined]
        try:
            return _shrink(decode_rgb(blob, "mjpeg" if "jpeg" in fmt else "png"), max_width)
        except VideoError:
            return None
    enc = str(getattr(msg, "encoding", "")).lower()
    ch = _CHANNELS.get(enc)
    h, w, step = int(msg.height), int(msg.width), int(msg.step)  # type: ignore[attr-defined]
    data = np.frombuffer(bytes(msg.data), dtype=np.uint8)  # type: ignore[attr-defined]
    if ch is None or h <= 0 or w <= 0 or step < w * ch or data.size < h * step:
        return None
    a = data[:h * step].reshape(h, step)[:, :w * ch].reshape(h, w, ch)
    if enc.startswith("bgr"):
        a = a[:, :, [2, 1, 0]]
    elif ch == 4:
        a = a[:, :, :3]
    if ch == 1:
        a = a[:, :, 0]
    return _shrink(a, max_width)


def _is_idr(data: bytes) -> bool:
    return any(data[h] & 0x1F == 5 for _, h, _ in nal_units(data))


def _video_frame(reader: Recording, conn: Any, target_ts: int) -> np.ndarray | None:
    """The h264 frame logged at ``target_ts``, decoded from the last keyframe before it."""
    window = 10_000_000_000
    while True:
        start = max(target_ts - window, 0)
        units: list[bytes] = []
        keyed, last = False, None
        for _, ts, raw in reader.messages(connections=[conn], start=start,
                                          stop=target_ts + 1):
            msg: Any = reader.decode(raw, conn)
            data = bytes(msg.data)
            if _is_idr(data):
                units, keyed = [], True  # decoding starts at the last keyframe
            units.append(data)
            last = ts
        if keyed or start == 0:
            break
        window *= 4
    if not keyed or last != target_ts:
        return None
    decoder = H264Decoder()
    frames: list[np.ndarray] = []
    try:
        for data in units:
            frames = decoder.decode(data) or frames
    except VideoError:
        return None
    return _shrink(frames[-1]) if frames else None


def nearest_images(bag_dir: Path, targets_ns: Sequence[int], *,
                   max_gap_ns: dict[str, int] | None = None,
                   topics: Sequence[str] | None = None
                   ) -> dict[int, list[tuple[str, int, np.ndarray]]]:
    """For each target time, ``(topic, log time, pixels)`` of the nearest colour image of
    every image topic of the bag (pixels as :func:`image_array` gives them).

    ``max_gap_ns``: topic → largest gap between its messages (the search window around a
    target is that gap); ``topics`` restricts the image topics. ``bag_dir`` holds a ROS 2 or
    a ROS 1 recording (:func:`harness.recording.bagread.open_indexed`). Depth and other non-colour
    images are skipped. Only the windows around the targets are read. Returns target → list
    sorted by topic."""
    out: dict[int, list[tuple[str, int, np.ndarray]]] = {t: [] for t in targets_ns}
    if not targets_ns:
        return out
    gaps = max_gap_ns or {}
    with open_indexed(bag_dir) as reader:
        conns = [c for c in reader.connections if c.msgtype in IMAGE_TYPES
                 and (topics is None or c.topic in topics)]
        non_color: set[str] = set()
        for target in targets_ns:
            for conn in sorted(conns, key=lambda c: c.topic):
                if conn.topic in non_color:
                    continue
                half = max(int(gaps.get(conn.topic, 1_000_000_000)), 1_000_000)
                best: tuple[int, bytes] | None = None
                for _, ts, raw in reader.messages(connections=[conn], start=target - half,
                                                  stop=target + half + 1):
                    if best is None or abs(ts - target) < abs(best[0] - target):
                        best = (ts, raw)
                if best is None:
                    continue
                if conn.msgtype == VIDEO_TYPE:
                    pixels = _video_frame(reader, conn, best[0])
                else:
                    pixels = image_array(reader.decode(best[1], conn))
                if pixels is None:
                    non_color.add(conn.topic)
                    continue
                out[target].append((conn.topic, best[0], pixels))
    return out


def keyframes(bag_dir: Path, targets_ns: Sequence[int], *, max_gap_ns: dict[str, int]
              | None = None, topics: Sequence[str] | None = None) -> dict[int, list[Keyframe]]:
    """For each target time, the nearest colour image of every image topic of the bag, as a
    PNG keyframe (see :func:`nearest_images`). Returns target → keyframes sorted by topic."""
    found = nearest_images(bag_dir, targets_ns, max_gap_ns=max_gap_ns, topics=topics)
    return {target: [Keyframe(topic, ts, target, px.shape[1], px.shape[0], encode_png(px))
                     for topic, ts, px in frames] for target, frames in found.items()}
