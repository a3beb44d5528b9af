"""Where a model file and the files it names are: relative paths and ``package://`` URIs.

A robot entry's model file is written relative to the scenario file that holds the entry (an
include's robots: relative to the include); the files a model file names (a URDF's meshes) are
relative to the model file's directory (:mod:`.model_file` passes it as ``base_dir``).
``package://<pkg>/<path>`` URIs — the form ROS tools write in URDF files — are looked up on the
package path, in order: a directory of it is the package when its name (or its
``package.xml``'s ``<name>``) is ``<pkg>``, else its subdirectory ``<pkg>`` is; failing both in
every directory, each directory is crawled as ROS 1's ``rospack`` crawls ``ROS_PACKAGE_PATH``:
the first folder below it (depth first, in name order) whose ``package.xml`` names ``<pkg>``,
never descending into a package or a folder holding ``CATKIN_IGNORE``, ``COLCON_IGNORE`` or
``AMENT_IGNORE``, nor into hidden ones. The package path is the model block's ``package_paths``
(relative to the same scenario file), then ``SRR_PACKAGE_PATH``, then ``ROS_PACKAGE_PATH``
(``os.pathsep``-separated). ``file://`` URIs are absolute paths, percent-decoded (``%20`` is a
space; ``file://localhost/`` is ``file:///``); a ``file://`` URI of a relative path and any
other scheme (``model://``, ``http://``) are refused, so no file is looked up in the current
directory.

Pure functions of their arguments: the caller passes the environment in.
"""

from __future__ import annotations

import functools
import os
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import unquote

from harness.errors import ScenarioError

__all__ = ["ENV_VARS", "ModelPathError", "ModelSource", "PackagePath", "resolve_uri"]


@dataclass(frozen=True)
class ModelSource:
    """Where a model file was named: the scenario file (as shown to the user), the field of
    the entry that names it (``robots[1]``, ``world``), the directory its relative paths
    start from, and the environment (for ``SRR_PACKAGE_PATH`` / ``ROS_PACKAGE_PATH``).
    ``origin``: the file (or ``--set``) that gave a field inside the entry, for errors about
    it (default: ``scenario_file``)."""

    scenario_file: str
    field: str
    base_dir: Path
    environ: Mapping[str, str]
    origin: Callable[[str], str] | None = None

    def error(self, sub: str, message: str) -> ScenarioError:
        field = f"{self.field}.{sub}"
        file = self.origin(field) if self.origin is not None else self.scenario_file
        return ScenarioError(file, field, message)

    def warning(self, sub: str, message: str) -> str:
        """The ``file: field: message`` line of a warning about ``sub``, as :meth:`error`
        would name it."""
        return str(self.error(sub, message))

#: Environment variables that extend the package path, in lookup order.
ENV_VARS = ("SRR_PACKAGE_PATH", "ROS_PACKAGE_PATH")
_PACKAGE_NAME = re.compile(r"<name>\s*([^<\s]+)\s*</name>")


class ModelPathError(Exception):
    """A path or URI that does not lead to a file (the message says what was tried)."""


@dataclass(frozen=True)
class PackagePath:
    """The directories ``package://`` URIs are looked up in, in order."""

    dirs: tuple[Path, ...]

    @classmethod
    def of(cls, base_dir: Path, package_paths: Sequence[str],
           environ: Mapping[str, str]) -> PackagePath:
        """``package_paths`` (relative to ``base_dir``), then the environment's."""
        dirs = [base_dir / p for p in package_paths]
        for var in ENV_VARS:
            dirs += [Path(p) for p in environ.get(var, "").split(os.pathsep) if p.strip()]
        return cls(tuple(dirs))

    def find(self, package: str) -> Path | None:
        """The directory of ``package``, or None (see the module doc)."""
        for d in self.dirs:
            if d.is_dir() and (d.name == package or _declared_name(d) == package):
                return d
            sub = d / package
            if sub.is_dir():
                return sub
        for d in self.dirs:
            found = _crawled(d).get(package)
            if found is not None:
                return found
        return None

    def describe(self) -> str:
        shown = ", ".join(str(d) for d in self.dirs)
        return f"package path: {shown}" if shown else (
            "the package path is empty: set the model's package_paths, SRR_PACKAGE_PATH or "
            "ROS_PACKAGE_PATH")


_IGNORE = ("CATKIN_IGNORE", "COLCON_IGNORE", "AMENT_IGNORE")


@functools.lru_cache(maxsize=64)
def _crawled(root: Path) -> dict[str, Path]:
    """Every package below ``root`` by its ``package.xml`` name (the first found, depth first
    in name order); a package's own folders are not searched for more."""
    found: dict[str, Path] = {}
    for top, dirs, files in os.walk(root):
        here = Path(top)
        if any(name in files for name in _IGNORE):
            dirs[:] = []
            continue
        if "package.xml" in files and here != root:
            name = _declared_name(here)
            if name is not None:
                found.setdefault(name, here)
            dirs[:] = []
            continue
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
    return found


def _declared_name(directory: Path) -> str | None:
    manifest = directory / "package.xml"
    if not manifest.is_file():
        return None
    try:
        found = _PACKAGE_NAME.search(manifest.read_text(encoding="utf-8", errors="replace"))
    except OSError:
        return None
    return found.group(1) if found else None


_SCHEME = re.compile(r"([A-Za-z][A-Za-z0-9+.-]+)://")


def resolve_uri(uri: str, base_dir: Path, packages: PackagePath) -> Path:
    """The file ``uri`` names: ``package://pkg/path``, ``file:///abs/path``, an absolute path,
    or a path relative to ``base_dir``. Raises :class:`ModelPathError` when a package is not
    on the package path, for a ``file://`` URI of a relative path and for another scheme;
    whether the file exists is the caller's to check."""
    text = uri.strip()
    if text.startswith("package://"):
        package, _, rest = text[len("package://"):].partition("/")
        if not package or not rest:
            raise ModelPathError(f"{uri!r} is not a package://<package>/<path> URI")
        root = packages.find(package)
        if root is None:
            raise ModelPathError(f"package {package!r} of {uri!r} not found "
                                 f"({packages.describe()})")
        return root / rest
    if text.startswith("file://"):
        rest = text[len("file://"):]
        if rest.startswith("localhost/"):  # RFC 8089: file://localhost/abs is file:///abs
            rest = rest[len("localhost"):]
        path = Path(unquote(rest))
        if not path.is_absolute():  # file://rel/x would be read from the current directory
            raise ModelPathError(f"{uri!r} is not a file:// URI of an absolute path (write "
                                 "file:///abs/path, or the relative path without file://)")
        return path
    scheme = _SCHEME.match(text)
    if scheme:
        raise ModelPathError(f"{uri!r}: {scheme.group(1)}:// URIs are not read (write a "
                             "package://<package>/<path> or file:///abs/path URI, or a path)")
    path = Path(text)
    return path if path.is_absolute() else base_dir / path
