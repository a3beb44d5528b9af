"""Loading, includes, defaults and overrides produce the typed, frozen model."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from harness.errors import ScenarioError
from harness.scenario import (
    DiffDriveControl,
    ForkliftControl,
    load_scenario,
    parse_override,
    scenario_from_mapping,
    scenario_to_mapping,
)


def test_bundled_scenario_resolves_includes(scenarios_dir: Path) -> None:
    sc = load_scenario(scenarios_dir / "forklift_warehouse.yaml")
    assert sc.name == "forklift_warehouse"
    (robot,) = sc.robots
    assert robot.name == "forklift" and robot.prim == "/World/forklift"
    assert isinstance(robot.control, ForkliftControl)
    assert robot.control.wheelbase == 1.49 and robot.control.wheel_radius == 0.15
    assert robot.odometry.robot_front == (-1.0, 0.0, 0.0)
    assert sc.clock.clock_topic == "clock"
    with pytest.raises(dataclasses.FrozenInstanceError):
        sc.seed = 3  # type: ignore[misc]


def test_overrides_by_index_and_by_name(scenarios_dir: Path) -> None:
    path = scenarios_dir / "forklift_warehouse.yaml"
    sc = load_scenario(path, [parse_override("robots.forklift.control.wheelbase=1.6"),
                              parse_override("robots.0.spawn.position=[1, 2, 0]"),
                              parse_override("seed=11")])
    assert sc.robots[0].control_spec.wheelbase == 1.6  # type: ignore[union-attr]
    assert sc.robots[0].spawn.position == (1.0, 2.0, 0.0)
    assert sc.seed == 11
    # the [i] form every error message writes works too
    assert parse_override("robots[0].spawn.position=[3, 2, 0]") == (
        "robots.0.spawn.position", [3, 2, 0])
    sc = load_scenario(path, [parse_override("robots[0].spawn.position=[3, 2, 0]")])
    assert sc.robots[0].spawn.position == (3.0, 2.0, 0.0)


def test_control_block_follows_model() -> None:
    sc = scenario_from_mapping({"format_version": 1, "name": "x", "robots": [
        {"name": "tb", "model": "turtlebot3_waffle_pi",
         "control": {"wheel_distance": 0.3}}]})
    assert isinstance(sc.robots[0].control, DiffDriveControl)
    assert sc.robots[0].control.wheel_distance == 0.3


def test_resolved_mapping_round_trips(scenarios_dir: Path) -> None:
    sc = load_scenario(scenarios_dir / "forklift_warehouse.yaml")
    again = scenario_from_mapping(scenario_to_mapping(sc))
    assert again == sc


def test_extending_with_plus_is_for_scenario_files() -> None:
    with pytest.raises(ScenarioError, match=r"to add to a list, write `robots\+:` in a "
                                            "scenario file"):
        parse_override("robots+=[]")


def test_a_list_index_counts_from_zero_only(scenarios_dir: Path) -> None:
    """``robots.-1`` is no item (error messages count items from 0; a Python negative index
    would quietly pick the last)."""
    path = scenarios_dir / "forklift_warehouse.yaml"
    with pytest.raises(ScenarioError, match=r"robots\.-1: no list item with that index or name"):
        load_scenario(path, [parse_override("robots.-1.name=x")])


def test_api_load_takes_one_override_as_a_string_too() -> None:
    # a str is a sequence of one-character strings: "seed=3" was read as "s", "e", ...
    from harness import api

    path = Path(__file__).resolve().parents[2] / "scenarios" / "forklift_warehouse.yaml"
    assert api.load(path, overrides="seed=3").seed == 3
    assert api.load(path, overrides=["seed=4"]).seed == 4
