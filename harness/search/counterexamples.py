"""Counterexamples into a suite (``--add-to-suite SUITE``, with ``--bless --reason TEXT``).

Each counterexample scenario is written beside the searched scenario file (so the paths it
names — models, meshes — resolve as they do for the original), and appended to the suite
file's ``scenarios:`` as ``{path, name}`` (ruamel's round trip keeps the file's comments and
layout; an entry of that name already there is left alone). With ``bless``, the new entries
are first run as a suite with ``--update-baselines`` (the existing bless path), and only
those whose run is valid are added.
"""

from __future__ import annotations

import io
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness.atomic import write_text_atomic
from harness.errors import SrrError
from harness.suite.spec import is_suite_file

__all__ = ["Added", "append_to_suite", "check_suite", "place_beside"]


@dataclass(frozen=True)
class Added:
    name: str
    file: Path
    added: bool  # False: the suite already had an entry of this name


def _round_trip() -> Any:
    from ruamel.yaml import YAML

    y = YAML(typ="rt")
    y.preserve_quotes = True
    y.indent(mapping=2, sequence=4, offset=2)
    y.width = 4096
    return y


def _read_suite(suite: Path) -> tuple[Any, Any]:
    from ruamel.yaml.error import YAMLError

    try:
        text = suite.read_text(encoding="utf-8")
    except OSError as err:
        raise SrrError(f"--add-to-suite {suite}: cannot be read ({err.strerror or err})") \
            from None
    y = _round_trip()
    try:
        doc = y.load(text)
    except YAMLError as err:
        raise SrrError(f"--add-to-suite {suite}: not valid YAML ({str(err).splitlines()[0]})") \
            from None
    if not is_suite_file(doc):
        raise SrrError(f"--add-to-suite {suite}: not a suite file (no `scenarios:` list)")
    return y, doc


def check_suite(suite: Path) -> None:
    """Before the search runs: ``suite`` is a readable suite file."""
    _read_suite(suite)


def place_beside(scenario_file: str, written: Path, name: str) -> Path:
    """Copy the counterexample ``written`` (in the search's output) beside the searched
    scenario file, as ``<name>.yaml``."""
    dest = Path(scenario_file).parent / f"{name}.yaml"
    write_text_atomic(dest, written.read_text(encoding="utf-8"))
    return dest


def append_to_suite(suite: Path, files: Sequence[tuple[str, Path]]) -> list[Added]:
    """Append ``(name, scenario file)`` entries to ``suite``'s ``scenarios:``, paths relative
    to the suite file, keeping its comments; names already listed are skipped."""
    from ruamel.yaml.comments import CommentedMap

    y, doc = _read_suite(suite)
    items = doc["scenarios"]
    names = {str(i.get("name")) for i in items if isinstance(i, Mapping) and i.get("name")}
    out: list[Added] = []
    for name, file in files:
        if name in names:
            out.append(Added(name, file, False))
            continue
        entry = CommentedMap()
        entry["path"] = Path(os.path.relpath(file.resolve(), suite.resolve().parent)).as_posix()
        entry["name"] = name
        entry["repeat"] = 1
        items.append(entry)
        names.add(name)
        out.append(Added(name, file, True))
    buf = io.StringIO()
    y.dump(doc, buf)
    write_text_atomic(suite, buf.getvalue())
    return out

