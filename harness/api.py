"""The Python API: everything the CLI does is a call here.

``run_scenario`` loads and validates a scenario, builds and runs it, records the bag, checks
that every published message was recorded, and writes the run directory:

    scenario.yaml   resolved scenario (includes expanded, defaults and overrides applied)
    bag/            rosbag2 directory: metadata.yaml + one .mcap
    summary.json    verdict, health checks, per-topic count/rate/bytes/sha256, versions, seed
    junit.xml       the health checks as test cases, for CI systems
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
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
from harness.bus import Recorder, TopicStats
from harness.engine import Simulation
from harness.errors import SrrError
from harness.graph import stage_to_json, stage_to_mermaid
from harness.report.junit import write_junit
from harness.scenario import Scenario, load_scenario, parse_override, scenario_to_mapping

__all__ = [
    "HealthCheck",
    "RepeatResult",
    "RunResult",
    "build_graphs",
    "default_run_dir",
    "graph_text",
    "load",
    "run_repeat",
    "run_scenario",
    "versions",
]

Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class HealthCheck:
    name: str
    ok: bool
    detail: str


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


def _health(stats: dict[str, TopicStats], published: dict[str, int]) -> list[HealthCheck]:
    checks = []
    mismatched = {t: (published.get(t, 0), stats[t].count if t in stats else 0)
                  for t in set(stats) | set(published)
                  if published.get(t, 0) != (stats[t].count if t in stats else 0)}
    detail = ("every published message was recorded "
              f"({sum(published.values())} messages on {len(published)} topics)")
    if mismatched:
        detail = "; ".join(f"{t}: published {p}, recorded {r}"
                           for t, (p, r) in sorted(mismatched.items()))
    checks.append(HealthCheck("recorded_equals_published", not mismatched, detail))
    return checks


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


def _write_json_atomic(path: Path, data: Any) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, sort_keys=True) + "\n", encoding="utf-8")
    os.replace(tmp, path)


def run_scenario(scenario: Scenario, *, source: str = "<scenario>", out: Path | None = None,
                 progress: Progress | None = None) -> RunResult:
    """Build, run and record ``scenario``; write the run directory and return its verdict."""
    run_dir = Path(out) if out is not None else default_run_dir(scenario)
    if run_dir.exists() and any(run_dir.iterdir()):
        raise SrrError(f"--out {run_dir}: directory exists and is not empty")
    sim = Simulation(scenario, source=source)
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
        recorder.close()
        shutil.rmtree(run_dir, ignore_errors=True)
        raise
    finally:
        sim.close()
    stats = recorder.close()
    published = sim.bus.published_counts()
    sim_s = sim.tick_index / scenario.physics.tick_hz
    checks = _health(stats, published)
    topics = _topic_table(stats, published, sim_s)
    ok = all(c.ok for c in checks)
    verdict = "INTERRUPTED" if interrupted else ("PASS" if ok else "INVALID")
    exit_code = 130 if interrupted else (0 if ok else 3)
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
        "verdict": verdict,
        "exit_code": exit_code,
        "health": [dataclasses.asdict(c) for c in checks],
        "graphs": sim.graph_paths,
        "systems_under_test": [name for name, _, _ in sim.suts],
        "topics": topics,
        "digest": combined_digest(topics),
        "versions": versions(),
    }
    _write_json_atomic(run_dir / "summary.json", summary)
    write_junit(run_dir / "junit.xml", scenario.name, checks)
    return RunResult(run_dir, verdict, exit_code, summary)


def run_repeat(scenario: Scenario, n: int, *, source: str = "<scenario>",
               out: Path | None = None, progress: Progress | None = None) -> RepeatResult:
    """Run ``n`` times (``run_1`` … ``run_n`` under one directory) and compare digests."""
    if n < 1:
        raise SrrError(f"--repeat: must be >= 1, got {n}")
    out_dir = Path(out) if out is not None else default_run_dir(scenario)
    runs = tuple(run_scenario(scenario, source=source, out=out_dir / f"run_{i + 1}",
                              progress=progress) for i in range(n))
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
    _write_json_atomic(out_dir / "determinism.json", report)
    worst = max(r.exit_code for r in runs)
    return RepeatResult(runs, identical, tuple(differing),
                        worst if identical else max(worst, 1), out_dir)
