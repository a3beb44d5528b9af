"""Where a scenario's baselines live, the configuration a baseline is compared under, and
blessing a finished run as its scenario's baseline (``srr baseline bless``)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from harness import runlock
from harness.errors import ScenarioError, SrrError
from harness.regression import baseline_path, comparable_config, save_baseline
from harness.run.summary import RunSummary
from harness.scenario import Scenario, load_scenario, scenario_to_mapping

__all__ = ["PROJECT_MARKERS", "baseline_name", "baselines_dir", "bless", "scene_config"]

#: What makes a folder a project root: the search for ``baselines/`` stops there.
PROJECT_MARKERS = (".git", "pyproject.toml")


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


def bless(run_dir: Path, reason: str, *, baselines: Path | None = None) -> Path:
    """Make a finished run the baseline of its scenario (``srr baseline bless``), in
    ``baselines`` if given, else in the folder the run was judged against (its summary's
    ``baselines_dir``; for runs from before it was recorded, :func:`baselines_dir` of its
    scenario file). An INVALID or interrupted run is refused (SrrError, exit 2)."""
    return bless_if_changed(run_dir, reason, baselines=baselines, keep_unchanged=False)[0]


def bless_if_changed(run_dir: Path, reason: str, *, baselines: Path | None = None,
                     keep_unchanged: bool = True) -> tuple[Path, bool]:
    """:func:`bless`, leaving a baseline that would only change in who blessed it when and
    why as it is (``srr suite --update-baselines``); the baseline's path and whether it was
    written."""
    runlock.refuse_if_live(run_dir)
    summary = RunSummary.read(run_dir)
    if summary.verdict == "INVALID" or summary.interrupted:
        why = " ".join("; ".join(summary.reasons).split())
        raise SrrError(f"{Path(run_dir).resolve()}: not blessed: the run is "
                       f"{summary.verdict} ({why or 'no reason recorded'}); "
                       "only a valid, complete run can become the baseline")
    # imported here: reading bags back is a bless's, never a run's start
    from harness.recording.verify import verify_recording

    verify_recording(Path(run_dir), summary.to_json())  # the bag is the summary's
    scenario = load_scenario(Path(run_dir) / "scenario.yaml")
    recorded = summary.baselines_dir  # the folder the run was judged against
    path = baseline_path(baseline_name(scenario), baselines_dir(
        summary.scenario_file, baselines if baselines is not None
        else Path(recorded) if recorded else None, scenario))
    written = save_baseline(path, summary.to_json(), reason=reason, source_run=str(run_dir),
                            config=scene_config(scenario, summary.scene_files),
                            bag=Path(run_dir) / "bag", keep_unchanged=keep_unchanged)
    return path, written is not None
