"""The Python API: everything the CLI does is a call here.

``run_scenario`` loads and validates a scenario, builds and runs it, records the bag, checks
that every published message was recorded, and writes the run directory:

    scenario.yaml   resolved scenario (includes expanded, defaults and overrides applied)
    bag/            rosbag2 directory: metadata.yaml + one .mcap
    summary.json    verdict and reasons, health gates, metrics, baseline comparison,
                    per-topic count/rate/bytes/sha256, versions, seed, command to reproduce
    junit.xml       health gates and metric comparisons as test cases, for CI systems
    report.html     the reviewer's page (harness.report), written last
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import platform
import shutil
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

import yaml

from harness import __version__
from harness.atomic import write_json_atomic
from harness.bus import Recorder, TopicStats
from harness.diff import DiffResult, Tolerance
from harness.diff import diff_runs as _diff_runs
from harness.engine import Simulation
from harness.errors import InvalidRunError, SrrError
from harness.graph import stage_to_json, stage_to_mermaid
from harness.regression import baseline_path, compare, decide, load_baseline, save_baseline
from harness.report.html import write_report
from harness.report.junit import junit_cases, write_junit
from harness.scenario import Scenario, load_scenario, parse_override, scenario_to_mapping
from harness.scoring import Scores, check_scoring, score_run
from harness.wiring import check_wiring

__all__ = [
    "RepeatResult",
    "RunResult",
    "baselines_dir",
    "bless",
    "build_graphs",
    "default_run_dir",
    "diff_runs",
    "graph_text",
    "load",
    "run_repeat",
    "run_scenario",
    "validate",
    "versions",
    "write_diff",
]

Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class RunResult:
    run_dir: Path
    verdict: str
    exit_code: int
    summary: dict[str, Any]


@dataclass(frozen=True)
class RepeatResult:
    runs: tuple[RunResult, ...]
    identical: bool
    differing_topics: tuple[str, ...]
    exit_code: int
    out_dir: Path


def versions() -> dict[str, str]:
    out = {"srr": __version__, "python": platform.python_version()}
    for dist in ("mujoco", "numpy", "rosbags", "mcap", "pandas"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = "not installed"
    return out


def load(path: str | Path, *, seed: int | None = None, duration: float | None = None,
         srr_gt: bool | None = None, overrides: Sequence[str] = ()) -> Scenario:
    """Load a scenario with CLI-style overrides (``--set``, ``--seed``, ``--duration``)."""
    pairs = [parse_override(o) for o in overrides]
    if seed is not None:
        pairs.append(("seed", seed))
    if duration is not None:
        pairs.append(("duration", duration))
    if srr_gt is not None:
        pairs.append(("srr_gt", srr_gt))
    return load_scenario(path, pairs)


def build_graphs(scenario: Scenario, source: str = "<scenario>") -> Simulation:
    return Simulation(scenario, source=source)


def graph_text(scenario: Scenario, fmt: str = "mermaid", source: str = "<scenario>") -> str:
    """The scenario's action graphs as Mermaid or JSON (``srr graph``)."""
    sim = Simulation(scenario, source=source)
    return stage_to_mermaid(sim.stage) if fmt == "mermaid" else stage_to_json(sim.stage)


def default_run_dir(scenario: Scenario, root: Path = Path("reports")) -> Path:
    """``reports/<scenario>/<run id>``; the run id is the local start time plus the seed
    (a name only: no wall-clock value goes into the recorded data)."""
    stamp = time.strftime("%Y%m%d-%H%M%S")
    base = root / scenario.name / f"{stamp}-s{scenario.seed}"
    candidate, n = base, 1
    while candidate.exists():
        n += 1
        candidate = base.with_name(f"{base.name}-{n}")
    return candidate


def combined_digest(topics: dict[str, Any]) -> str:
    h = hashlib.sha256()
    for name in sorted(topics):
        h.update(f"{name}\0{topics[name]['sha256']}\n".encode())
    return h.hexdigest()


def _topic_table(stats: dict[str, TopicStats], published: dict[str, int],
                 duration_s: float) -> dict[str, Any]:
    table = {}
    for name, st in stats.items():
        rate = st.count / duration_s if duration_s > 0 else 0.0
        table[name] = {
            "type": st.msgtype,
            "count": st.count,
            "published": published.get(name, 0),
            "rate_hz": round(rate, 3),
            "bytes": st.bytes,
            "sha256": st.sha256,
            "durability": st.durability,
        }
    return table


def run_scenario(scenario: Scenario, *, source: str = "<scenario>", out: Path | None = None,
                 progress: Progress | None = None, baselines: Path | None = None,
                 update_baseline: bool = False, update_reason: str = "updated with "
                 "--update-baseline") -> RunResult:
    """Build, run and record ``scenario``; write the run directory and return its verdict."""
    run_dir = Path(out) if out is not None else default_run_dir(scenario)
    if run_dir.exists() and any(run_dir.iterdir()):
        raise SrrError(f"--out {run_dir}: directory exists and is not empty")
    check_scoring(scenario, srr_gt=scenario.srr_gt, source=source)
    sim = Simulation(scenario, source=source)
    try:
        warnings = check_wiring(sim.plan(), scenario, source)
    except BaseException:
        sim.close()
        raise
    run_dir.mkdir(parents=True, exist_ok=True)
    (run_dir / "scenario.yaml").write_text(
        yaml.safe_dump(scenario_to_mapping(scenario), sort_keys=False), encoding="utf-8")
    recorder = Recorder(run_dir / "bag")
    recorder.open(sim.bus.qos)
    sim.add_tap(recorder)
    interrupted = False
    try:
        sim.run(scenario.n_ticks, progress)
    except KeyboardInterrupt:
        interrupted = True
    except BaseException:
        with contextlib.suppress(Exception):  # the original error is the one to report
            recorder.close()
        shutil.rmtree(run_dir, ignore_errors=True)
        raise
    finally:
        sim.close()
    stats = recorder.close()
    published = sim.bus.published_counts()
    sim_s = sim.tick_index / scenario.physics.tick_hz
    topics = _topic_table(stats, published, sim_s)
    scores = score_run(scenario, run_dir / "bag", srr_gt=sim.srr_gt, published=published,
                       recorded={t: st.count for t, st in stats.items()}, duration_s=sim_s,
                       source=source)
    summary: dict[str, Any] = {
        "scenario": scenario.name,
        "scenario_file": source,
        "seed": scenario.seed,
        "srr_gt": sim.srr_gt,
        "duration_s": scenario.duration,
        "simulated_s": sim_s,
        "ticks": sim.tick_index,
        "tick_hz": scenario.physics.tick_hz,
        "interrupted": interrupted,
        "warnings": list(warnings),
        "health": [dataclasses.asdict(h) for h in scores.health],
        "metrics": [dataclasses.asdict(m) for m in scores.metrics],
        "graphs": sim.graph_paths,
        "systems_under_test": [name for name, _, _ in sim.suts],
        "topics": topics,
        "digest": combined_digest(topics),
        "versions": versions(),
        "command": reproduce_command(source, scenario, run_dir),
    }
    bdir = baselines_dir(source, baselines)
    if update_baseline and not interrupted:
        if not all(h.ok for h in scores.health):
            raise InvalidRunError(f"{run_dir}: health gates tripped; an invalid run cannot "
                                  "become the baseline")
        save_baseline(baseline_path(baseline_name(scenario), bdir), summary,
                      reason=update_reason, source_run=str(run_dir))
    _judge(summary, scenario, scores, bdir)
    if interrupted:
        summary["verdict"], summary["exit_code"] = "INTERRUPTED", 130
        summary["reasons"] = ["interrupted before the end of the scenario"]
    write_json_atomic(run_dir / "summary.json", summary)
    write_junit(run_dir / "junit.xml", scenario.name, junit_cases(summary))
    try:  # last: a report that fails to render never costs the run its summary
        write_report(run_dir, summary=summary, scenario=scenario)
    except SrrError:
        raise
    except Exception as err:
        raise SrrError(f"{run_dir / 'report.html'}: the report could not be rendered "
                       f"({type(err).__name__}: {err}); summary.json is complete") from err
    return RunResult(run_dir, summary["verdict"], summary["exit_code"], summary)


def validate(scenario: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """Every check that can be made without running (``srr validate``): the scenario itself
    (done by loading it), the scoring block, building the world and the graphs, loading and
    setting up the systems under test, and the wiring (topics and TF). Raises the first error;
    returns the warnings."""
    check_scoring(scenario, srr_gt=scenario.srr_gt, source=source)
    sim = Simulation(scenario, source=source)
    try:
        return check_wiring(sim.plan(), scenario, source)
    finally:
        sim.close()


def baseline_name(scenario: Scenario) -> str:
    return scenario.baseline or scenario.name


def baselines_dir(source: str, explicit: Path | None = None) -> Path:
    """``--baselines`` if given, else the ``baselines/`` folder of the project the scenario
    file lives in (the nearest ancestor that has one), else ``./baselines``."""
    if explicit is not None:
        return Path(explicit)
    here = Path(source).resolve().parent if source and not source.startswith("<") else None
    while here is not None and here != here.parent:
        if (here / "baselines").is_dir():
            return here / "baselines"
        here = here.parent
    return Path("baselines")


def reproduce_command(source: str, scenario: Scenario, run_dir: Path) -> str:
    return (f"srr run {source} --seed {scenario.seed} --duration {scenario.duration:g} "
            f"--out {run_dir}")


def _judge(summary: dict[str, Any], scenario: Scenario, scores: Scores, bdir: Path) -> None:
    """Compare with the baseline and fill ``verdict``, ``exit_code``, ``reasons``,
    ``baseline`` and ``comparison`` in the summary."""
    path = baseline_path(baseline_name(scenario), bdir)
    base = load_baseline(path) if scores.metrics else None
    cmp = compare(scores.metrics, base, scenario.scoring.tolerances) if base else None
    note = (f"no baseline at {path}: bless one with `srr baseline bless RUN_DIR --reason "
            "TEXT` or `srr run ... --update-baseline`")
    verdict = decide(scores.health, scores.metrics, cmp, note)
    summary["verdict"], summary["exit_code"] = verdict.name, verdict.exit_code
    summary["reasons"] = list(verdict.reasons)
    summary["baseline"] = None if base is None else {
        "path": str(path), "blessed_by": base.blessed_by, "reason": base.reason,
        "blessed_at": base.blessed_at, "seed": base.seed, "digest": base.digest,
        "digest_matches": base.digest == summary["digest"],
    }
    summary["comparison"] = [] if cmp is None else [dataclasses.asdict(e) for e in cmp.entries]


def bless(run_dir: Path, reason: str, *, baselines: Path | None = None) -> Path:
    """Make a finished run the baseline of its scenario (``srr baseline bless``)."""
    summary_file = Path(run_dir) / "summary.json"
    if not summary_file.exists():
        raise SrrError(f"{run_dir}: summary.json: missing (not a finished run directory)")
    try:
        summary = json.loads(summary_file.read_text(encoding="utf-8"))
    except ValueError as err:
        raise SrrError(f"{summary_file}: not valid JSON: {err}") from err
    if summary.get("verdict") == "INVALID" or summary.get("interrupted"):
        raise InvalidRunError(f"{run_dir}: the run is {summary.get('verdict', 'invalid')}; "
                              "only a valid, complete run can become the baseline")
    scenario = load_scenario(Path(run_dir) / "scenario.yaml")
    path = baseline_path(baseline_name(scenario),
                         baselines_dir(summary.get("scenario_file", ""), baselines))
    save_baseline(path, summary, reason=reason, source_run=str(run_dir))
    return path


def run_repeat(scenario: Scenario, n: int, *, source: str = "<scenario>",
               out: Path | None = None, progress: Progress | None = None,
               baselines: Path | None = None) -> RepeatResult:
    """Run ``n`` times (``run_1`` … ``run_n`` under one directory) and compare digests."""
    if n < 1:
        raise SrrError(f"--repeat: must be >= 1, got {n}")
    out_dir = Path(out) if out is not None else default_run_dir(scenario)
    runs = tuple(run_scenario(scenario, source=source, out=out_dir / f"run_{i + 1}",
                              progress=progress, baselines=baselines) for i in range(n))
    first = runs[0].summary["topics"]
    differing = sorted({t for r in runs[1:] for t in set(first) | set(r.summary["topics"])
                        if first.get(t, {}).get("sha256")
                        != r.summary["topics"].get(t, {}).get("sha256")})
    identical = not differing
    report = {
        "runs": [str(r.run_dir) for r in runs],
        "identical": identical,
        "differing_topics": differing,
        "digests": [r.summary["digest"] for r in runs],
    }
    write_json_atomic(out_dir / "determinism.json", report)
    worst = max(r.exit_code for r in runs)
    return RepeatResult(runs, identical, tuple(differing),
                        worst if identical else max(worst, 1), out_dir)


def diff_runs(a: str | Path, b: str | Path, *,
              tolerances: Sequence[Tolerance | str] = ()) -> DiffResult:
    """Compare two run directories (``srr diff A B``): per topic counts, digests, the first
    divergence and per-field differences against ``tolerances``
    (``TOPIC_GLOB[:FIELD_GLOB]=ABS[,REL]`` strings or :class:`Tolerance`), and both runs'
    metrics side by side. ``result.exit_code`` is 0 when the recorded data are equal within
    tolerance, 1 when not; bad input raises :class:`SrrError` (exit 2)."""
    return _diff_runs(a, b, tolerances=tolerances)


def write_diff(result: DiffResult, path: str | Path) -> Path:
    """Write the one-page HTML view of ``result`` (``srr diff --html FILE``): both runs'
    trajectories on one map, their time series overlaid, metric deltas, the topic table and
    camera keyframes side by side at the first divergence and the worst moments."""
    from harness.diff.html import write_diff as _write

    return _write(result, path)
