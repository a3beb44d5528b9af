"""``--set KEY=VALUE`` overrides: parsing one, and applying them to a scenario's raw mapping."""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

import yaml

from harness import yamlio
from harness.errors import ScenarioError

__all__ = ["apply_overrides", "dotted", "parse_override", "split_key"]


_INDEX = re.compile(r"\[(-?\d+)\]")
_QUOTED = re.compile(r"(\"[^\"]*\"|'[^']*')")


def dotted(path: str) -> str:
    """``workers[0].speed``, as every error message writes a list item, as ``--set`` paths
    write it: ``workers.0.speed`` (a quoted key is left as it is)."""
    parts = _QUOTED.split(path)  # the quoted keys at the odd places
    return "".join(part if i % 2 else _INDEX.sub(r".\1", part) for i, part in enumerate(parts))


def split_key(key: str) -> list[str]:
    """The keys of a ``--set`` path, split at its dots; a key in quotes is one key, dots and
    all: ``scoring.tolerances."perception.position_error.p95".abs`` → ``scoring``, ``tolerances``,
    ``perception.position_error.p95``, ``abs``."""
    parts: list[str] = []
    i = 0
    while i <= len(key):
        if i < len(key) and key[i] in "\"'":
            end = key.find(key[i], i + 1)
            if end < 0:
                raise ScenarioError("--set", key, f"a key opened with {key[i]} is not closed")
            if end + 1 < len(key) and key[end + 1] != ".":
                raise ScenarioError("--set", key, "a quoted key is a whole key: write a dot "
                                    "after its closing quote")
            parts.append(key[i + 1:end])
            i = end + 2
        else:
            end = key.find(".", i)
            end = len(key) if end < 0 else end
            parts.append(key[i:end])
            i = end + 1
    return parts


def parse_override(text: str) -> tuple[str, Any]:
    """``"robots.forklift.spawn.position=[1, 2, 0]"`` → (path, parsed YAML value)."""
    key, sep, value = text.partition("=")
    key = dotted(key.strip())
    if not sep or not key:
        raise ScenarioError("--set", text, "expected KEY=VALUE")
    split_key(key)  # a quote not closed is said now
    if key.endswith("+"):  # '+' extends an include's list in a scenario file
        raise ScenarioError("--set", key, "--set replaces a value (robots=[...]) or one field "
                            "(robots.0.spawn.position=...); to add to a list, write `robots+:` "
                            "in a scenario file that includes this one")
    try:
        parsed = yamlio.load(value) if value.strip() else ""
    except yaml.YAMLError as err:
        raise ScenarioError("--set", key, f"value is not valid YAML ({yamlio.describe(err)}): "
                            f"{value!r}") from err
    return key, parsed


def apply_overrides(data: dict[str, Any], overrides: Sequence[tuple[str, Any]]) -> list[str]:
    """Apply dotted-path overrides in place. List items can be addressed by index or ``name``.
    Returns the field path each override set, as error messages write it
    (``systems_under_test.teleop.params.rate_hz`` → ``systems_under_test[0].params.rate_hz``):
    the first key it had to make where the mapping had none (everything below it is the
    override's), else the field it set."""
    fields = []
    for key, value in overrides:
        parts = split_key(key)
        node: Any = data
        field = made = ""
        for depth, part in enumerate(parts):
            last = depth == len(parts) - 1
            where = ".".join(f'"{p}"' if "." in p else p for p in parts[: depth + 1])
            if isinstance(node, list):
                idx = _list_index(node, part)
                if idx is None:
                    raise ScenarioError("--set", where, "no list item with that index or name")
                field += f"[{idx}]"
                if last:
                    node[idx] = value
                else:
                    node = node[idx]
            elif isinstance(node, dict):
                field = f"{field}.{part}" if field else part
                if last:
                    node[part] = value
                else:
                    if part not in node or node[part] is None:
                        node[part] = {}
                        made = made or field
                    node = node[part]
            else:
                raise ScenarioError("--set", where, "cannot set a field inside a "
                                    f"{type(node).__name__}")
        fields.append(made or field)
    return fields


def _list_index(items: list[Any], part: str) -> int | None:
    if part.isdigit():  # an index from 0, as error messages count (no Python negatives)
        idx = int(part)
        return idx if idx < len(items) else None
    for i, item in enumerate(items):
        if isinstance(item, dict) and item.get("name") == part:
            return i
    return None

