"""Suite summaries (``OUT/summary.json``, format ``srr-suite/1``) built for tests, with the
files they point to: a real run's ``report.html`` copied to every repeat that has a report,
and a log for every repeat that crashed or timed out.

Statistics are computed the way the suite does (sample std, Student-t 95 % interval), so a
summary built here reads like one ``srr suite`` writes.
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["GROUP_ORDER", "FakeRun", "SuiteBuilder", "stats_of"]

GROUP_ORDER = ("INVALID", "FLAKY", "MISMATCH", "REGRESSED", "FAIL", "INTERRUPTED", "UNSCORED",
               "RECORDED", "PASS")
T95 = {2: 12.706, 3: 4.303, 4: 3.182, 5: 2.776, 6: 2.571}
UNITS = {"safety.match_rate": ("%", "higher", "safety"),
         "safety.under_mute_pct": ("%", "lower", "safety"),
         "control.goal_reached": ("bool", "higher", "control"),
         "control.cross_track_error.max": ("m", "lower", "control"),
         "control.cross_track_error.mean": ("m", "lower", "control"),
         "control.heading_error.max": ("rad", "lower", "control"),
         "perception.recall": ("ratio", "higher", "perception"),
         "perception.precision": ("ratio", "higher", "perception")}


def stats_of(name: str, values: Sequence[float], baseline: tuple[float, float] | None = None,
             status: str | None = None) -> dict[str, Any]:
    """One ``stats`` entry over the repeats' values; ``status`` is worked out from the
    baseline and tolerance when not given."""
    unit, direction, group = UNITS.get(name, ("", "none", name.split(".")[0]))
    n = len(values)
    mean = sum(values) / n if n else None
    std = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1)) if n > 1 and mean is not None \
        else (0.0 if n == 1 else None)
    ci = None
    if n > 1 and mean is not None and std is not None:
        h = T95[n] * std / math.sqrt(n)
        ci = [mean - h, mean + h]
    if status is None and baseline is not None and mean is not None:
        b, tol = baseline
        worse = mean < b - tol if direction == "higher" else mean > b + tol
        status = "regressed" if worse else "ok"
    band = None
    if name == "safety.match_rate" and values:
        low = min(values)
        band = "PASS" if low >= 95 else "NEAR" if low >= 80 else "FAIL"
    return {"unit": unit, "direction": direction, "group": group, "n": n, "mean": mean,
            "std": std, "min": min(values) if values else None,
            "max": max(values) if values else None, "ci95": ci,
            "baseline": None if baseline is None else baseline[0],
            "tolerance": None if baseline is None else baseline[1], "status": status,
            "band": band}


@dataclass(frozen=True)
class FakeRun:
    """One repeat: its verdict and metric values, and how it ended."""

    verdict: str
    metrics: Mapping[str, float] = field(default_factory=dict)
    digest: str | None = "ab12" * 16
    crash: str | None = None
    timed_out: bool = False
    reasons: tuple[str, ...] = ()


class SuiteBuilder:
    """Adds groups (and sweeps) one by one and writes the files their runs point to under
    ``out``; :meth:`summary` gives the summary, groups in the order added."""

    def __init__(self, out: Path, report_src: Path, *, name: str = "nightly",
                 started_at: str = "2026-11-23T02:00:00Z") -> None:
        self.out, self.report_src = out, report_src
        self.name, self.started_at = name, started_at
        self.groups: list[dict[str, Any]] = []
        self.runs: list[dict[str, Any]] = []
        self.sweeps: list[dict[str, Any]] = []

    def group(self, entry: str, runs: Sequence[FakeRun], *,
              params: Mapping[str, Any] | None = None, sweep: str | None = None,
              baselines: Mapping[str, tuple[float, float]] | None = None,
              verdict: str | None = None, reasons: Sequence[str] = (),
              flaky_detail: Mapping[str, Any] | None = None,
              against_baseline: Mapping[str, Any] | None = None) -> str:
        params = dict(params or {})
        label = ",".join(f"{k}={v}" for k, v in params.items())
        gid = f"{entry}[{label}]" if params else entry
        run_ids = []
        for k, r in enumerate(runs, start=1):
            rid = f"{gid}#{k}"
            run_dir = f"runs/{entry}/{label or 'nominal'}/r{k}"
            report = None
            if r.crash is None and not r.timed_out:
                (self.out / run_dir).mkdir(parents=True, exist_ok=True)
                shutil.copyfile(self.report_src, self.out / run_dir / "report.html")
                report = f"{run_dir}/report.html"
            log = f"logs/{rid.replace('[', '_').replace(']', '_').replace('#', '_r')}.log"
            (self.out / log).parent.mkdir(parents=True, exist_ok=True)
            (self.out / log).write_text(f"worker log of {rid}\n", encoding="utf-8")
            reasons_r = list(r.reasons)
            if r.crash:
                reasons_r.insert(0, f"the worker crashed: {r.crash}")
            if r.timed_out:
                reasons_r.insert(0, "timed out after 60 s of wall-clock time and was stopped")
            self.runs.append({
                "id": rid, "group": gid, "repeat": k, "scenario": entry, "params": params,
                "verdict": r.verdict, "exit_code": 0 if r.verdict == "PASS" else 1,
                "reasons": reasons_r, "wall_s": 7.2,
                "run_dir": run_dir if report else None, "report": report, "log": log,
                "digest": r.digest if report else None, "timed_out": r.timed_out,
                "crash": r.crash, "metrics": dict(r.metrics)})
            run_ids.append(rid)
        names = sorted({m for r in runs for m in r.metrics})
        stats = {m: stats_of(m, [r.metrics[m] for r in runs if m in r.metrics],
                             (baselines or {}).get(m)) for m in names}
        if verdict is None:
            verdict = min((r.verdict for r in runs), key=GROUP_ORDER.index)
        if not reasons:  # as the suite does: each failing repeat's reasons, tagged
            reasons = list(dict.fromkeys(
                f"#{k}: {x}" if len(runs) > 1 else x
                for k, r in enumerate(runs, start=1) if r.verdict != "PASS" for x in r.reasons))
        self.groups.append({
            "id": gid, "name": entry, "scenario": entry,
            "scenario_file": f"scenarios/{entry}.yaml", "params": params, "sweep": sweep,
            "repeats": len(runs), "verdict": verdict,
            "exit_code": {"PASS": 0, "INVALID": 3}.get(verdict, 1),
            "reasons": list(reasons), "flaky": flaky_detail is not None,
            "flaky_detail": None if flaky_detail is None else dict(flaky_detail),
            "stats": stats, "runs": run_ids,
            "against_baseline": None if against_baseline is None else dict(against_baseline)})
        return gid

    def sweep(self, name: str, params: Sequence[str], groups: Sequence[str]) -> None:
        self.sweeps.append({"name": name, "scenario": name, "params": list(params),
                            "groups": list(groups)})

    def summary(self, *, interrupted: bool = False) -> dict[str, Any]:
        counts: dict[str, int] = {}
        for g in self.groups:
            counts[g["verdict"]] = counts.get(g["verdict"], 0) + 1
        verdict = min(counts, key=GROUP_ORDER.index) if counts else "INVALID"
        return {"format": "srr-suite/1", "name": self.name, "started_at": self.started_at,
                "wall_s": 123.4, "executor": "local", "jobs": 2, "address": None,
                "verdict": "INTERRUPTED" if interrupted else verdict,
                "exit_code": 130 if interrupted else 3 if verdict == "INVALID" else
                0 if verdict == "PASS" else 1,
                "interrupted": interrupted, "counts": counts, "groups": list(self.groups),
                "runs": list(self.runs), "sweeps": list(self.sweeps), "history": None}
