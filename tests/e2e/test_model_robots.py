"""Robots from model files end to end from the CLI: the URDF diff-drive robot and the MJCF
pallet truck each drive their route through ``cmd_vel`` (goal reached, distance travelled,
scored against their blessed baselines: PASS), publish their whole TF tree with the model's
link names, and give identical digests run after run."""

from __future__ import annotations

import json
import subprocess
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

import pytest

from tests.conftest import ROOT, SCENARIOS, ModuleTmp
from tests.e2e.bagread import decoded

pytestmark = pytest.mark.slow  # every test reads a run of the module's fixture

# scenario → (robot, root link, link tree (parent, child), frames of other messages,
#             least distance travelled in metres)
CASES: dict[str, tuple[str, str, set[tuple[str, str]], set[str], float]] = {
    "diffbot_urdf": ("diffbot", "base_footprint", {
        ("base_footprint", "base_link"), ("base_link", "left_wheel"),
        ("base_link", "right_wheel"), ("base_link", "caster_link"),
        ("base_link", "lidar_link")}, {"lidar_link"}, 4.5),
    "pallet_truck_mjcf": ("pallet_truck", "chassis", {
        ("chassis", "load_wheel_left"), ("chassis", "load_wheel_right"),
        ("chassis", "steer_link"), ("steer_link", "traction_wheel")}, set(), 9.0),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def run(request: pytest.FixtureRequest, module_tmp: ModuleTmp,
        ) -> tuple[str, Path]:
    name = str(request.param)
    out = module_tmp(name)
    done = subprocess.run([sys.executable, "-m", "harness.cli", "run",
                           str(SCENARIOS / f"{name}.yaml"), "--repeat", "2", "--out", str(out),
                           "-q"], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "identical per-topic digests across 2 runs" in done.stdout
    return name, out


def test_report_rebuilds_the_graphs_with_the_model_file(run: tuple[str, Path]) -> None:
    """The report rebuilds the action graphs from the run's scenario, with the model file
    found relative to the scenario file the run was started from (not the run directory)."""
    name, out = run
    robot = CASES[name][0]
    html = (out / "run_1" / "report.html").read_text()
    assert "could not be rebuilt" not in html and f"/World/{robot}_TfGraph" in html


def test_repeats_give_identical_digests_and_pass(run: tuple[str, Path]) -> None:
    _, out = run
    report = json.loads((out / "determinism.json").read_text())
    assert report["identical"] and len(set(report["digests"])) == 1
    summary = json.loads((out / "run_1" / "summary.json").read_text())
    assert summary["verdict"] == "PASS"


def test_route_driven_through_cmd_vel(run: tuple[str, Path]) -> None:
    name, out = run
    summary = json.loads((out / "run_1" / "summary.json").read_text())
    metrics = {m["name"]: m["value"] for m in summary["metrics"]}
    assert metrics["control.goal_reached"] == 1
    assert metrics["control.distance_travelled"] > CASES[name][4]
    assert metrics["control.cross_track_error.mean"] < 0.25
    assert summary["topics"]["/cmd_vel"]["count"] > 0


def test_full_tf_tree_with_the_models_link_names(run: tuple[str, Path]) -> None:
    name, out = run
    robot, root, links, frames, _ = CASES[name]
    edges: dict[str, set[tuple[str, str]]] = defaultdict(set)
    used: set[str] = set()
    for topic, _, _, msg in decoded(out / "run_1"):
        transforms: Any = getattr(msg, "transforms", None)
        if transforms is not None:
            edges[topic] |= {(t.header.frame_id, t.child_frame_id) for t in transforms}
        elif hasattr(msg, "header"):
            used.add(msg.header.frame_id)
    assert edges["/tf_static"] == {("world", "odom")}
    assert edges["/tf"] == {("odom", root)} | links
    assert edges[f"/gt/{robot}/tf"] == {("world", robot)}
    tree = {c for _, c in edges["/tf"]} | {"world", "odom"}
    assert frames <= used <= tree  # every message's frame is in the recorded tree
