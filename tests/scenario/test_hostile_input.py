"""Hostile scenario input never escapes as anything but a one-line ScenarioError."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from harness.errors import ScenarioError
from harness.scenario import load_scenario, scenario_from_mapping

KEYS = ["format_version", "name", "duration", "seed", "robots", "cameras", "workers", "zones",
        "physics", "world", "routes", "systems_under_test", "scoring", "model", "spawn",
        "position", "control", "wheelbase", "enabled", "fps", "resolution", "loading_roi",
        "waypoints", "tick_hz", "include", "clock", "clock_topic", "x", "rtsp", "port",
        "mount_path", "record", "h264", "rgb", "depth", "preset"]
scalars = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6),
                    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=12))
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.sampled_from(KEYS), inner, max_size=5)),
    max_leaves=25)
documents = st.dictionaries(st.sampled_from(KEYS), values, max_size=8)


def _check(err: ScenarioError) -> None:
    text = str(err)
    assert "\n" not in text and text.startswith("s.yaml"), text


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(documents)
def test_random_mappings_validate_or_fail_cleanly(doc: dict[str, Any]) -> None:
    doc = {"format_version": 1, "name": "fuzz", **doc}
    try:
        scenario_from_mapping(doc, "s.yaml")
    except ScenarioError as err:
        _check(err)


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.text(max_size=200))
def test_random_text_files_fail_cleanly(tmp_path: Path, text: str) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(text, encoding="utf-8")
    try:
        load_scenario(path)
    except ScenarioError as err:
        assert "\n" not in str(err)
        assert str(path) in str(err)


def test_a_valid_document_survives_a_yaml_round_trip(tmp_path: Path) -> None:
    doc = {"format_version": 1, "name": "ok", "robots": [{"name": "f", "model": "forklift"}]}
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(doc))
    assert load_scenario(path).robots[0].name == "f"
