"""Recordings: writing MCAP rosbag2 bags (the MCAP writer, the bag directory, the
recorder, the ROS 1-profile recorder), reading them back and recovering a bag a crash
left unfinished.

Names are imported from their submodules on first use (:mod:`harness._lazy`): reading a
bag loads no recorder."""

from __future__ import annotations

from typing import TYPE_CHECKING

from harness._lazy import lazy_exports

if TYPE_CHECKING:
    from harness.recording.recorder import Recorder, TopicStats

__all__ = ["Recorder", "TopicStats"]

_WHERE = {
    "Recorder": "recorder",
    "TopicStats": "recorder",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
