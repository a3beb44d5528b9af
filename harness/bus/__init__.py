"""The in-process bus, ROS 2 message helpers and the MCAP recorder."""

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
from harness.bus.live import LiveConfig, LiveView
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
