"""The small facts every run summary carries: the versions it ran with, its per-topic table
and combined digest, the command that reproduces it, and the default run directory name."""

from __future__ import annotations

import hashlib
import platform
import time
from collections.abc import Mapping, Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

from harness import __version__
from harness.bus import TopicStats
from harness.scenario import Scenario
from harness.sut.base import SutContext

__all__ = ["combined_digest", "default_run_dir", "reproduce_command", "sut_endpoints",
           "topic_table", "versions"]


def versions() -> dict[str, str]:
    out = {"srr": __version__, "python": platform.python_version()}
    for dist in ("mujoco", "numpy", "rosbags", "mcap", "pandas"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = "not installed"
    return out


def default_run_dir(scenario: Scenario, root: Path = Path("reports"), suffix: str = "") -> Path:
    """``reports/<scenario>/<run id>``; the run id is the local start time plus the seed
    (a name only: no wall-clock value goes into the recorded data), then ``suffix``."""
    stamp = time.strftime("%Y%m%d-%H%M%S")
    base = root / scenario.name / f"{stamp}-s{scenario.seed}{suffix}"
    candidate, n = base, 1
    while candidate.exists():
        n += 1
        candidate = base.with_name(f"{base.name}-{n}")
    return candidate


def combined_digest(topics: Mapping[str, Any]) -> str:
    h = hashlib.sha256()
    for name in sorted(topics):
        h.update(f"{name}\0{topics[name]['sha256']}\n".encode())
    return h.hexdigest()


def topic_table(stats: Mapping[str, TopicStats], published: Mapping[str, int],
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


def sut_endpoints(suts: Sequence[tuple[str, Any, SutContext]]) -> dict[str, Any]:
    """Name → plug-in and the topics it publishes and subscribes (what a replay withholds)."""
    out: dict[str, Any] = {}
    for name, sut, ctx in suts:
        out[name] = {
            "plugin": f"{type(sut).__module__}:{type(sut).__qualname__}",
            "publishes": sorted({e.topic for e in ctx.endpoints if e.kind == "pub"}),
            "subscribes": sorted({e.topic for e in ctx.endpoints if e.kind == "sub"}),
        }
    return out


def reproduce_command(source: str, scenario: Scenario, run_dir: Path) -> str:
    return (f"srr run {source} --seed {scenario.seed} --duration {scenario.duration:g} "
            f"--out {run_dir}")
