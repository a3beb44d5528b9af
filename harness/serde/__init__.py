"""Messages and their serialization: the ROS 2 message types and CDR encoding
(:mod:`~harness.serde.messages`, :mod:`~harness.serde.cdr`, the scatter-gather payload
pieces of :mod:`~harness.serde.pieces`) and the ROS 1 message types and wire format
(:mod:`~harness.serde.ros1`).

Names are imported from their submodules on first use (:mod:`harness._lazy`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from harness._lazy import lazy_exports

if TYPE_CHECKING:
    from harness.serde.messages import TYPESTORE, serialize

__all__ = ["TYPESTORE", "serialize"]

_WHERE = {
    "TYPESTORE": "messages",
    "serialize": "messages",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
