"""What ``srr run --foxglove`` asks for (:class:`LiveConfig`), apart from the server that
serves it (:mod:`harness.live.view`): the command line builds it without loading the bus."""

from __future__ import annotations

import math
from dataclasses import dataclass

from harness.live.errors import LiveViewError

__all__ = ["DEFAULT_PORT", "LiveConfig"]

DEFAULT_PORT = 8765


@dataclass(frozen=True)
class LiveConfig:
    """What ``--foxglove`` asks for.

    ``host``/``port``: where the WebSocket server listens (port 0: any free port).
    ``wait_s``: hold the first tick until a client subscribes to a topic (and its other
    subscriptions settled, :mod:`harness.live.view`), at most this long
    (None: do not wait). ``rate``: pace the run so simulated time goes at most ``rate`` times
    as fast as the wall clock (None: as fast as it computes)."""

    host: str = "127.0.0.1"
    port: int = DEFAULT_PORT
    wait_s: float | None = None
    rate: float | None = None

    def __post_init__(self) -> None:
        if not self.host.strip():
            raise LiveViewError("--foxglove-host: must not be empty")
        if isinstance(self.port, bool) or not isinstance(self.port, int) \
                or not 0 <= self.port <= 65535:
            raise LiveViewError(f"--foxglove-port: must be a port number 0..65535, "
                                f"got {self.port!r}")
        if self.wait_s is not None and not (math.isfinite(self.wait_s) and self.wait_s >= 0):
            raise LiveViewError(f"--foxglove-wait: must be >= 0 seconds, got {self.wait_s!r}")
        if self.rate is not None and not (math.isfinite(self.rate) and self.rate > 0):
            raise LiveViewError(f"--rate: must be > 0 (simulated seconds per wall-clock "
                                f"second), got {self.rate!r}")
