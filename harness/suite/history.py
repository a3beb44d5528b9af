"""Night-to-night history of a suite: the ``history`` block of ``OUT/summary.json`` built from
earlier suite outputs (``srr suite --history DIR``).

``DIR`` is a folder of earlier suite output folders (each with its ``summary.json``, format
``srr-suite/1``), or one such folder itself. Earlier nights of the same suite (``name``) are
ordered by ``started_at``; the last ``last`` of them are kept, then tonight. A summary that is
damaged, of another format or of another suite is skipped with a warning (in the block's
``warnings``), never a traceback; a ``DIR`` that does not exist is an :class:`SrrError`.

The block (the schema's ``nights`` and ``series``, plus two fields the suite page uses)::

    {"nights": [{"started_at": ..., "verdict": ..., "path": ...}, ...],  # tonight last
     "series": {"<group id>": {"<metric>": [mean or null per night]}},
     "verdicts": {"<group id>": [group verdict or null per night]},
     "warnings": ["history: skipped ...", ...]}

Series and verdicts cover tonight's groups; a group's metrics are every metric it had on any
kept night, the value of a night being that group's ``stats[metric].mean`` (null when absent).
Tonight's ``path`` is ``"."`` (OUT itself).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from harness.errors import SrrError
from harness.summary import SUITE_FORMAT, SUMMARY_NAME

__all__ = ["DEFAULT_LAST", "load_history"]

DEFAULT_LAST = 14


@dataclass(frozen=True)
class _Night:
    """One suite output as history reads it."""

    when: datetime
    started_at: str
    verdict: str
    path: str
    groups: Mapping[str, Mapping[str, Any]]


def _parse_time(text: Any) -> datetime | None:
    """An ISO 8601 time (``Z`` allowed); one without a zone is taken as UTC."""
    if not isinstance(text, str):
        return None
    try:
        t = datetime.fromisoformat(text)
    except ValueError:
        return None
    return t if t.tzinfo is not None else t.replace(tzinfo=UTC)


def _groups(summary: Mapping[str, Any]) -> dict[str, Mapping[str, Any]] | None:
    groups = summary.get("groups")
    if not isinstance(groups, list):
        return None
    out: dict[str, Mapping[str, Any]] = {}
    for g in groups:
        if not isinstance(g, Mapping) or not isinstance(g.get("id"), str):
            return None
        if "stats" in g and not isinstance(g["stats"], Mapping):
            return None
        out[g["id"]] = g
    return out


def _read_night(folder: Path, name: str) -> _Night | str:
    """The night in ``folder``, or why it is skipped."""
    file = folder / SUMMARY_NAME
    try:
        data = json.loads(file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as err:
        return f"{file}: unreadable ({err.__class__.__name__}: {err})"
    except ValueError as err:
        return f"{file}: not valid JSON ({err})"
    except RecursionError:
        return f"{file}: not valid JSON (nested too deeply)"
    if not isinstance(data, dict):
        return f"{file}: not an srr suite summary (a JSON {type(data).__name__})"
    if data.get("format") != SUITE_FORMAT:
        return (f"{file}: not an srr suite summary (format {data.get('format')!r}, "
                f"expected {SUITE_FORMAT!r})")
    when = _parse_time(data.get("started_at"))
    if when is None:
        return f"{file}: started_at {data.get('started_at')!r} is not an ISO 8601 time"
    if data.get("name") != name:
        return f"{file}: another suite ({data.get('name')!r}, not {name!r})"
    groups = _groups(data)
    if groups is None:
        return f"{file}: groups is not a list of groups with an id and stats"
    return _Night(when, str(data["started_at"]), str(data.get("verdict", "")), str(folder),
                  groups)


def _folders(d: Path) -> list[Path]:
    """Suite output folders in ``d``: ``d`` itself when it holds a summary, else its
    subfolders that do (in name order)."""
    if not d.exists():
        raise SrrError(f"{d}: history folder does not exist")
    if not d.is_dir():
        raise SrrError(f"{d}: history is not a folder")
    if (d / SUMMARY_NAME).is_file():
        return [d]
    try:
        subs = sorted(p for p in d.iterdir() if p.is_dir())
    except OSError as err:
        raise SrrError(f"{d}: history folder cannot be read ({err})") from err
    return [p for p in subs if (p / SUMMARY_NAME).is_file()]


def _mean(group: Mapping[str, Any] | None, metric: str) -> float | None:
    stats = (group or {}).get("stats")
    st = stats.get(metric) if isinstance(stats, Mapping) else None
    v = st.get("mean") if isinstance(st, Mapping) else None
    if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v):
        return float(v)
    return None


def load_history(dirs: Sequence[Path], current: Mapping[str, Any], *,
                 last: int = DEFAULT_LAST) -> dict[str, Any]:
    """The ``history`` block for tonight's suite summary ``current`` from the earlier suite
    outputs under ``dirs`` (see the module docstring). Raises :class:`SrrError` when a
    ``dirs`` entry does not exist or ``last`` is negative."""
    if last < 0:
        raise SrrError(f"history: the number of earlier nights must be 0 or more, not {last}")
    name = current.get("name")
    name = name if isinstance(name, str) else "srr suite"
    tonight_at = _parse_time(current.get("started_at"))
    warnings: list[str] = []
    nights: list[_Night] = []
    seen: dict[datetime, str] = {}
    for d in dirs:
        folders = _folders(Path(d))
        if not folders:
            warnings.append(f"history: no earlier suite output ({SUMMARY_NAME}) in {d}")
        for folder in folders:
            night = _read_night(folder, name)
            if isinstance(night, str):
                warnings.append(f"history: skipped {night}")
                continue
            if tonight_at is not None and night.when == tonight_at:
                continue  # tonight's own output inside the history folder
            if tonight_at is not None and night.when > tonight_at:
                warnings.append(f"history: skipped {folder / SUMMARY_NAME}: started at "
                                f"{night.started_at}, after tonight's suite")
                continue
            if night.when in seen:
                warnings.append(f"history: skipped {folder / SUMMARY_NAME}: same started_at "
                                f"as {seen[night.when]}")
                continue
            seen[night.when] = night.path
            nights.append(night)
    nights.sort(key=lambda n: n.when)
    kept = nights[-last:] if last else []
    groups = [g for g in current.get("groups") or [] if isinstance(g, Mapping)
              and isinstance(g.get("id"), str)]
    series: dict[str, dict[str, list[float | None]]] = {}
    verdicts: dict[str, list[str | None]] = {}
    for g in groups:
        gid = str(g["id"])
        olds = [n.groups.get(gid) for n in kept]
        metrics: set[str] = set()
        for grp in [*olds, g]:
            stats = (grp or {}).get("stats")
            if isinstance(stats, Mapping):
                metrics.update(str(k) for k in stats)
        series[gid] = {m: [*(_mean(o, m) for o in olds), _mean(g, m)] for m in sorted(metrics)}
        verdicts[gid] = [*(None if o is None else str(o.get("verdict", "")) or None
                           for o in olds), str(g.get("verdict", "")) or None]
    return {
        "nights": [*({"started_at": n.started_at, "verdict": n.verdict, "path": n.path}
                     for n in kept),
                   {"started_at": str(current.get("started_at", "")),
                    "verdict": str(current.get("verdict", "")), "path": "."}],
        "series": series,
        "verdicts": verdicts,
        "warnings": warnings,
    }
