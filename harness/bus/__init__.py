"""The in-process transport: the bus (publish/subscribe with QoS), its endpoints, and the
topic- and frame-name rules.

Names are imported from their submodules on first use (:mod:`harness._lazy`): reading
topic-name rules (:mod:`~harness.bus.names`) loads no bus. Messages and their
serialization live in :mod:`harness.serde`, recording and reading bags in
:mod:`harness.recording`, the Foxglove live view in :mod:`harness.live`."""

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
    from harness.bus.names import (
        FrameIdError,
        TopicNameError,
        remap_topic,
        resolve_topic,
        validate_frame_id,
        validate_namespace,
        validate_topic,
    )

__all__ = [
    "TRANSIENT_LOCAL",
    "Bus",
    "BusError",
    "Deferred",
    "Envelope",
    "FrameIdError",
    "Publisher",
    "Qos",
    "TopicInfo",
    "TopicNameError",
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
    "FrameIdError": "names",
    "TopicNameError": "names",
    "remap_topic": "names",
    "resolve_topic": "names",
    "validate_frame_id": "names",
    "validate_namespace": "names",
    "validate_topic": "names",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
