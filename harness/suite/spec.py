"""What a suite runs: scenario files, folders of them, and suite files, as checked entries.

A suite file (``suite.yaml``) is recognised by its ``scenarios:`` list::

    suite: nightly                    # the suite's name (default "srr suite")
    defaults: {repeat: 1, timeout: 600}
    scenarios:
      - scenarios/forklift_warehouse.yaml           # a path, relative to the suite file
      - path: scenarios/dock_worker_crossing.yaml
        name: crossing_speeds                       # unique in the suite (default: scenario name)
        repeat: 3
        timeout: 120                                # wall-clock seconds per run
        set: {duration: 12}                         # --set overrides (mapping or KEY=VALUE list)
        sweep: {workers.0.speed: [0.6, 1.0, 1.4]}   # replaces the scenario's own sweep

Precedence for ``repeat`` and ``timeout``: the entry's value, then the command line's
(``--repeat``, ``--timeout``), then the suite file's ``defaults``, then 1 repeat and no timeout.
A folder contributes its top-level ``*.yaml`` scenario files (sorted; suite files and include
fragments in it are skipped). Every error names the file and the field.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from harness import yamlio
from harness.errors import ScenarioError, SrrError
from harness.scenario import load_scenario, parse_override
from harness.suite.sweep import SweepParam, parse_sweep

__all__ = ["Entry", "SuiteSpec", "is_suite_file", "load_suite"]


@dataclass(frozen=True)
class Entry:
    """One scenario of the suite. ``sweep_source`` names where the sweep was declared."""

    name: str
    scenario: str  # the scenario's ``name:``
    scenario_file: str
    baseline: str  # the scenario's baseline name (points append @<label>)
    repeat: int
    timeout_s: float | None
    overrides: tuple[str, ...]
    sweep: tuple[SweepParam, ...]
    sweep_source: str
    declared_in: str  # the suite file and entry index, or the path given


@dataclass(frozen=True)
class SuiteSpec:
    name: str
    entries: tuple[Entry, ...]


def _read(path: Path) -> Any:
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SrrError(f"{path}: no such file or folder") from None
    except (OSError, UnicodeDecodeError) as err:
        raise SrrError(f"{path}: cannot be read ({err})") from err
    try:
        return yamlio.load(text)
    except yamlio.DuplicateKeyError as err:
        raise ScenarioError(str(path), err.field, f"set twice (lines {err.first_line} and "
                            f"{err.line}): remove one") from err
    except yaml.YAMLError as err:
        raise ScenarioError(str(path), "", f"not valid YAML: {yamlio.describe(err)}") from err


def is_suite_file(data: Any) -> bool:
    return isinstance(data, Mapping) and isinstance(data.get("scenarios"), list)


def _is_scenario(data: Any) -> bool:
    return isinstance(data, Mapping) and "name" in data and not is_suite_file(data)


#: More repeats of one scenario than this is a typo (and would not fit in memory as runs).
MAX_REPEAT = 1000


def _count(value: Any, file: str, field: str, *, integer: bool) -> Any:
    ok = (isinstance(value, int) if integer else isinstance(value, (int, float))) \
        and not isinstance(value, bool) and math.isfinite(min(value, math.inf)) and value > 0
    if not ok:
        kind = "a whole number" if integer else "a number of seconds"
        raise ScenarioError(file, field, f"expected {kind} > 0, got {value!r}")
    if integer and value > MAX_REPEAT:
        raise ScenarioError(file, field, f"at most {MAX_REPEAT} repeats, got {value!r}")
    return value


def _overrides(raw: Any, file: str, field: str) -> tuple[str, ...]:
    if raw is None:
        return ()
    if isinstance(raw, Mapping):
        items = [f"{k}={yamlio.dump(v, default_flow_style=True).strip().removesuffix('...')}"
                 .strip() for k, v in raw.items()]
    elif isinstance(raw, list) and all(isinstance(x, str) for x in raw):
        items = list(raw)
    else:
        raise ScenarioError(file, field, "expected a mapping of paths to values or a list of "
                            "KEY=VALUE strings")
    for i, text in enumerate(items):
        try:
            parse_override(text)
        except ScenarioError as err:
            raise ScenarioError(file, f"{field}[{i}]", err.message) from None
    return tuple(items)


@dataclass(frozen=True)
class _Defaults:
    repeat: int | None
    timeout_s: float | None


_ENTRY_KEYS = frozenset({"path", "name", "repeat", "timeout", "set", "sweep"})


def _entry(raw: Any, base: Path, file: str, field: str, cli: _Defaults,
           suite: _Defaults) -> Entry:
    if isinstance(raw, str):
        raw = {"path": raw}
    if not isinstance(raw, Mapping):
        raise ScenarioError(file, field, "expected a scenario path or a mapping with `path:`")
    unknown = sorted(set(raw) - _ENTRY_KEYS)
    if unknown:
        raise ScenarioError(file, f"{field}.{unknown[0]}",
                            f"unknown key (expected one of {', '.join(sorted(_ENTRY_KEYS))})")
    path = raw.get("path")
    if not isinstance(path, str) or not path:
        raise ScenarioError(file, f"{field}.path", "expected the path of a scenario file")
    scenario_file = base / path
    try:
        is_file = scenario_file.is_file()
    except OSError as err:  # a name too long for the file system
        raise ScenarioError(file, f"{field}.path", f"cannot read {path!r}: "
                            f"{err.strerror or err}") from None
    if not is_file:
        raise ScenarioError(file, f"{field}.path", f"no such file: {scenario_file}")
    repeat = raw.get("repeat")
    repeat = (_count(repeat, file, f"{field}.repeat", integer=True) if repeat is not None
              else cli.repeat or suite.repeat or 1)
    timeout = raw.get("timeout")
    timeout_s = (float(_count(timeout, file, f"{field}.timeout", integer=False))
                 if timeout is not None else cli.timeout_s or suite.timeout_s)
    overrides = _overrides(raw.get("set"), file, f"{field}.set")
    name = raw.get("name")
    if name is not None and (not isinstance(name, str) or not _safe_name(name)):
        raise ScenarioError(file, f"{field}.name", "expected a name of letters, digits, '_', "
                            f"'-' and '.', got {name!r}")
    try:
        return _checked(str(scenario_file), overrides, repeat=repeat, timeout_s=timeout_s,
                        name=name, sweep_raw=raw.get("sweep"), has_sweep="sweep" in raw,
                        sweep_file=file, sweep_field=f"{field}.sweep",
                        declared_in=f"{file}: {field}")
    except ScenarioError as err:
        if err.file != "--set":
            raise
        raise ScenarioError(file, f"{field}.set", f"{err.field}: {err.message}") from None


def _safe_name(name: str) -> bool:
    return bool(name) and name not in (".", "..") and all(
        c.isalnum() or c in "_-." for c in name)


def _checked(scenario_file: str, overrides: tuple[str, ...], *, repeat: int,
             timeout_s: float | None, name: str | None, sweep_raw: Any, has_sweep: bool,
             sweep_file: str, sweep_field: str, declared_in: str) -> Entry:
    """Load the scenario once (schema, includes, overrides) to learn its name and sweep."""
    sc = load_scenario(scenario_file, [parse_override(o) for o in overrides])
    if has_sweep:
        sweep, source = parse_sweep(sweep_raw, sweep_file, sweep_field), sweep_file
    else:
        sweep, source = parse_sweep(sc.sweep, scenario_file, "sweep"), scenario_file
    if name is None and not _safe_name(sc.name):
        raise ScenarioError(scenario_file, "name", "cannot name a suite entry (letters, digits, "
                            "'_', '-' and '.'); give the entry a `name:` in the suite file")
    return Entry(name=name or sc.name, scenario=sc.name, scenario_file=scenario_file,
                 baseline=sc.baseline or sc.name, repeat=int(repeat), timeout_s=timeout_s,
                 overrides=overrides, sweep=sweep, sweep_source=source, declared_in=declared_in)


def _suite_file(path: Path, data: Mapping[str, Any], cli: _Defaults) -> tuple[str, list[Entry]]:
    file = str(path)
    unknown = sorted(set(data) - {"suite", "defaults", "scenarios"})
    if unknown:
        raise ScenarioError(file, unknown[0], "unknown key (expected suite, defaults, scenarios)")
    name = data.get("suite", "srr suite")
    if not isinstance(name, str) or not name.strip():
        raise ScenarioError(file, "suite", f"expected the suite's name, got {name!r}")
    raw_def = data.get("defaults") or {}
    if not isinstance(raw_def, Mapping):
        raise ScenarioError(file, "defaults", "expected a mapping (repeat, timeout)")
    bad = sorted(set(raw_def) - {"repeat", "timeout"})
    if bad:
        raise ScenarioError(file, f"defaults.{bad[0]}", "unknown key (expected repeat, timeout)")
    suite = _Defaults(
        _count(raw_def["repeat"], file, "defaults.repeat", integer=True)
        if "repeat" in raw_def else None,
        float(_count(raw_def["timeout"], file, "defaults.timeout", integer=False))
        if "timeout" in raw_def else None)
    if not data["scenarios"]:
        raise ScenarioError(file, "scenarios", "the suite lists no scenarios")
    entries = [_entry(raw, path.parent, file, f"scenarios[{i}]", cli, suite)
               for i, raw in enumerate(data["scenarios"])]
    return name, entries


def load_suite(paths: Sequence[str | Path], *, repeat: int | None = None,
               timeout_s: float | None = None) -> SuiteSpec:
    """Expand ``paths`` (scenario files, folders of them, suite files) into checked entries.

    Raises :class:`~harness.errors.SrrError` (exit 2) naming the file and field of the first
    problem; nothing has run then."""
    if not paths:
        raise SrrError("srr suite: no scenario files, folders or suite files given")
    if repeat is not None:
        _count(repeat, "--repeat", "", integer=True)
    if timeout_s is not None:
        _count(timeout_s, "--timeout", "", integer=False)
    cli = _Defaults(repeat, timeout_s)
    names: list[str] = []
    entries: list[Entry] = []
    for given in paths:
        path = Path(given)
        if path.is_dir():
            files = sorted(p for p in (*path.glob("*.yaml"), *path.glob("*.yml")) if p.is_file())
            found = [p for p in files if _is_scenario(_read(p))]
            if not found:
                raise SrrError(f"{path}: the folder holds no scenario files (*.yaml with a "
                               "`name:`)")
            entries += [_checked(str(p), (), repeat=cli.repeat or 1, timeout_s=cli.timeout_s,
                                 name=None, sweep_raw=None, has_sweep=False, sweep_file=str(p),
                                 sweep_field="sweep", declared_in=str(p)) for p in found]
            continue
        data = _read(path)
        if is_suite_file(data):
            name, more = _suite_file(path, data, cli)
            names.append(name)
            entries += more
        elif _is_scenario(data):
            entries.append(_checked(str(path), (), repeat=cli.repeat or 1,
                                    timeout_s=cli.timeout_s, name=None, sweep_raw=None,
                                    has_sweep=False, sweep_file=str(path), sweep_field="sweep",
                                    declared_in=str(path)))
        else:
            raise ScenarioError(str(path), "", "neither a scenario (no `name:`) nor a suite "
                                "file (no `scenarios:` list)")
    seen: dict[str, Entry] = {}
    for e in entries:
        if e.name in seen:
            raise ScenarioError(e.declared_in, "name", f"{e.name!r} is already used by "
                                f"{seen[e.name].declared_in}; give one entry another `name:` in "
                                "a suite file")
        seen[e.name] = e
    return SuiteSpec(names[0] if len(names) == 1 else "srr suite", tuple(entries))
