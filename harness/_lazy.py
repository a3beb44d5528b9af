"""Lazy package exports (PEP 562): a package's ``__init__`` names what it exports and where
each name lives, and the submodule is imported on first use of the name.

Importing a package then costs nothing but its ``__init__``; ``import harness.metrics``
loads no recording, graph or MuJoCo code until one of its names is used. The ``__init__``
also imports the same names under ``typing.TYPE_CHECKING``, so type checkers see them.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["lazy_exports"]


def lazy_exports(package: str, where: Mapping[str, str],
                 namespace: dict[str, Any]) -> tuple[Callable[[str], Any],
                                                     Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for ``package``: ``where`` maps each exported name to the
    module that defines it: a submodule's name relative to the package (``"bus"``), or an
    absolute module name (``"harness.tf_tree"``). A name, once
    looked up, is stored in the package's ``namespace`` (its ``globals()``)."""

    def __getattr__(name: str) -> Any:
        sub = where.get(name)
        if sub is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module = sub if sub.startswith("harness.") else f"{package}.{sub}"
        value = getattr(importlib.import_module(module), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted({*namespace, *where})

    return __getattr__, __dir__
