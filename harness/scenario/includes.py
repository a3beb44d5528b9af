"""Reading a scenario file and merging its ``include:`` files (``key+`` extends an included
value), remembering which file each top-level key came from (:class:`Origins`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from harness import yamlio
from harness.errors import ScenarioError, reason
from harness.scenario.origins import origin_of

__all__ = ["Origins", "expand_includes", "read_yaml"]


class Origins:
    """Which file each top-level key, or each item of a list extended with ``key+``, came from
    (the scenario file or one of its includes); the loader adds each field a ``--set`` gave
    (``robots[0].spawn.position``: ``--set``)."""

    def __init__(self, default: str) -> None:
        self.default = default
        self.by_key: dict[str, str] = {}

    def file_for(self, path: str) -> str:
        return origin_of(self.by_key, path) or self.default

    def forget(self, key: str) -> None:
        """``key`` is defined anew: drop it and its items' origins."""
        for k in [k for k in self.by_key if k == key or k.startswith(f"{key}[")]:
            del self.by_key[k]


def read_yaml(path: Path, shown: str, field: str = "") -> dict[str, Any]:
    try:
        if not path.exists():
            raise ScenarioError(shown, field, "file not found")
        if path.is_dir():
            raise ScenarioError(shown, field, "is a directory, not a scenario file")
        text = path.read_text(encoding="utf-8")
    except (OSError, ValueError) as err:  # a name too long, a NUL byte, no permission
        why = err.strerror if isinstance(err, OSError) and err.strerror else reason(err)
        raise ScenarioError(shown, field, f"cannot read: {why}") from err
    try:
        data = yamlio.load(text)
    except yamlio.DuplicateKeyError as err:
        raise ScenarioError(shown, err.field, f"set twice (lines {err.first_line} and "
                            f"{err.line}): remove one") from err
    except yaml.YAMLError as err:
        raise ScenarioError(shown, "", f"YAML syntax error at {yamlio.describe(err)}") from err
    if data is None:
        raise ScenarioError(shown, "", "file is empty")
    if not isinstance(data, dict):
        raise ScenarioError(shown, "", f"expected a mapping at the top level, got "
                            f"{type(data).__name__}")
    return data


def expand_includes(path: Path, data: dict[str, Any], origins: Origins) -> dict[str, Any]:
    """Merge top-level ``include:`` files in order; keys in the including file win.

    A key written ``key+`` (in the scenario file or a later include) extends what is there
    instead of replacing it: a list gets the new items appended (an item whose ``name`` is
    already there is refused), a mapping gets the new keys (a key already there is refused).
    """
    raw = data.pop("include", None)
    shown = str(path)
    if raw is None:
        includes: list[Any] = []
    else:
        includes = [raw] if isinstance(raw, str) else raw
        if not isinstance(includes, list) or not all(isinstance(i, str) for i in includes):
            raise ScenarioError(shown, "include", "expected a file name or a list of file names")
    merged: dict[str, Any] = {}
    for i, rel in enumerate(includes):
        field = "include" if isinstance(raw, str) else f"include[{i}]"
        if not rel or "\0" in rel:
            raise ScenarioError(shown, field, f"not a file name: {rel!r}")
        inc_path = (path.parent / rel).resolve()
        inc_shown = str(path.parent / rel)
        try:
            missing = not inc_path.exists()
        except OSError:  # a name the OS refuses: read_yaml says so
            missing = False
        if missing:  # named from the file that includes it
            raise ScenarioError(shown, field, f"{inc_shown}: file not found")
        inc = read_yaml(inc_path, inc_shown, field)
        if "include" in inc:
            raise ScenarioError(inc_shown, "include", "nested includes are not supported")
        inc.pop("format_version", None)
        for key, value in inc.items():
            if str(key).endswith("+"):
                _extend(merged, str(key), value, inc_shown, origins)
                continue
            if key in merged:
                raise ScenarioError(inc_shown, key, f"also defined in {origins.by_key[key]}")
            merged[key] = value
            origins.by_key[key] = inc_shown
    for key in data:
        if str(key).endswith("+") and str(key)[:-1] in data:
            raise ScenarioError(shown, str(key), f"both {str(key)[:-1]!r} and {key!r} are set: "
                                f"use {str(key)[:-1]!r} to replace the included value or "
                                f"{key!r} to extend it")
    for key, value in data.items():
        if str(key).endswith("+"):
            _extend(merged, str(key), value, shown, origins)
            continue
        merged[key] = value
        origins.forget(key)
    return merged


def _extend(merged: dict[str, Any], key: str, value: Any, shown: str,
            origins: Origins) -> None:
    """Apply ``key+: value`` to ``merged`` (see :func:`expand_includes`)."""
    base = key[:-1]
    if base not in merged:  # nothing to extend yet: the value is the first definition
        merged[base] = value
        origins.by_key[base] = shown
        return
    old = merged[base]
    where = origins.file_for(base)
    if isinstance(old, list):
        if not isinstance(value, list):
            raise ScenarioError(shown, key, f"expected a list of items to append to {base!r}, "
                                f"got {value!r}")
        names = {item.get("name"): n for n, item in enumerate(old)
                 if isinstance(item, dict) and item.get("name")}
        for j, item in enumerate(value):
            name = item.get("name") if isinstance(item, dict) else None
            if name and name in names:
                first = origins.file_for(f"{base}[{names[name]}]")
                raise ScenarioError(shown, f"{key}[{j}].name",
                                    f"{base} already has an item named {name!r} (from {first}); "
                                    f"change it with --set {base}.{name}.FIELD=VALUE or replace "
                                    f"the whole list with {base!r}")
            if name:
                names[name] = len(old)
            origins.by_key.setdefault(base, where)
            origins.by_key[f"{base}[{len(old)}]"] = shown
            old.append(item)
        return
    if isinstance(old, dict):
        if not isinstance(value, dict):
            raise ScenarioError(shown, key, f"expected a mapping of entries to add to {base!r}, "
                                f"got {value!r}")
        for k, v in value.items():
            if k in old:
                raise ScenarioError(shown, f"{key}.{k}", f"{base} already has {k!r} (from "
                                    f"{where}); replace the whole mapping with {base!r}")
            old[k] = v
        return
    raise ScenarioError(shown, key, f"only a list or a mapping can be extended; {base!r} is "
                        f"{old!r}")

