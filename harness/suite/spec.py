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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from harness import yamlio
from harness.errors import ScenarioError, SrrError
from harness.run.loading import ScenarioLoads
from harness.scenario import parse_override
from harness.scenario.overrides import dotted
from harness.suite.sweep import SweepParam, parse_sweep, varied_path
from harness.validation import validate

__all__ = ["DefaultsFile", "Entry", "EntryFile", "SuiteFile", "SuiteSpec", "is_suite_file",
           "is_suite_path", "load_suite"]


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
    sweep_field: str = "sweep"  # the sweep's field in sweep_source (scenarios[1].sweep)


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


def is_suite_path(path: Path) -> bool:
    """Whether ``path`` is a suite file or a folder of scenarios (what ``srr validate``
    checks as a suite); False for a file that cannot be read or parsed, which the scenario
    loader then names."""
    if path.is_dir():
        return True
    try:
        return is_suite_file(_read(path))
    except SrrError:
        return False


def _is_scenario(data: Any) -> bool:
    return isinstance(data, Mapping) and "name" in data and not is_suite_file(data)


def _yaml_files(folder: Path) -> list[Path]:
    return sorted(p for p in (*folder.glob("*.yaml"), *folder.glob("*.yml")) if p.is_file())


def folder_files(folder: Path) -> tuple[Path, ...]:
    """The files of ``folder`` that ``srr validate FOLDER`` checks one by one: its scenario
    and suite files (``*.yaml``, ``*.yml``, sorted), and those that cannot be read or parsed
    (their check names the problem); fragments that scenarios include (no ``name:``, no
    ``scenarios:``) are left out. None: :class:`~harness.errors.SrrError`."""
    found = []
    for p in _yaml_files(folder):
        try:
            data = _read(p)
        except SrrError:
            found.append(p)
            continue
        if _is_scenario(data) or is_suite_file(data):
            found.append(p)
    if not found:
        raise SrrError(f"{folder}: the folder holds no scenario or suite files (*.yaml with a "
                       "`name:` or a `scenarios:` list)")
    return tuple(found)


#: More repeats of one scenario than this is a typo (and would not fit in memory as runs).
MAX_REPEAT = 1000
#: The ranges of a suite file's ``repeat`` and ``timeout`` (seconds), as field metadata
#: (harness.validation checks them; ``srr schema suite`` says them).
_REPEAT = {"range": (1, MAX_REPEAT, False)}
_TIMEOUT = {"range": (0, None, True)}


def _count(value: Any, file: str, field: str, *, integer: bool) -> Any:
    ok = (isinstance(value, int) if integer else isinstance(value, (int, float))) \
        and not isinstance(value, bool) and math.isfinite(min(value, math.inf)) and value > 0
    if not ok:
        kind = "a whole number" if integer else "a number of seconds"
        raise ScenarioError(file, field, f"expected {kind} > 0, got {value!r}")
    if integer and value > MAX_REPEAT:
        raise ScenarioError(file, field, f"at most {MAX_REPEAT} repeats, got {value!r}")
    return value


def _overrides(raw: Mapping[str, Any] | tuple[str, ...] | None, file: str,
               field: str) -> tuple[str, ...]:
    if raw is None:
        return ()
    if isinstance(raw, Mapping):
        items = [f"{k}={yamlio.dump(v, default_flow_style=True).strip().removesuffix('...')}"
                 .strip() for k, v in raw.items()]
    else:
        items = list(raw)
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


@dataclass(frozen=True)
class EntryFile:
    """One item of a suite file's ``scenarios:`` (a bare string is its ``path``): the
    scenario file, relative to the suite file, and what the suite changes about it."""

    path: str
    name: str | None = None
    repeat: int | None = field(default=None, metadata=_REPEAT)
    timeout: int | float | None = field(default=None, metadata=_TIMEOUT)
    set: dict[str, Any] | tuple[str, ...] | None = None
    sweep: Any = None  # checked by parse_sweep


@dataclass(frozen=True)
class DefaultsFile:
    """A suite file's ``defaults:``."""

    repeat: int | None = field(default=None, metadata=_REPEAT)
    timeout: int | float | None = field(default=None, metadata=_TIMEOUT)


@dataclass(frozen=True, kw_only=True)
class SuiteFile:
    """A suite file: its name, defaults and scenarios."""

    suite: str = "srr suite"
    defaults: DefaultsFile | None = None
    scenarios: tuple[str | EntryFile, ...]


def _entry(item: str | EntryFile, raw: Any, base: Path, file: str, field: str,
           cli: _Defaults, suite: _Defaults, loads: ScenarioLoads) -> Entry:
    """``item``: the entry as read; ``raw``: as written (whether it declares a sweep)."""
    e = EntryFile(path=item) if isinstance(item, str) else item
    if not e.path:
        raise ScenarioError(file, f"{field}.path", "expected the path of a scenario file")
    path = e.path
    scenario_file = base / path
    try:
        is_file = scenario_file.is_file()
    except OSError as err:  # a name too long for the file system
        raise ScenarioError(file, f"{field}.path", f"cannot read {path!r}: "
                            f"{err.strerror or err}") from None
    if not is_file:
        raise ScenarioError(file, f"{field}.path", f"no such file: {scenario_file}")
    repeat = (_count(e.repeat, file, f"{field}.repeat", integer=True) if e.repeat is not None
              else cli.repeat or suite.repeat or 1)
    timeout_s = (float(_count(e.timeout, file, f"{field}.timeout", integer=False))
                 if e.timeout is not None else cli.timeout_s or suite.timeout_s)
    overrides = _overrides(e.set, file, f"{field}.set")
    name = e.name
    if name is not None and not _safe_name(name):
        raise ScenarioError(file, f"{field}.name", "expected a name of letters, digits, '_', "
                            f"'-' and '.', got {name!r}")
    has_sweep = isinstance(raw, Mapping) and "sweep" in raw
    try:
        return _checked(str(scenario_file), overrides, loads, repeat=repeat,
                        timeout_s=timeout_s, name=name, sweep_raw=e.sweep, has_sweep=has_sweep,
                        sweep_file=file, sweep_field=f"{field}.sweep",
                        declared_in=f"{file}: {field}")
    except ScenarioError as err:
        # a value the entry's set: gave is the suite file's to answer for, wherever the
        # loader found it wrong (an unknown key, a value out of range)
        keys = [parse_override(o)[0] for o in overrides]  # dotted, as the loader got them
        where = dotted(err.field)
        ours = err.file == "--set" or any(where == k or where.startswith(f"{k}.")
                                          for k in keys)
        if not ours:
            raise
        raise ScenarioError(file, f"{field}.set", f"{err.field}: {err.message}") from None


def _folder(path: Path, cli: _Defaults, loads: ScenarioLoads) -> list[Entry]:
    """The entries of a folder's scenario files. Every file is read before any is refused:
    the first problem is said, and how many other files have one (``srr validate FOLDER``
    says each)."""
    found: list[Entry] = []
    errors: list[SrrError] = []
    scenarios = 0
    for file in _yaml_files(path):
        try:
            if not _is_scenario(_read(file)):
                continue
            scenarios += 1
            found.append(_checked(str(file), (), loads, repeat=cli.repeat or 1,
                                  timeout_s=cli.timeout_s, name=None, sweep_raw=None,
                                  has_sweep=False, sweep_file=str(file), sweep_field="sweep",
                                  declared_in=str(file)))
        except SrrError as err:
            errors.append(err)
    if errors:
        more = (f" (and {len(errors) - 1} more file(s) of {path} that do not load: `srr "
                f"validate {path}` says each)") if len(errors) > 1 else ""
        raise SrrError(f"{errors[0]}{more}")
    if not scenarios:
        raise SrrError(f"{path}: the folder holds no scenario files (*.yaml with a `name:`)")
    return found


def _safe_name(name: str) -> bool:
    return bool(name) and name not in (".", "..") and all(
        c.isalnum() or c in "_-." for c in name)


def _checked(scenario_file: str, overrides: tuple[str, ...], loads: ScenarioLoads, *,
             repeat: int, timeout_s: float | None, name: str | None, sweep_raw: Any,
             has_sweep: bool, sweep_file: str, sweep_field: str, declared_in: str) -> Entry:
    """Load the scenario once (schema, includes, overrides) to learn its name and sweep."""
    sc = loads(scenario_file, overrides)
    if has_sweep:
        sweep, source = parse_sweep(sweep_raw, sweep_file, sweep_field), sweep_file
    else:
        sweep, source = parse_sweep(sc.sweep, scenario_file, "sweep"), scenario_file
        sweep_field = "sweep"
    for o in overrides:
        path = parse_override(o)[0]
        swept = varied_path(path, (p.path for p in sweep))
        if swept is not None:
            raise SrrError(f"{declared_in}.set: {path} is swept ({sweep_field}: {swept}): each "
                           "point's value would replace the one set: gives; leave one of the "
                           "two out")
    if name is None and not _safe_name(sc.name):
        raise ScenarioError(scenario_file, "name", "cannot name a suite entry (letters, digits, "
                            "'_', '-' and '.'); give the entry a `name:` in the suite file")
    return Entry(name=name or sc.name, scenario=sc.name, scenario_file=scenario_file,
                 baseline=sc.baseline or sc.name, repeat=int(repeat), timeout_s=timeout_s,
                 overrides=overrides, sweep=sweep, sweep_source=source, declared_in=declared_in,
                 sweep_field=sweep_field)


def _suite_file(path: Path, data: Mapping[str, Any], cli: _Defaults,
                loads: ScenarioLoads) -> tuple[str, list[Entry]]:
    file = str(path)
    spec = validate(SuiteFile, data, file)
    if not spec.suite.strip():
        raise ScenarioError(file, "suite", f"expected the suite's name, got {spec.suite!r}")
    d = spec.defaults or DefaultsFile()
    suite = _Defaults(
        _count(d.repeat, file, "defaults.repeat", integer=True) if d.repeat is not None
        else None,
        float(_count(d.timeout, file, "defaults.timeout", integer=False))
        if d.timeout is not None else None)
    if not spec.scenarios:
        raise ScenarioError(file, "scenarios", "the suite lists no scenarios")
    entries = [_entry(item, raw, path.parent, file, f"scenarios[{i}]", cli, suite, loads)
               for i, (item, raw) in enumerate(zip(spec.scenarios, data["scenarios"],
                                                   strict=True))]
    return spec.suite, entries


def load_suite(paths: Sequence[str | Path], *, repeat: int | None = None,
               timeout_s: float | None = None,
               loads: ScenarioLoads | None = None) -> SuiteSpec:
    """Expand ``paths`` (scenario files, folders of them, suite files) into checked entries
    (``loads``: where the scenarios loaded are kept for the rest of the planning).

    Raises :class:`~harness.errors.SrrError` (exit 2) naming the file and field of the first
    problem; nothing has run then."""
    if not paths:
        raise SrrError("srr suite: no scenario files, folders or suite files given")
    if repeat is not None:
        _count(repeat, "--repeat", "", integer=True)
    if timeout_s is not None:
        _count(timeout_s, "--timeout", "", integer=False)
    cli = _Defaults(repeat, timeout_s)
    loads = loads if loads is not None else ScenarioLoads()
    names: list[str] = []
    entries: list[Entry] = []
    for given in paths:
        path = Path(given)
        if path.is_dir():
            entries += _folder(path, cli, loads)
            continue
        data = _read(path)
        if is_suite_file(data):
            name, more = _suite_file(path, data, cli, loads)
            names.append(name)
            entries += more
        elif _is_scenario(data):
            entries.append(_checked(str(path), (), loads, repeat=cli.repeat or 1,
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
