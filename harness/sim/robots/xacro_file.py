"""Expand a ``.xacro`` robot description into URDF text with the ``xacro`` package.

``xacro`` (the ROS macro processor, from PyPI) does the expansion: properties, macros,
conditionals, ``xacro:include``, ``$(arg name)`` with the scenario's ``args`` and the file's
``xacro:arg`` defaults. ``$(find pkg)`` is answered from srr's package path — the same
directories ``package://`` URIs are looked up in (:class:`~.paths.PackagePath`), not ROS's
ament index — and is the package's directory.

``xacro`` keeps its state in module globals (the files it read, the arguments, the ``find``
function), so one expansion runs at a time, under a lock, and the ``find`` hook is put back
afterwards.

Errors are :class:`XacroError` with a one-line message.
"""

from __future__ import annotations

import re
import threading
import xml.parsers.expat
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import xacro
from xacro import substitution_args

from harness.sim.robots.paths import PackagePath
from harness.validation import close_match

__all__ = ["Expanded", "UnknownXacroArg", "XacroError", "XacroInputs", "expand_xacro"]

_LOCK = threading.Lock()


class XacroError(Exception):
    """A xacro file that cannot be expanded; the message is one line."""


class UnknownXacroArg(XacroError):
    """An argument given (``args``) that the file neither declares (``<xacro:arg>``) nor
    reads (``$(arg NAME)``): a typo, whose value xacro would silently never use."""

    def __init__(self, name: str, message: str) -> None:
        self.name = name
        super().__init__(message)


class _ArgTable(dict[str, str]):
    """xacro's table of arguments, noting every name xacro looks up in it: an
    ``<xacro:arg>`` it evaluates (to set its default) and a ``$(arg NAME)`` it substitutes."""

    def __init__(self, given: Mapping[str, str]) -> None:
        super().__init__(given)
        self.looked_up: set[str] = set()

    def __contains__(self, key: object) -> bool:
        if isinstance(key, str):
            self.looked_up.add(key)
        return super().__contains__(key)

    def __getitem__(self, key: str) -> str:
        self.looked_up.add(key)
        return super().__getitem__(key)


def _declared(files: Iterable[Path]) -> set[str]:
    """The names of the ``<xacro:arg>`` elements in ``files``, as xacro parses them (also
    those in a branch the expansion did not take)."""
    names: set[str] = set()
    for file in files:
        try:
            doc: Any = xacro.parse(file.read_text(encoding="utf-8"))
        except (OSError, ValueError, xml.parsers.expat.ExpatError):  # a YAML file xacro read
            continue
        names |= {str(el.getAttribute("name")) for el in doc.getElementsByTagName("xacro:arg")}
    return names


def _check_args(args: Mapping[str, str], table: _ArgTable, files: Iterable[Path]) -> None:
    """Refuse the first of ``args`` the file neither declares nor reads."""
    known = table.looked_up | _declared(files)
    for name in args:
        if name not in known:
            close = close_match(name, known)
            hint = f" (did you mean {close!r}?)" if close else ""
            raise UnknownXacroArg(name, f"declares no argument {name!r}{hint}; its arguments: "
                                  f"{', '.join(sorted(known)) or 'none'}")


@dataclass(frozen=True)
class XacroInputs:
    """What an expansion read besides the main file: every file it included (``xacro:include``,
    ``xacro.load_yaml``), in the order it read them, each once; and the arguments it was
    given (sorted by name)."""

    files: tuple[Path, ...]
    args: tuple[tuple[str, str], ...]


@dataclass(frozen=True)
class Expanded:
    """The URDF text a xacro file expands to, and what it was made from."""

    text: str
    inputs: XacroInputs


def _one_line(text: str) -> str:
    flat = " ".join(part.strip() for part in text.splitlines() if part.strip())
    return flat if len(flat) <= 300 else flat[:297] + "..."


@contextmanager
def _find_hook(find: Callable[[str], str]) -> Iterator[None]:
    """``$(find pkg)`` (and ``find`` in ``$(eval ...)``) answered by ``find`` for the block."""
    saved = substitution_args._eval_find, substitution_args._eval_dict["find"]
    substitution_args._eval_find = find
    substitution_args._eval_dict["find"] = find
    try:
        yield
    finally:
        substitution_args._eval_find, substitution_args._eval_dict["find"] = saved


_CLASS_PREFIX = re.compile(r"^<class '[\w.]+'>: ")


def _describe(err: BaseException) -> str:
    """xacro's message without the repeats it adds: a wrapped exception's class and text
    when its own message already says them, an OSError's errno form."""
    if not isinstance(err, xacro.XacroException):
        return str(err)
    msg = _CLASS_PREFIX.sub("", str(err.args[0]) if err.args and err.args[0] else "")
    inner = err.exc
    parts = [msg]
    if inner is not None and not isinstance(inner, OSError) and str(inner) not in msg:
        parts.append(str(inner))
    if err.suffix:
        parts.append(str(err.suffix))
    return " ".join(p for p in parts if p)


def _missing_arg(err: BaseException) -> str | None:
    """The name of the ``$(arg ...)`` without a value behind ``err``, if that is its cause."""
    seen: set[int] = set()
    todo: list[BaseException | None] = [err]
    while todo:
        cur = todo.pop()
        if cur is None or id(cur) in seen:
            continue
        seen.add(id(cur))
        if isinstance(cur, substitution_args.ArgException):
            return str(cur)
        exc = getattr(cur, "exc", None)
        todo += [exc if isinstance(exc, BaseException) else None, cur.__cause__,
                 cur.__context__]
    return None


def expand_xacro(path: Path, args: Mapping[str, str], packages: PackagePath) -> Expanded:
    """Run xacro on ``path`` with ``args`` (``$(arg name)``); ``$(find pkg)`` is looked up in
    ``packages``. Raises :class:`XacroError` (:class:`UnknownXacroArg` for an argument of
    ``args`` the file neither declares nor reads)."""
    if not path.exists():
        raise XacroError("file not found")
    if not path.is_file():
        raise XacroError("is not a file")
    main = path.resolve()
    unknown: list[str] = []

    def find(package: str) -> str:
        root = packages.find(package)
        if root is None:
            unknown.append(package)
            raise XacroError(f"$(find {package}): package {package!r} not found "
                             f"({packages.describe()})")
        return str(root.resolve())

    with _LOCK, _find_hook(find):
        xacro.all_includes = []
        table = _ArgTable(args)
        try:
            doc: Any = xacro.process_file(str(main), mappings=table, verbosity=0)
            text = str(doc.toxml())
        except xml.parsers.expat.ExpatError as err:
            where = xacro.filestack[-1] if xacro.filestack else main
            raise XacroError(f"not well-formed XML ({where}): {err}") from err
        except RecursionError as err:
            raise XacroError("xacro cannot expand it: too deep a recursion (a macro that "
                             "calls itself?)") from err
        except (xacro.XacroException, OSError, ValueError, TypeError, NameError,
                KeyError, AttributeError, SyntaxError, RuntimeError) as err:
            # RuntimeError: a tag without a required attribute (xacro:arg without default)
            name = _missing_arg(err)
            if name is not None:
                raise XacroError(f"$(arg {name}) has no value: give it in the model's args "
                                 f"(or a default in <xacro:arg name=\"{name}\">)") from err
            if unknown:
                raise XacroError(f"$(find {unknown[0]}): package {unknown[0]!r} not found "
                                 f"({packages.describe()})") from err
            where = xacro.filestack[-1] if xacro.filestack else None
            shown = f" (in {where})" if where and Path(where).resolve() != main else ""
            raise XacroError(f"xacro cannot expand it: {_one_line(_describe(err))}{shown}") \
                from err
        read = [Path(f).resolve() for f in xacro.all_includes]
        _check_args(args, table, [main, *read])
    files: list[Path] = []
    for file in read:
        if file != main and file not in files and file.is_file():
            files.append(file)
    return Expanded(text, XacroInputs(tuple(files), tuple(sorted(args.items()))))
