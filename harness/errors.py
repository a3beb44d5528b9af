"""The small error hierarchy of srr.

Every error a user can cause derives from :class:`SrrError`; the CLI turns it into one line and
an exit code. Library code raises these and never calls ``sys.exit`` or prints.
"""

from __future__ import annotations

__all__ = [
    "BagError",
    "BagReadError",
    "DiskSpaceError",
    "GraphError",
    "InvalidRunError",
    "LiveViewError",
    "PluginError",
    "RunInUseError",
    "RunStopped",
    "ScenarioError",
    "SimulationError",
    "SrrError",
    "StreamError",
    "VideoError",
    "reason",
]


class SrrError(Exception):
    """Base of every error srr raises on purpose."""

    exit_code: int = 2


class ScenarioError(SrrError):
    """A scenario file (or an override of it) is not acceptable.

    ``file`` is the file the offending value came from, ``field`` a dotted path inside it.
    """

    def __init__(self, file: str, field: str, message: str) -> None:
        self.file = file
        self.field = field
        self.message = message
        where = f"{file}: {field}" if field else file
        super().__init__(f"{where}: {message}")


class GraphError(SrrError):
    """An action graph could not be built: unknown node type, attribute or connection."""


class PluginError(SrrError):
    """A system-under-test plug-in could not be loaded or broke its contract."""


class SimulationError(SrrError):
    """The simulated world could not be built or stepped."""

    exit_code = 3


class BagError(SrrError):
    """A recorded bag is missing, truncated or corrupt."""


class BagReadError(BagError):
    """A recording's bytes do not read: what a reader (rosbags, mcap, a decompressor, the
    file system) raised on a damaged, truncated or foreign file, translated where the
    recording is opened (:mod:`harness.bus.bagread`). ``file``: the recording as the user
    named it; the message is ``<file>: <what>: <reason>``."""

    def __init__(self, file: object, what: str, why: str) -> None:
        self.file = str(file)
        self.what = what
        self.why = why
        super().__init__(f"{file}: {what}: {why}")


class DiskSpaceError(SrrError):
    """Not enough free disk space to start a run (its estimated bag size plus the margin)."""


class LiveViewError(SrrError):
    """The live view (``--foxglove``) cannot start: a bad address, a port in use, or the
    foxglove-sdk package missing."""


class VideoError(SrrError):
    """An image or video encoder or decoder failed: an encoder that cannot open (NVENC
    without an NVIDIA GPU), a frame of the wrong size, bytes that do not decode."""


class StreamError(SrrError):
    """A camera stream (RTSP) cannot be served: GStreamer's RTSP server missing, a port in
    use, an address that cannot be bound."""


class InvalidRunError(SrrError):
    """A health gate tripped, so the run's scores cannot be trusted."""

    exit_code = 3


class RunInUseError(SrrError):
    """A run directory is owned by a live process (harness.runlock): it is still being
    written, so it can be neither read nor changed yet."""


class RunStopped(SrrError):
    """Raised from inside a tick to stop the run at that tick boundary, INVALID: the health
    gate ``gate`` trips with this message (e.g. an external ROS 2 output that never came)."""

    exit_code = 3

    def __init__(self, gate: str, message: str) -> None:
        self.gate = gate
        super().__init__(message)


def reason(err: BaseException) -> str:
    """What went wrong, for a one-line message: the exception's text, or its kind when it
    has none (some readers raise bare ``EndOfFile()``)."""
    text = next((line.strip() for line in str(err).splitlines() if line.strip()), "")
    name = type(err).__name__
    if not text:
        return {"EndOfFile": "unexpected end of file (truncated)"}.get(name, name)
    return text if len(text) < 200 else text[:197] + "..."
