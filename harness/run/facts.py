"""The small facts every run summary carries: the versions it ran with, its per-topic table
and combined digest, the command that reproduces it, and the default run directory name."""

from __future__ import annotations

import hashlib
import json
import platform
import shlex
import time
from collections.abc import Mapping, Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

from harness import __version__, yamlio
from harness.recording import TopicStats
from harness.run.summary import TopicRow
from harness.scenario import Scenario, scenario_to_mapping
from harness.sut.base import SutContext
from harness.sut.participant import plugin_of

__all__ = [
    "combined_digest",
    "default_run_dir",
    "reproduce_command",
    "scenario_path",
    "scenario_text",
    "sut_endpoints",
    "topic_table",
    "versions",
    "write_scenario",
]


def versions(gl_renderer: str | None = None) -> dict[str, str]:
    """srr's, Python's and the recording libraries' versions, and for a run that rendered,
    the OpenGL renderer that drew its images (``gl_renderer``: camera images are the
    driver's, so a GPU and Mesa's llvmpipe record different pixels)."""
    out = {"srr": __version__, "python": platform.python_version()}
    for dist in ("mujoco", "numpy", "rosbags", "mcap", "pandas"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = "not installed"
    if gl_renderer:
        out["gl_renderer"] = gl_renderer
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


def combined_digest(topics: Mapping[str, TopicRow]) -> str:
    """One SHA-256 over every topic's name and digest, in name order."""
    h = hashlib.sha256()
    for name in sorted(topics):
        h.update(f"{name}\0{topics[name].sha256}\n".encode())
    return h.hexdigest()


def topic_table(stats: Mapping[str, TopicStats], published: Mapping[str, int],
                duration_s: float) -> dict[str, TopicRow]:
    """Each recorded topic's row: its type, messages recorded and published, rate over
    ``duration_s`` of simulated time, bytes, SHA-256 and durability."""
    return {name: TopicRow(type=st.msgtype, count=st.count, sha256=st.sha256,
                           published=published.get(name, 0),
                           rate_hz=round(st.count / duration_s if duration_s > 0 else 0.0, 3),
                           bytes=st.bytes, durability=st.durability)
            for name, st in stats.items()}


def sut_endpoints(suts: Sequence[tuple[str, Any, SutContext]]) -> dict[str, Any]:
    """Name → plug-in and the topics it publishes and subscribes (what a replay withholds)."""
    out: dict[str, Any] = {}
    for name, sut, ctx in suts:
        plugin = type(plugin_of(sut))
        out[name] = {
            "plugin": f"{plugin.__module__}:{plugin.__qualname__}",
            "publishes": sorted({e.topic for e in ctx.endpoints if e.kind == "pub"}),
            "subscribes": sorted({e.topic for e in ctx.endpoints if e.kind == "sub"}),
        }
    return out


def scenario_path(source: str) -> str:
    """The scenario file ``source`` names, as a run directory records it (``summary.json``'s
    ``scenario_file``, the command that reproduces the run): absolute, its folder resolved
    (``..`` and links), so that it means the same file from any directory; the file itself is
    not followed through a link, since its folder is where its includes and baselines are
    found. A name that is no file (``<scenario>``) as it is."""
    path = Path(source)
    return str(path.parent.resolve() / path.name) if path.is_file() else source


def reproduce_command(source: str, scenario: Scenario, run_dir: Path,
                      baselines: Path | None = None) -> str:
    """The ``srr run`` command line that records this run again (into ``run_dir``, once it is
    moved away): the scenario file, seed and duration, every ``--set`` the scenario was
    loaded with (values as JSON, which YAML reads back the same) and ``--baselines`` when
    one was given; paths absolute, so it works from any directory."""
    args = ["srr", "run", scenario_path(source), "--seed", str(scenario.seed),
            "--duration", f"{scenario.duration:g}"]
    for key, value in scenario.overrides:
        if key not in ("seed", "duration"):  # said above
            args += ["--set", f"{key}={json.dumps(value)}"]
    if baselines is not None:
        args += ["--baselines", str(Path(baselines).absolute())]
    return shlex.join([*args, "--out", str(Path(run_dir).absolute())])


def scenario_text(scenario: Scenario) -> str:
    """The resolved scenario (includes expanded, defaults filled, overrides applied) as YAML
    that srr reads back the same (a run's ``scenario.yaml``, a search's counterexamples)."""
    return yamlio.dump(scenario_to_mapping(scenario), sort_keys=False)


def write_scenario(run_dir: Path, scenario: Scenario) -> None:
    """The run directory's ``scenario.yaml`` (:func:`scenario_text`)."""
    (Path(run_dir) / "scenario.yaml").write_text(scenario_text(scenario), encoding="utf-8")
