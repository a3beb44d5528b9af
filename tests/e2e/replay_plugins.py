"""A replacement perception plug-in for the replay tests: it subscribes like the real one but
reports nobody, every time a depth image arrives."""

from __future__ import annotations

from typing import Any

from harness.serde.messages import make
from harness.sut import SutContext, SystemUnderTest


class BlindTracker(SystemUnderTest):
    def setup(self, ctx: SutContext) -> None:
        self.pending = False
        for cam in ctx.params.get("cameras", []):
            ctx.subscribe(f"{cam}_depth", "sensor_msgs/msg/Image", self._on_depth)
        self.pub = ctx.publisher("/perception/tracks", "visualization_msgs/msg/MarkerArray")

    def _on_depth(self, msg: Any) -> None:
        self.pending = True

    def step(self, now_ns: int) -> None:
        if self.pending:
            self.pending = False
            self.pub.publish(make("visualization_msgs/msg/MarkerArray", markers=[]))
