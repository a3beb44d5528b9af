"""The in-process bus, ROS 2 message helpers and the MCAP recorder.

Names are imported from their submodules on first use (:mod:`harness._lazy`): reading
topic-name rules (:mod:`~harness.bus.names`) or a bag loads neither the recorder nor the
live view."""

from __future__ import annotations

from typing import TYPE_CHECKING

from harness._lazy import lazy_exports

if TYPE_CHECKING:
    from harness.bus.bus import (
        TRANSIENT_LOCAL,
        Bus,
        BusError,
        Deferred,
        Envelope,
        Publisher,
        Qos,
        TopicInfo,
        resolved,
    )
    from harness.bus.live import LiveView
    from harness.bus.liveconfig import LiveConfig
    from harness.bus.names import (
        FrameIdError,
        TopicNameError,
        remap_topic,
        resolve_topic,
        validate_frame_id,
        validate_namespace,
        validate_topic,
    )
    from harness.bus.recorder import Recorder, TopicStats

__all__ = [
    "TRANSIENT_LOCAL",
    "Bus",
    "BusError",
    "Deferred",
    "Envelope",
    "FrameIdError",
    "LiveConfig",
    "LiveView",
    "Publisher",
    "Qos",
    "Recorder",
    "TopicInfo",
    "TopicNameError",
    "TopicStats",
    "remap_topic",
    "resolve_topic",
    "resolved",
    "validate_frame_id",
    "validate_namespace",
    "validate_topic",
]

_WHERE = {
    "TRANSIENT_LOCAL": "bus",
    "Bus": "bus",
    "BusError": "bus",
    "Deferred": "bus",
    "Envelope": "bus",
    "Publisher": "bus",
    "Qos": "bus",
    "TopicInfo": "bus",
    "resolved": "bus",
    "LiveConfig": "liveconfig",
    "LiveView": "live",
    "FrameIdError": "names",
    "TopicNameError": "names",
    "remap_topic": "names",
    "resolve_topic": "names",
    "validate_frame_id": "names",
    "validate_namespace": "names",
    "validate_topic": "names",
    "Recorder": "recorder",
    "TopicStats": "recorder",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
