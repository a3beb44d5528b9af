"""Reading a run directory's ``summary.json`` back, checked field by field (the typed summary
that every writer builds, and that reads these checked fields, is
:class:`harness.run.summary.RunSummary`).

Every command that reads a run directory (``report``, ``replay``, ``baseline bless``, ``diff``)
goes through :func:`read_summary`: a missing, unparsable or mis-typed summary is one
:class:`~harness.errors.SrrError` line naming the file and the field (exit 2), never a
traceback deeper in.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from harness.errors import SrrError

__all__ = ["SUMMARY_NAME", "Check", "check_summary", "fail", "is_int", "read_summary",
           "replay_note"]

SUMMARY_NAME = "summary.json"

Check = Callable[[Any], bool]


def is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_num(v: Any) -> bool:
    return is_int(v) or isinstance(v, float)


def _opt_num(v: Any) -> bool:
    return v is None or _is_num(v)


def _str(v: Any) -> bool:
    return isinstance(v, str)


def _rows(fields: Mapping[str, tuple[Check, str]]) -> Check:
    def ok(v: Any) -> bool:
        return isinstance(v, dict) and all(k in v and check(v[k]) for k, (check, _) in
                                           fields.items())
    return ok


_METRIC = {"name": (_str, "a string"), "value": (_opt_num, "a number or null"),
           "unit": (_str, "a string"), "direction": (_str, "a string")}
_HEALTH = {"name": (_str, "a string"), "ok": (lambda v: isinstance(v, bool), "true or false"),
           "detail": (_str, "a string")}
_TOPIC = {"count": (is_int, "an integer"), "sha256": (_str, "a string"),
          "type": (_str, "a string")}

#: field → (check, what it should be); fields a summary must have.
REQUIRED: dict[str, tuple[Check, str]] = {
    "scenario": (_str, "a string"),
    "verdict": (_str, "a string"),
    "seed": (is_int, "an integer"),
    "digest": (_str, "a string"),
    "metrics": (lambda v: isinstance(v, list), "a list"),
    "health": (lambda v: isinstance(v, list), "a list"),
    "topics": (lambda v: isinstance(v, dict), "a mapping"),
}
OPTIONAL: dict[str, tuple[Check, str]] = {
    "ticks": (is_int, "an integer"),
    "simulated_s": (_is_num, "a number"),
    "srr_gt": (lambda v: isinstance(v, bool), "true or false"),
    "scenario_file": (_str, "a string"),
    "baselines_dir": (_str, "a string"),
    "sut_endpoints": (lambda v: isinstance(v, dict), "a mapping"),
    "replay_of": (lambda v: isinstance(v, dict), "a mapping"),
    "comparison": (lambda v: isinstance(v, list), "a list"),
    "baseline": (lambda v: v is None or isinstance(v, dict), "a mapping or null"),
    "interrupted": (lambda v: isinstance(v, bool), "true or false"),
}


def replay_note(summary: Mapping[str, Any]) -> str | None:
    """``open-loop replay of RUN (changed: --set X=Y, --sut NAME=module:Class)``, or None
    when the summary is not a replay's (its ``replay_of``): what the console, the report
    and ``srr diff`` say of a replay."""
    r = summary.get("replay_of")
    if not isinstance(r, Mapping):
        return None
    replaced: Mapping[str, Any] = r["replaced"] if isinstance(r.get("replaced"), Mapping) else {}
    overrides: list[Any] = r["overrides"] if isinstance(r.get("overrides"), list) else []
    changes = [f"--set {o}" for o in overrides] + [f"--sut {k}={v}" for k, v in replaced.items()]
    what = (f"changed: {', '.join(changes)}" if changes else
            "nothing changed: the recorded systems under test and settings")
    return f"open-loop replay of {r.get('run_dir', '?')} ({what})"


def fail(path: Path, field: str, message: str) -> SrrError:
    return SrrError(f"{path}: {field}: {message}")


def read_summary(run_dir: str | Path) -> dict[str, Any]:
    """The run's ``summary.json``, its fields checked; :class:`SrrError` (exit 2) when the
    directory is not a finished run directory or the summary is malformed."""
    run = Path(run_dir)
    path = run / SUMMARY_NAME
    if not run.is_dir():
        raise SrrError(f"{run}: not a run directory (no such directory)")
    if not path.is_file():
        raise SrrError(f"{path}: missing (not a finished run directory)")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError, OSError) as err:
        raise SrrError(f"{path}: not valid JSON: {err}") from err
    check_summary(data, path)
    checked: dict[str, Any] = data
    return checked


def check_summary(data: Any, path: Path) -> None:
    """:class:`SrrError` naming ``path`` and the field when ``data`` is not a run summary."""
    if not isinstance(data, dict):
        raise SrrError(f"{path}: expected a JSON object, got {type(data).__name__}")
    for key, (check, what) in REQUIRED.items():
        if key not in data:
            raise fail(path, key, "missing (not an srr run summary)")
        if not check(data[key]):
            raise fail(path, key, f"expected {what}, got {data[key]!r:.60}")
    for key, (check, what) in OPTIONAL.items():
        if key in data and not check(data[key]):
            raise fail(path, key, f"expected {what}, got {data[key]!r:.60}")
    for i, m in enumerate(data["metrics"]):
        if not _rows(_METRIC)(m):
            raise fail(path, f"metrics[{i}]", "expected name, value, unit and direction")
    for i, h in enumerate(data["health"]):
        if not _rows(_HEALTH)(h):
            raise fail(path, f"health[{i}]", "expected name, ok and detail")
    for name, t in data["topics"].items():
        if not _rows(_TOPIC)(t):
            raise fail(path, f"topics.{name}", "expected count, sha256 and type")
