"""``--set KEY=VALUE`` overrides: parsing one, and applying them to a scenario's raw mapping."""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

import yaml

from harness import yamlio
from harness.errors import ScenarioError

__all__ = ["apply_overrides", "dotted", "parse_override"]


_INDEX = re.compile(r"\[(-?\d+)\]")


def dotted(path: str) -> str:
    """``workers[0].speed``, as every error message writes a list item, as ``--set`` paths
    write it: ``workers.0.speed``."""
    return _INDEX.sub(r".\1", path)


def parse_override(text: str) -> tuple[str, Any]:
    """``"robots.forklift.spawn.position=[1, 2, 0]"`` → (path, parsed YAML value)."""
    key, sep, value = text.partition("=")
    key = dotted(key.strip())
    if not sep or not key:
        raise ScenarioError("--set", text, "expected KEY=VALUE")
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
    (``systems_under_test.teleop.params.rate_hz`` → ``systems_under_test[0].params.rate_hz``)."""
    fields = []
    for key, value in overrides:
        parts = key.split(".")
        node: Any = data
        field = ""
        for depth, part in enumerate(parts):
            last = depth == len(parts) - 1
            where = ".".join(parts[: depth + 1])
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
                    node = node[part]
            else:
                raise ScenarioError("--set", where, "cannot set a field inside a "
                                    f"{type(node).__name__}")
        fields.append(field)
    return fields


def _list_index(items: list[Any], part: str) -> int | None:
    if part.isdigit():  # an index from 0, as error messages count (no Python negatives)
        idx = int(part)
        return idx if idx < len(items) else None
    for i, item in enumerate(items):
        if isinstance(item, dict) and item.get("name") == part:
            return i
    return None

