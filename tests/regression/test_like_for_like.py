"""A baseline is only compared with runs of its own configuration; anything else is MISMATCH
with the differing fields named, never a silent comparison (nor a misleading REGRESSED)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from harness import api
from harness.regression import comparable_config, config_differences, with_defaults
from harness.scenario import load_scenario, scenario_to_mapping
from harness.sim import World
from tests.conftest import SCENARIOS

FW = SCENARIOS / "forklift_warehouse.yaml"


def mapping(*overrides: str) -> dict[str, object]:
    return scenario_to_mapping(api.load(FW, overrides=list(overrides)))


def test_what_counts_as_the_configuration() -> None:
    base = mapping()
    assert config_differences(base, base) == []
    assert config_differences(base, mapping("duration=8")) == ["duration: 35.0 → 8.0"]
    assert config_differences(base, mapping("seed=9", "physics.substeps=8")) == [
        "physics.substeps: 4 → 8", "seed: 7 → 9"]
    assert config_differences(base, mapping("robots.forklift.spawn.position=[-12, -2, 0]")) \
        == ["robots[0].spawn.position: [-12.0, -3.0, 0.0] → [-12.0, -2.0, 0.0]"]
    # what a regression test varies does not count: the systems under test, tolerances,
    # names, health settings
    same = mapping("systems_under_test.route_follower.params.speed=1.0", "name=other",
                   "scoring.tolerances={control.*: {abs: 1}}",
                   "scoring.health.rate_fraction=0.5", "render.overlap=false")
    assert config_differences(base, same) == []
    # how images look does count (rendering on a background thread or not gives the same bytes)
    assert config_differences(base, mapping("render.shadows=true")) == [
        "render.shadows: False → True"]
    assert "systems_under_test" not in comparable_config(base)
    many = mapping("routes.dock_approach.waypoints=[[0, 0], [0, 1]]", "duration=1", "seed=1",
                   "srr_gt=false", "world.wall_height=3", "physics.tick_hz=30")
    diffs = config_differences(base, many, limit=4)
    assert len(diffs) == 5 and diffs[-1].startswith("… and ")


@pytest.mark.slow
def test_a_shortened_run_is_a_mismatch_not_a_regression(tmp_path: Path) -> None:
    res = api.run_scenario(api.load(FW, duration=2.0), source=str(FW), out=tmp_path / "r")
    assert (res.verdict, res.exit_code) == ("MISMATCH", 1)
    assert res.summary["reasons"][0].startswith(
        "not compared: the baseline was recorded with another configuration (duration: "
        "35.0 → 2.0)")
    assert res.summary["baseline"]["config_differences"] == ["duration: 35.0 → 2.0"]
    html = (res.run_dir / "report.html").read_text()
    assert "Not compared: the baseline was recorded with another configuration" in html
    assert "duration: 35.0 → 2.0" in html


@pytest.mark.slow
def test_a_baseline_without_a_recorded_configuration_is_still_compared(tmp_path: Path) -> None:
    """Baselines blessed before the configuration was recorded compare as before, and the
    summary says the configuration was not checked."""
    bdir = tmp_path / "baselines"
    bdir.mkdir()
    data = json.loads((SCENARIOS.parent / "baselines" / "forklift_warehouse.json").read_text())
    del data["config"]
    (bdir / "forklift_warehouse.json").write_text(json.dumps(data))
    res = api.run_scenario(api.load(FW, duration=2.0), source=str(FW), out=tmp_path / "r",
                           baselines=bdir)
    assert res.verdict == "REGRESSED"  # compared: 2 s do not reach the goal
    assert res.summary["baseline"]["config_checked"] is False


@pytest.mark.slow
def test_blessing_records_the_configuration(tmp_path: Path) -> None:
    sc = api.load(FW, duration=1.0)
    res = api.run_scenario(sc, source=str(FW), out=tmp_path / "r")
    shutil.copy(FW, tmp_path / "forklift_warehouse.yaml")
    bdir = tmp_path / "b"
    path = api.bless(res.run_dir, "one second", baselines=bdir,
                     allow_failing=True)  # its route's goal not reached in one second
    stored = json.loads(path.read_text())["config"]
    assert stored == comparable_config(scenario_to_mapping(load_scenario(
        res.run_dir / "scenario.yaml")))
    assert stored["duration"] == 1.0
    again = api.run_scenario(sc, source=str(FW), out=tmp_path / "r2", baselines=bdir)
    assert {e["status"] for e in again.summary["comparison"]} == {"ok"}  # compared, held
    assert again.summary["baseline"]["config_differences"] == []
    # (a one-second drive does not reach the goal: that absolute criterion still fails)
    assert again.verdict == "FAIL" and len(again.summary["reasons"]) == 1


@pytest.mark.parametrize("name", ["forklift_warehouse", "two_forklifts", "dock_empty",
                                  "dock_nominal", "dock_worker_crossing",
                                  "dock_worker_standing"])
def test_shipped_baselines_record_their_configuration(name: str) -> None:
    """Each is the scenario's configuration; a baseline blessed before ``graphs:`` and
    ``render:`` existed (as the forklift scenes' were until they were re-blessed) reads those
    fields as their defaults."""
    data = json.loads((SCENARIOS.parent / "baselines" / f"{name}.json").read_text())
    want = comparable_config(scenario_to_mapping(api.load(SCENARIOS / f"{name}.yaml")))
    assert with_defaults(data["config"]) == want
    if name in ("forklift_warehouse", "two_forklifts"):  # both fields at their defaults
        older = {k: v for k, v in data["config"].items() if k not in ("graphs", "render")}
        assert with_defaults(older) == want


@pytest.mark.slow
def test_an_edited_model_file_is_another_configuration(tmp_path: Path) -> None:
    """The baseline records the digest of the robot's model file (and its meshes): a copy of
    the scene compares like for like, the same path with an edited file does not."""
    for name in ("same", "edited"):
        shutil.copytree(SCENARIOS / "models" / "pallet_truck",
                        tmp_path / name / "models" / "pallet_truck")
        shutil.copy(SCENARIOS / "pallet_truck_mjcf.yaml", tmp_path / name)
    xml = tmp_path / "edited" / "models" / "pallet_truck" / "pallet_truck.xml"
    xml.write_text(xml.read_text().replace('kv="800"', 'kv="400"'))
    bdir = SCENARIOS.parent / "baselines"
    stored = json.loads((bdir / "pallet_truck_mjcf.json").read_text())["config"]
    assert set(stored["scene_files"]) == {"robots[0].model"}
    diffs = {}
    for name in ("same", "edited"):
        path = tmp_path / name / "pallet_truck_mjcf.yaml"
        res = api.run_scenario(api.load(path, duration=1.0), source=str(path),
                               out=tmp_path / f"run_{name}", baselines=bdir)
        assert res.verdict == "MISMATCH"  # one second, not eleven
        diffs[name] = res.summary["baseline"]["config_differences"]
    assert diffs["same"] == ["duration: 11.0 → 1.0"]
    assert diffs["edited"][0] == "duration: 11.0 → 1.0"
    assert diffs["edited"][1].startswith(
        f"scene_files.robots[0].model: '{stored['scene_files']['robots[0].model']}' → '")


def test_a_world_file_is_part_of_the_configuration() -> None:
    """The shelf world's baseline records its world file's digest, which the run computes
    from the file and its meshes as they are now."""
    path = SCENARIOS / "shelf_world_mjcf.yaml"
    stored = json.loads((SCENARIOS.parent / "baselines" / "shelf_world_mjcf.json").read_text())
    world = World.build(load_scenario(path), str(path))
    assert dict(world.scene_files) == stored["config"]["scene_files"]
    assert set(world.scene_files) == {"world.model"}


def test_a_list_that_gained_its_first_item_says_so_in_the_right_direction() -> None:
    """A baseline without workers against a run with one: the lines are the worker's own
    fields, added (not the run's ``workers`` said to be absent)."""
    base = {"workers": [], "seed": 1}
    run = {"workers": [{"enabled": True, "speed": 1.0}], "seed": 1}
    assert config_differences(base, run) == ["workers[0].enabled: (absent) → True",
                                             "workers[0].speed: (absent) → 1.0"]
    assert config_differences(run, base) == ["workers[0].enabled: True → (absent)",
                                             "workers[0].speed: 1.0 → (absent)"]
