"""The safety team's dock scenes against their shipped baselines, and the degraded variants
that must be caught. These run the real stack: MuJoCo, rendered depth cameras, the reference
perception and safety monitor, the bag, the metrics and the baseline comparison."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness.cli import main

pytestmark = pytest.mark.slow
SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


def _run(capsys: pytest.CaptureFixture[str], scenario: Path, out: Path,
         *extra: str) -> tuple[int, dict, str]:  # type: ignore[type-arg]
    code = main(["run", str(scenario), "--out", str(out), "-q", *extra])
    printed = capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    return code, summary, printed


@pytest.mark.parametrize("name", ["dock_nominal", "dock_worker_crossing", "dock_worker_standing",
                                  "dock_empty"])
def test_nominal_scene_passes_against_its_baseline(name: str, tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    code, summary, printed = _run(capsys, SCENARIOS / f"{name}.yaml", tmp_path / "r")
    assert code == 0, printed
    assert summary["verdict"] == "PASS" and summary["baseline"] is not None
    statuses = {e["status"] for e in summary["comparison"]}
    assert statuses <= {"ok", "improved"}, printed
    match = {m["name"]: m for m in summary["metrics"]}["safety.match_rate"]
    assert match["value"] >= 95.0 and match["verdict"] == "PASS"


def test_crossing_worker_unmutes_while_in_the_roi(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """The recorded /safety/is_muted drops while the worker is in the ROI (24.5–30.5 s)."""
    from tests.e2e.bagread import decoded

    code, _, printed = _run(capsys, SCENARIOS / "dock_worker_crossing.yaml", tmp_path / "r")
    assert code == 0, printed
    muted = [(t / 1e9, msg.data) for topic, _, t, msg in decoded(tmp_path / "r")
             if topic == "/safety/is_muted"]
    state_at = dict(muted)

    def at(t: float) -> bool:
        return state_at[min(state_at, key=lambda s: abs(s - t))]

    assert not at(10.0)  # forklift still outside the trailer
    assert at(23.0)  # inside, ROI clear
    assert not at(27.5)  # worker in the ROI
    assert at(33.5)  # worker gone again


@pytest.mark.parametrize(("variant", "metric"), [
    ("dock_worker_crossing_short_range", "perception.recall"),
    ("dock_worker_crossing_slow_reaction", "safety.mute_lag.p50"),
])
def test_degraded_variant_exits_1_naming_the_metric(variant: str, metric: str, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    code, summary, printed = _run(capsys, SCENARIOS / "regressions" / f"{variant}.yaml",
                                  tmp_path / "r")
    assert code == 1
    assert summary["verdict"] == "REGRESSED"
    assert summary["baseline"]["path"].endswith("dock_worker_crossing.json")
    (reason,) = [r for r in summary["reasons"] if r.startswith(metric + ":")]
    assert "vs baseline" in reason and "tolerance ±" in reason and "regressed" in reason
    assert reason in printed  # the console names it too
    assert summary["comparison"][0]["status"] == "regressed"  # regressions first


def test_disabled_perception_is_refused_before_running(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    """The scoring reads /perception/tracks; with its publisher switched off that is known
    before the first tick: exit 2 naming the field, no run directory."""
    code = main(["run", str(SCENARIOS / "dock_worker_crossing.yaml"), "--out",
                 str(tmp_path / "r"), "-q", "--set", "systems_under_test.perception.enabled=false"])
    err = capsys.readouterr().err
    assert code == 2
    assert "scoring.health.sut_outputs./perception/tracks: nothing in the scenario publishes " \
           "/perception/tracks" in err
    assert not (tmp_path / "r").exists()


def test_a_system_under_test_that_goes_quiet_makes_the_run_invalid(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The safety monitor advertises /safety/is_muted but publishes only every 10 s: after its
    first message it is silent for longer than the 0.5 s allowed, and the run is INVALID."""
    code, summary, _printed = _run(
        capsys, SCENARIOS / "dock_worker_crossing.yaml", tmp_path / "r", "--duration", "4",
        "--set", "systems_under_test.safety_monitor.params.rate_hz=0.1")
    assert code == 3
    assert summary["verdict"] == "INVALID"
    assert any("/safety/is_muted" in r and "silent for the last" in r
               for r in summary["reasons"]), summary["reasons"]
