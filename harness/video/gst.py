"""GStreamer and its RTSP server through PyGObject (``gi``), loaded on first use.

Debian ships PyGObject for its own Python (``python3-gi``, in ``/usr/lib/python3/
dist-packages``), and a virtual environment made from that Python does not see it. When
``import gi`` fails, :func:`load` looks for a ``gi`` package built for this interpreter's
version in the system's ``dist-packages`` directories and imports that one package from
there (nothing else from those directories is put on the path). ``SRR_GI_PATH`` names another
directory to look in first.
"""

from __future__ import annotations

import importlib
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness.video.errors import StreamError

__all__ = ["APT_PACKAGES", "Gst", "gi_search_path", "load"]

#: What Debian/Ubuntu need for the RTSP streams (PyGObject, the RTSP server's typelib, and the
#: appsrc and rtph264pay elements).
APT_PACKAGES = ("python3-gi", "gir1.2-gst-rtsp-server-1.0", "gstreamer1.0-plugins-base",
                "gstreamer1.0-plugins-good")
_ELEMENTS = ("appsrc", "rtph264pay")


@dataclass(frozen=True)
class Gst:
    """The loaded modules: ``Gst``, ``GstRtspServer`` and ``GLib`` from ``gi.repository``."""

    Gst: Any
    GstRtspServer: Any
    GLib: Any


_loaded: Gst | None = None


def gi_search_path() -> list[Path]:
    """Directories :func:`load` looks in for the system's ``gi`` package."""
    ver = f"{sys.version_info.major}.{sys.version_info.minor}"
    dirs = [os.environ.get("SRR_GI_PATH", ""), "/usr/lib/python3/dist-packages",
            f"/usr/lib/python{ver}/dist-packages", f"/usr/lib/python{ver}/site-packages",
            f"/usr/lib64/python{ver}/site-packages"]
    return [Path(d) for d in dirs if d]


def _import_gi() -> Any:
    try:
        return importlib.import_module("gi")
    except ImportError:
        pass
    tag = f"cpython-{sys.version_info.major}{sys.version_info.minor}"
    for d in gi_search_path():
        if not any((d / "gi").glob(f"_gi.{tag}*.so")):
            continue
        sys.path.append(str(d))
        try:
            return importlib.import_module("gi")
        except ImportError:
            continue
        finally:
            sys.path.remove(str(d))
    return None


def _missing(what: str) -> StreamError:
    return StreamError(f"RTSP streams need {what} (Debian/Ubuntu: apt-get install "
                       f"{' '.join(APT_PACKAGES)})")


def load() -> Gst:
    """Import and initialise GStreamer and its RTSP server (once per process), or raise
    :class:`~harness.video.errors.StreamError` saying what to install."""
    global _loaded
    if _loaded is not None:
        return _loaded
    gi = _import_gi()
    if gi is None:
        raise _missing(f"PyGObject (gi) for Python {sys.version_info.major}."
                       f"{sys.version_info.minor}")
    try:
        gi.require_version("Gst", "1.0")
        gi.require_version("GstRtspServer", "1.0")
        from gi.repository import GLib, GstRtspServer
        from gi.repository import Gst as _Gst
    except (ValueError, ImportError) as err:
        raise _missing(f"GStreamer's RTSP server ({err})") from err
    _Gst.init(None)
    absent = [e for e in _ELEMENTS if _Gst.ElementFactory.find(e) is None]
    if absent:
        raise _missing(f"the GStreamer elements {', '.join(absent)}")
    _loaded = Gst(_Gst, GstRtspServer, GLib)
    return _loaded
