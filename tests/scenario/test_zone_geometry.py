"""Zone geometry a user gets wrong: a polygon that crosses itself (a bow-tie) is refused
naming its two crossing edges, and the JSON Schema asks for three points or none; a trailer
tripwire whose ``inside`` side holds every robot's spawn and every route waypoint (the whole
room past it: the safety monitor mutes from the start) is a warning of validate and run."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest

from harness.cli import main

ROOM = """\
format_version: 1
name: t
duration: 2
world: {size: [30, 20]}
robots:
  - {name: forklift, model: forklift, spawn: {position: [0, 0, 0]}}
"""


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "scenario.yaml"
    path.write_text(ROOM + text)
    return path


@pytest.mark.parametrize(("text", "field", "edges"), [
    # a symmetric bow-tie: zero signed area, which used to read "the polygon has zero area"
    ("zones: {loading_roi: [[0, 0], [4, 4], [4, 0], [0, 4]]}", "zones.loading_roi",
     "its edge from point 0 [0.0, 0.0] to point 1 [4.0, 4.0] meets its edge from point 2 "
     "[4.0, 0.0] to point 3 [0.0, 4.0]"),
    # a lopsided one: non-zero signed area, which used to pass silently
    ("scoring: {perception: {area: [[0, 0], [6, 3], [6, 0], [0, 4]]}}",
     "scoring.perception.area",
     "its edge from point 0 [0.0, 0.0] to point 1 [6.0, 3.0] meets its edge from point 2 "
     "[6.0, 0.0] to point 3 [0.0, 4.0]"),
    # five points: the first crossing found is named (edge 3 also crosses edge 1)
    ("zones: {loading_roi: [[0, 0], [4, 0], [0, 3], [4, 3], [2, -1]]}", "zones.loading_roi",
     "its edge from point 0 [0.0, 0.0] to point 1 [4.0, 0.0] meets its edge from point 3 "
     "[4.0, 3.0] to point 4 [2.0, -1.0]"),
], ids=["bow-tie", "lopsided-bow-tie", "pentagon"])
def test_a_self_crossing_polygon_is_refused_naming_the_edges(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, field: str,
        edges: str) -> None:
    path = _write(tmp_path, text + "\n")
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.splitlines() == [
        f"srr validate: {path}: {field}: the polygon crosses itself: {edges}; list the points "
        "in order around the polygon"], err


def test_a_simple_polygon_in_any_order_of_turn_is_accepted(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for roi in ("[[0, 0], [4, 0], [4, 4], [0, 4]]", "[[0, 4], [4, 4], [4, 0], [0, 0]]",
                "[[0, 0], [4, 0], [2, 1], [4, 4], [0, 4]]"):  # concave
        path = _write(tmp_path, f"zones: {{loading_roi: {roi}}}\n")
        assert main(["validate", str(path)]) == 0, capsys.readouterr().err
        capsys.readouterr()


def test_the_json_schema_asks_a_polygon_for_three_points_or_none(
        capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    validator = jsonschema.Draft202012Validator(schema)
    for zones, ok in (({"loading_roi": []}, True),
                      ({"loading_roi": [[0, 0], [1, 0], [0, 1]]}, True),
                      ({"loading_roi": [[0, 0], [1, 0]]}, False)):
        doc = {"format_version": 1, "name": "t", "zones": zones}
        assert validator.is_valid(doc) is ok, zones
    doc = {"format_version": 1, "name": "t", "scoring": {"perception": {"area": [[0, 0]]}}}
    assert not validator.is_valid(doc)


WIRE = "routes:\n  go: {waypoints: [[0, 0], [10, 0]]}\n" \
       "zones:\n  trailer_tripwire: {a: [12, 3], b: [12, -3], inside: %s}\n"


def test_a_tripwire_with_the_whole_room_inside_is_a_warning(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # a → b runs along -y, so its left is +x: the robot at x 0 and its route up to x 10 lie
    # on its right
    path = _write(tmp_path, WIRE % "right")
    assert main(["validate", str(path)]) == 0
    err = capsys.readouterr().err
    mine = [line for line in err.splitlines() if "past the tripwire" in line]
    assert mine == [
        f"srr validate: warning: {path}: zones.trailer_tripwire.inside: 'right' puts every "
        "robot's spawn and every route waypoint past the tripwire a [12.0, 3.0] → b [12.0, "
        "-3.0] (right of a → b, seen from above, is toward -x): the robot is in the trailer "
        "from the first tick and never crosses in, so the safety monitor mutes from the start "
        "unless a worker is in the loading ROI; if the trailer is on the other side, inside: "
        "left"], err


def test_a_safety_monitors_own_tripwire_is_checked_too(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _write(tmp_path, WIRE % "left" + (
        "systems_under_test:\n  - name: safety_monitor\n"
        "    plugin: harness.sut.safety_monitor:SafetyMonitor\n"
        "    params: {tripwire: [[-20, 3], [-20, -3]], inside: left,"
        " roi: [[0, 5], [2, 5], [2, 7]]}\n"))
    assert main(["validate", str(path)]) == 0
    err = capsys.readouterr().err
    mine = [line for line in err.splitlines() if "past the tripwire" in line]
    assert mine == [
        f"srr validate: warning: {path}: systems_under_test[0].params.inside: 'left' puts "
        "every robot's spawn and every route waypoint past the tripwire a [-20.0, 3.0] → b "
        "[-20.0, -3.0] (left of a → b, seen from above, is toward +x): the robot is in the "
        "trailer from the first tick and never crosses in, so the safety monitor mutes from "
        "the start unless a worker is in the loading ROI; if the trailer is on the other "
        "side, inside: right"], err


@pytest.mark.parametrize("text", [
    WIRE % "left",  # the trailer past x 12: the route stops short of it
    # the route drives in: its end is past the tripwire, its start is not
    "routes:\n  go: {waypoints: [[0, 0], [14, 0]]}\n"
    "zones:\n  trailer_tripwire: {a: [12, 3], b: [12, -3], inside: left}\n",
    # the robot starts in the trailer and drives out
    "routes:\n  go: {waypoints: [[0, 0], [-14, 0]]}\n"
    "zones:\n  trailer_tripwire: {a: [-12, 3], b: [-12, -3], inside: left}\n",
], ids=["outside", "drives-in", "drives-out"])
def test_a_tripwire_some_point_lies_outside_of_is_no_warning(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str) -> None:
    path = _write(tmp_path, text)
    assert main(["validate", str(path)]) == 0
    assert "past the tripwire" not in capsys.readouterr().err
