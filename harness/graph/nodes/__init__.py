"""Node types. :func:`register_all` imports every node module, which registers its types."""

from __future__ import annotations

import importlib

__all__ = ["MODULES", "register_all"]

# Built-ins first, then simulation, sensors and the ROS bridge.
MODULES = ("core", "isaac_core", "prims", "camera", "sensors_range", "ros_bridge",
           "ros_subscriber", "video")


def register_all() -> None:
    """Import every node module once (importing registers its node types)."""
    for name in MODULES:
        importlib.import_module(f"{__name__}.{name}")
