"""Camera keyframes for the report: the recorded frame nearest a moment, as an inline PNG.

The PNG writer is the format's minimum (IHDR, one IDAT of zlib-compressed scanlines with
filter type 0, IEND), enough for 8-bit RGB and grey images; no imaging library is needed.
"""

from __future__ import annotations

import base64
import contextlib
import struct
import zlib
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from mcap.reader import make_reader
from rosbags.rosbag2 import Reader

from harness.bus.messages import TYPESTORE
from harness.frames import finished_mcap

__all__ = ["IMAGE_TYPE", "Keyframe", "data_uri", "encode_png", "image_array", "keyframes",
           "nearest_images"]

IMAGE_TYPE = "sensor_msgs/msg/Image"
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


def image_array(msg: object) -> np.ndarray | None:
    """An ``(h, w, 3)`` RGB or ``(h, w)`` grey array of a ``sensor_msgs/Image``, or None for
    encodings that are not colour or 8-bit grey (depth images)."""
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
    factor = -(-w // MAX_WIDTH)
    return a[::factor, ::factor] if factor > 1 else a


def nearest_images(bag_dir: Path, targets_ns: Sequence[int], *,
                   max_gap_ns: dict[str, int] | None = None,
                   topics: Sequence[str] | None = None
                   ) -> dict[int, list[tuple[str, int, np.ndarray]]]:
    """For each target time, ``(topic, log time, pixels)`` of the nearest colour image of
    every image topic of the bag (pixels as :func:`image_array` gives them).

    ``max_gap_ns``: topic → largest gap between its messages (the search window around a
    target is that gap); ``topics`` restricts the image topics. Depth and other non-colour
    images are skipped. Only the windows around the targets are read. Returns target → list
    sorted by topic."""
    out: dict[int, list[tuple[str, int, np.ndarray]]] = {t: [] for t in targets_ns}
    if not targets_ns:
        return out
    gaps = max_gap_ns or {}
    with _windows(Path(bag_dir)) as (connections, window):
        conns = [c for c in connections if c.msgtype == IMAGE_TYPE
                 and (topics is None or c.topic in topics)]
        non_color: set[str] = set()
        for target in targets_ns:
            for conn in sorted(conns, key=lambda c: c.topic):
                if conn.topic in non_color:
                    continue
                half = max(int(gaps.get(conn.topic, 1_000_000_000)), 1_000_000)
                best: tuple[int, bytes] | None = None
                for ts, raw in window(conn, target - half, target + half + 1):
                    if best is None or abs(ts - target) < abs(best[0] - target):
                        best = (ts, raw)
                if best is None:
                    continue
                msg = TYPESTORE.deserialize_cdr(best[1], conn.msgtype)
                pixels = image_array(msg)
                if pixels is None:
                    non_color.add(conn.topic)
                    continue
                out[target].append((conn.topic, best[0], pixels))
    return out


Window = Callable[[Any, int, int], Iterator[tuple[int, bytes]]]


@contextlib.contextmanager
def _windows(bag_dir: Path) -> Iterator[tuple[list[Any], Window]]:
    """The bag's connections and a reader of one connection's messages in ``[start, stop)``
    (log time order): through the MCAP file's chunk index when the bag is one finished MCAP
    file (no ruamel parsing of ``metadata.yaml``), else through rosbags' Reader."""
    mcap = finished_mcap(bag_dir)
    if mcap is None:
        with Reader(bag_dir) as reader:
            def rosbags_window(conn: Any, start: int, stop: int) -> Iterator[tuple[int, bytes]]:
                for _, ts, raw in reader.messages(connections=[conn], start=start, stop=stop):
                    yield ts, raw
            yield list(reader.connections), rosbags_window
        return
    with mcap.path.open("rb") as f:
        indexed = make_reader(f)

        def mcap_window(conn: Any, start: int, stop: int) -> Iterator[tuple[int, bytes]]:
            for _, _, message in indexed.iter_messages(topics=[conn.topic], start_time=start,
                                                       end_time=stop):
                yield message.log_time, message.data
        yield list(mcap.connections), mcap_window


def keyframes(bag_dir: Path, targets_ns: Sequence[int], *, max_gap_ns: dict[str, int]
              | None = None, topics: Sequence[str] | None = None) -> dict[int, list[Keyframe]]:
    """For each target time, the nearest colour image of every image topic of the bag, as a
    PNG keyframe (see :func:`nearest_images`). Returns target → keyframes sorted by topic."""
    found = nearest_images(bag_dir, targets_ns, max_gap_ns=max_gap_ns, topics=topics)
    return {target: [Keyframe(topic, ts, target, px.shape[1], px.shape[0], encode_png(px))
                     for topic, ts, px in frames] for target, frames in found.items()}
