"""The video layer's errors: an encoder or decoder that fails, a camera stream that cannot be
served. Both derive from :class:`~harness.errors.SrrError` (one line, exit 2)."""

from __future__ import annotations

from harness.errors import SrrError

__all__ = ["StreamError", "VideoError"]


class VideoError(SrrError):
    """An image or video encoder or decoder failed: an encoder that cannot open (NVENC
    without an NVIDIA GPU), a frame of the wrong size, bytes that do not decode."""


class StreamError(SrrError):
    """A camera stream (RTSP) cannot be served: GStreamer's RTSP server missing, a port in
    use, an address that cannot be bound."""
