"""The in-process bus, ROS 2 message helpers and the MCAP recorder."""

from harness.bus.bus import TRANSIENT_LOCAL, Bus, BusError, Envelope, Publisher, Qos, TopicInfo
from harness.bus.names import TopicNameError, resolve_topic, validate_topic
from harness.bus.recorder import Recorder, TopicStats

__all__ = [
    "TRANSIENT_LOCAL",
    "Bus",
    "BusError",
    "Envelope",
    "Publisher",
    "Qos",
    "Recorder",
    "TopicInfo",
    "TopicNameError",
    "TopicStats",
    "resolve_topic",
    "validate_topic",
]
