"""A system under test for the robot-camera record tests: it reads the robot camera's raw
topics and publishes, per image, its stamp and mean (rgb: mean pixel value; depth: mean of
the finite depths, metres), so a replay that decodes the compressed topics can be compared
with the run that read the rendered frames."""

from __future__ import annotations

from typing import Any

import numpy as np

from harness.serde.messages import make
from harness.sut import SutContext, SystemUnderTest

STATS = "std_msgs/msg/Float64MultiArray"


def _stamp(msg: Any) -> float:
    return float(msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec)


class ImageStats(SystemUnderTest):
    def setup(self, ctx: SutContext) -> None:
        self.pending: list[tuple[Any, list[float]]] = []
        self.rgb = ctx.publisher("image_stats/rgb", STATS)
        self.depth = ctx.publisher("image_stats/depth", STATS)
        ctx.subscribe(ctx.params["rgb"], "sensor_msgs/msg/Image", self._on_rgb)
        ctx.subscribe(ctx.params["depth"], "sensor_msgs/msg/Image", self._on_depth)

    def _on_rgb(self, msg: Any) -> None:
        pixels = np.frombuffer(bytes(msg.data), np.uint8)
        self.pending.append((self.rgb, [_stamp(msg), float(pixels.mean())]))

    def _on_depth(self, msg: Any) -> None:
        d = np.frombuffer(bytes(msg.data), "<f4")
        self.pending.append((self.depth, [_stamp(msg), float(d[np.isfinite(d)].mean())]))

    def step(self, now_ns: int) -> None:
        for pub, data in self.pending:
            pub.publish(make(STATS, data=np.array(data, np.float64)))
        self.pending = []
