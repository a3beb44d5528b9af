"""The live view: the Foxglove WebSocket server of ``srr run --foxglove``
(:mod:`~harness.live.view`), its configuration (:mod:`~harness.live.config`) and the
subprotocol front of its socket (:mod:`~harness.live.wsfront`).

Names are imported from their submodules on first use (:mod:`harness._lazy`): reading
the configuration loads no server."""

from __future__ import annotations

from typing import TYPE_CHECKING

from harness._lazy import lazy_exports

if TYPE_CHECKING:
    from harness.live.config import LiveConfig
    from harness.live.view import LiveView

__all__ = ["LiveConfig", "LiveView"]

_WHERE = {
    "LiveConfig": "config",
    "LiveView": "view",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
