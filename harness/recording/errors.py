"""The recording layer's errors: a recorded bag that is missing, truncated, corrupt or does not
read. Both derive from :class:`~harness.errors.SrrError` (one line, exit 2)."""

from __future__ import annotations

from harness.errors import SrrError

__all__ = ["BagError", "BagReadError"]


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
