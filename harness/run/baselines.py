"""Where a scenario's baselines live, the configuration a baseline is compared under, and
blessing a finished run as its scenario's baseline (``srr baseline bless``)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from harness import runlock
from harness.errors import ScenarioError, SrrError
from harness.metrics.types import MetricResult
from harness.regression import absolute_failures, baseline_path, comparable_config, save_baseline
from harness.run.summary import RunSummary
from harness.scenario import Scenario, load_scenario, scenario_to_mapping

__all__ = ["PROJECT_MARKERS", "NotBlessedError", "baseline_name", "baselines_dir", "bless",
           "blessing_refusal", "scene_config"]

#: What makes a folder a project root: the search for ``baselines/`` stops there.
PROJECT_MARKERS = (".git", "pyproject.toml")


class NotBlessedError(SrrError):
    """A finished run that cannot become its scenario's baseline (exit 2): it is INVALID or
    interrupted, or (without ``allow_failing``) it fails an absolute criterion."""


def _metric(data: Mapping[str, Any]) -> MetricResult:
    """A metric of a ``summary.json`` back as the :class:`MetricResult` it was written from
    (what the verdict's absolute criteria read)."""
    return MetricResult(name=str(data.get("name", "")), value=data.get("value"),
                        unit=str(data.get("unit", "")),
                        direction=data.get("direction", "none"),
                        group=data.get("group", "control"), detail=str(data.get("detail", "")),
                        verdict=data.get("verdict"))


def blessing_refusal(summary: RunSummary, *, allow_failing: bool = False) -> str | None:
    """Why the finished run of ``summary`` cannot become its scenario's baseline, or None
    when it can: the one rule of ``srr baseline bless``, ``srr run --update-baseline`` and
    ``srr suite --update-baselines``.

    An INVALID (a health gate tripped) or interrupted run never can. A run that fails an
    absolute criterion of the verdict (a required spec violated or not evaluated, the safety
    match rate in its FAIL band, a route goal not reached:
    :func:`~harness.regression.absolute_failures`) can only with ``allow_failing``: a
    baseline is the bar later runs are held to, and every later run would FAIL against it.
    The verdict itself is not the test: a run with no baseline yet is FAIL too."""
    if summary.verdict == "INVALID" or summary.interrupted or not summary.ok:
        why = " ".join("; ".join(summary.reasons).split())
        return (f"the run is {summary.verdict} ({why or 'no reason recorded'}); only a valid, "
                "complete run can become the baseline")
    if allow_failing:
        return None
    failed = absolute_failures([_metric(m) for m in summary.metrics])
    if not failed:
        return None
    what = "; ".join(" ".join(f.split(" — ")[0].split()) for f in failed)
    return (f"the run fails {'an absolute criterion' if len(failed) == 1 else 'absolute criteria'}"
            f" ({what}), and every later run would FAIL against it; add --allow-failing to "
            "bless it anyway")


def baseline_name(scenario: Scenario) -> str:
    return scenario.baseline or scenario.name


def baselines_dir(source: str, explicit: Path | None = None,
                  scenario: Scenario | None = None) -> Path:
    """The absolute baselines folder of the scenario in file ``source``, the same from any
    working directory (run, suite, replay and bless all use it):

    1. ``explicit`` (``--baselines``), relative to the working directory;
    2. the scenario's ``baselines:`` field, relative to the file that sets it;
    3. the nearest ``baselines/`` folder in the scenario file's folder or a parent, looking
       no higher than the project root (a folder with ``.git`` or ``pyproject.toml``) or
       the filesystem root;
    4. else ``baselines/`` beside the scenario file (blessing creates it).

    A scenario that comes from no file (``<scenario>``) uses ``./baselines``."""
    if explicit is not None:
        folder = Path(explicit).resolve()
        if folder.exists() and not folder.is_dir():
            raise SrrError(f"--baselines: {folder} is not a folder")
        return folder
    from_file = bool(source) and not source.startswith("<")
    if scenario is not None and scenario.baselines is not None:
        origin = scenario.source_file("baselines", source)
        base = Path(origin).resolve().parent if not origin.startswith("<") else Path.cwd()
        folder = (base / scenario.baselines).resolve()
        if folder.exists() and not folder.is_dir():
            raise ScenarioError(scenario.file_for("baselines", source), "baselines",
                                f"{folder} is not a folder")
        return folder
    if not from_file:
        return Path("baselines").resolve()
    folder = Path(source).resolve().parent
    here = folder
    while True:
        if (here / "baselines").is_dir():
            return here / "baselines"
        if any((here / m).exists() for m in PROJECT_MARKERS) or here == here.parent:
            return folder / "baselines"
        here = here.parent


def scene_config(scenario: Scenario, scene_files: Mapping[str, str] | None) -> dict[str, Any]:
    """The comparable configuration of a run: the scenario's comparable part plus, when the
    scene has model files, their digests by field (``robots[0].model`` → SHA-256), so an
    edited URDF or mesh makes another configuration even under the same path."""
    config = comparable_config(scenario_to_mapping(scenario))
    if scene_files:
        config["scene_files"] = dict(sorted(scene_files.items()))
    return config


def bless(run_dir: Path, reason: str, *, baselines: Path | None = None,
          allow_failing: bool = False) -> Path:
    """Make a finished run the baseline of its scenario (``srr baseline bless``), in
    ``baselines`` if given, else in the folder the run was judged against (its summary's
    ``baselines_dir``; for runs from before it was recorded, :func:`baselines_dir` of its
    scenario file). A run :func:`blessing_refusal` refuses is refused
    (:class:`NotBlessedError`, exit 2)."""
    return bless_if_changed(run_dir, reason, baselines=baselines, keep_unchanged=False,
                            allow_failing=allow_failing)[0]


def bless_if_changed(run_dir: Path, reason: str, *, baselines: Path | None = None,
                     keep_unchanged: bool = True,
                     allow_failing: bool = False) -> tuple[Path, bool]:
    """:func:`bless`, leaving a baseline that would only change in who blessed it when and
    why as it is (``srr suite --update-baselines``); the baseline's path and whether it was
    written."""
    runlock.refuse_if_live(run_dir)
    summary = RunSummary.read(run_dir)
    # an invalid run first, then the recording, then the criteria (what --allow-failing
    # lifts is the last thing said)
    refusal = blessing_refusal(summary, allow_failing=True)
    if refusal is None:
        # imported here: reading bags back is a bless's, never a run's start
        from harness.recording.verify import verify_recording

        verify_recording(Path(run_dir), summary.to_json())  # the bag is the summary's
        refusal = blessing_refusal(summary, allow_failing=allow_failing)
    if refusal is not None:
        raise NotBlessedError(f"{Path(run_dir).resolve()}: not blessed: {refusal}")
    scenario = load_scenario(Path(run_dir) / "scenario.yaml")
    recorded = summary.baselines_dir  # the folder the run was judged against
    path = baseline_path(baseline_name(scenario), baselines_dir(
        summary.scenario_file, baselines if baselines is not None
        else Path(recorded) if recorded else None, scenario))
    written = save_baseline(path, summary.to_json(), reason=reason, source_run=str(run_dir),
                            config=scene_config(scenario, summary.scene_files),
                            bag=Path(run_dir) / "bag", keep_unchanged=keep_unchanged)
    return path, written is not None
