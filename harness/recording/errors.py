"""The recording layer's errors: a recorded bag that is missing, truncated, corrupt or does not
read. Both derive from :class:`~harness.errors.SrrError` (one line, exit 2)."""

from __future__ import annotations

from harness.errors import SrrError

__all__ = ["BagError", "BagReadError", "NothingRecorded"]


class BagError(SrrError):
    """A recorded bag is missing, truncated or corrupt."""


class BagReadError(BagError):
    """A recording's bytes do not read: what a reader (rosbags, mcap, a decompressor, the
    file system) raised on a damaged, truncated or foreign file, translated where the
    recording is opened (:mod:`harness.recording.bagread`). ``file``: the recording as the user
    named it; the message is ``<file>: <what>: <reason>``."""

    def __init__(self, file: object, what: str, why: str) -> None:
        self.file = str(file)
        self.what = what
        self.why = why
        super().__init__(f"{file}: {what}: {why}")


class NothingRecorded(BagError):
    """An MCAP file cut short before its first chunk was complete: it holds no message, so
    there is nothing to recover (``srr recover`` refuses it rather than write an empty bag).
    ``mcap``: the file; ``size``: its length in bytes; ``message``: what to say instead of the
    default line."""

    def __init__(self, mcap: object, size: int, message: str | None = None) -> None:
        self.mcap = str(mcap)
        self.size = size
        super().__init__(message or f"{mcap}: nothing was recorded: no complete chunk ({size} "
                         "bytes, cut before its first chunk was written); nothing to recover")
