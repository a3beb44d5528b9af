"""Errors of the ROS 2 set-up (:mod:`harness.ros2`)."""

from __future__ import annotations

from harness.errors import SrrError

__all__ = ["Ros2SetupError"]


class Ros2SetupError(SrrError):
    """A ROS 2 interface package cannot be made available: a prerequisite is missing (the
    message says in one line what to install) or generating or compiling it failed."""
