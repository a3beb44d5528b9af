"""Entries → runs: one :class:`RunSpec` per sweep point and repeat, with its id, its folder
under the suite's output and what it asks of an executor.

Ids: ``<entry>`` for a scenario without a sweep, ``<entry>[path=value,...]`` for a sweep
point (the *group*); a run is ``<group>#<repeat>``. Folders: ``runs/<entry>/<point label or
"nominal">/r<repeat>``. A sweep point is compared with its own baseline,
``<baseline>@<label>`` (``baselines/dock_worker_crossing@speed=1.4.json``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from harness.errors import ScenarioError
from harness.run.loading import ScenarioLoads
from harness.suite.spec import Entry, SuiteSpec
from harness.suite.sweep import Point, Scalar, expand

__all__ = ["RunSpec", "plan_runs", "safe_file_name"]


@dataclass(frozen=True)
class RunSpec:
    id: str
    group: str
    entry: str
    scenario: str
    scenario_file: str
    overrides: tuple[str, ...]  # entry overrides, then the point's, then its baseline
    params: tuple[tuple[str, Scalar], ...]
    sweep: bool
    repeat: int  # 1-based
    repeats: int
    timeout_s: float | None
    run_dir: str  # POSIX, relative to the suite's output folder
    renders: bool  # has enabled cameras: asks Ray for a GPU share when the cluster has GPUs
    cost: float = 0.0  # expected work, for scheduling: simulated seconds * (1 + cameras)

    def job(self) -> dict[str, Any]:
        """What a worker needs, as plain JSON-able data."""
        return {"id": self.id, "scenario_file": self.scenario_file,
                "overrides": list(self.overrides), "run_dir": self.run_dir}


def safe_file_name(text: str) -> str:
    """A run or group id as one file name (``/`` and other separators replaced)."""
    return "".join(c if c.isalnum() or c in "_-.=,@" else "_" for c in text)


def _point_runs(entry: Entry, point: Point, renders: bool, cost: float) -> list[RunSpec]:
    label = point.label
    group = f"{entry.name}[{label}]" if label else entry.name
    overrides = entry.overrides + point.overrides()
    if label:
        overrides += (f"baseline='{entry.baseline}@{label}'",)
    folder = safe_file_name(label) if label else "nominal"
    return [RunSpec(id=f"{group}#{k}", group=group, entry=entry.name, scenario=entry.scenario,
                    scenario_file=entry.scenario_file, overrides=overrides, params=point.params,
                    sweep=bool(label), repeat=k, repeats=entry.repeat, timeout_s=entry.timeout_s,
                    run_dir=f"runs/{entry.name}/{folder}/r{k}", renders=renders,
                    cost=cost)
            for k in range(1, entry.repeat + 1)]


def plan_runs(spec: SuiteSpec, *, on_render: Callable[[], None] | None = None,
              loads: ScenarioLoads | None = None) -> tuple[RunSpec, ...]:
    """Every run of the suite, entries in order, points in grid order, repeats innermost.

    Each sweep point's scenario is loaded once here, so a path that does not exist or a value
    out of range is reported (naming where the sweep was declared) before anything runs.
    ``on_render`` is called once, as soon as a run that renders is planned (``srr suite``
    then has its hosts make their OpenGL contexts while the rest is planned). ``loads``:
    the scenarios the planning has loaded, kept for the rest of it."""
    loads = loads if loads is not None else ScenarioLoads()
    runs: list[RunSpec] = []
    for entry in spec.entries:
        for point in expand(entry.sweep):
            try:
                sc = loads(entry.scenario_file, entry.overrides + point.overrides())
            except ScenarioError as err:
                if not point.params:
                    raise
                what = f"{err.field}: {err.message}" if err.file == "--set" else str(err)
                raise ScenarioError(entry.sweep_source, f"{entry.sweep_field} ({point.label})",
                                    what) from None
            cameras = sc.camera_count
            if cameras and on_render is not None:
                on_render()
                on_render = None
            runs += _point_runs(entry, point, cameras > 0, sc.duration * (1 + cameras))
    return tuple(runs)

