# mypy: disable-error-code="no-untyped-def"
"""Seed 001 end to end: the bundled camera_publishing scenario from the CLI, the camera TF
read back from bags with the independent reader, point clouds placed by that TF on known
geometry, and the seed's ``publish_camera_tf`` ported by changing imports."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from harness import api
from harness.builders import camera_tf
from harness.cli import main
from harness.engine import Simulation
from harness.scenario.schema import (
    CameraSpec,
    DockSpec,
    Pose,
    Scenario,
    WorldSpec,
)
from tests import seed001
from tests.conftest import SCENARIOS, ModuleTmp
from tests.e2e.bagread import decoded
from tests.seed001 import Camera, publish_camera_tf

pytestmark = pytest.mark.slow

SEED_TOPICS = {"/clock", "/floating_camera_rgb", "/floating_camera_depth",
               "/floating_camera_pointcloud", "/floating_camera_camera_info", "/tf", "/tf_static"}


def transforms(run_dir: Path) -> tuple[dict[tuple[str, str], list[Any]], list[Any]]:
    """(parent, child) → transforms in order, and every point cloud, from a recorded bag."""
    tfs: dict[tuple[str, str], list[Any]] = {}
    clouds = []
    for topic, _, _, msg in decoded(run_dir):
        if topic in ("/tf", "/tf_static"):
            for t in msg.transforms:
                tfs.setdefault((t.header.frame_id, t.child_frame_id), []).append(t)
        elif topic.endswith("_pointcloud"):
            clouds.append(msg)
    return tfs, clouds


def pose(t: Any) -> tuple[np.ndarray, Rotation]:
    tr, q = t.transform.translation, t.transform.rotation
    return np.array([tr.x, tr.y, tr.z]), Rotation.from_quat([q.x, q.y, q.z, q.w])


def cloud_points(msg: Any) -> np.ndarray:
    assert [f.name for f in msg.fields] == ["x", "y", "z"] and msg.point_step == 12
    return np.frombuffer(bytes(msg.data), "<f4").reshape(-1, 3).astype(np.float64)


def at_stamp(tfs: list[Any], stamp: Any) -> Any:
    (match,) = [t for t in tfs if (t.header.stamp.sec, t.header.stamp.nanosec)
                == (stamp.sec, stamp.nanosec)]
    return match


# ----------------------------------------------------------------------------- the scenario

@pytest.fixture(scope="module")
def repeat_dir(module_tmp: ModuleTmp) -> Path:
    out = module_tmp("camera_publishing") / "rep"
    code = main(["run", str(SCENARIOS / "camera_publishing.yaml"), "--duration", "0.25",
                 "--repeat", "2", "--out", str(out), "-q"])
    assert code == 1  # recorded, identical, but nothing scored: UNSCORED is not a pass
    return out


def test_cli_runs_are_identical_and_publish_exactly_the_seed_topics(repeat_dir: Path) -> None:
    report = json.loads((repeat_dir / "determinism.json").read_text())
    assert report["identical"] and report["differing_topics"] == []
    assert report["digests"][0] == report["digests"][1]
    summary = json.loads((repeat_dir / "run_1" / "summary.json").read_text())
    assert summary["verdict"] == "UNSCORED"
    assert set(summary["topics"]) == SEED_TOPICS
    counts = Counter(topic for topic, _, _, _ in decoded(repeat_dir / "run_1"))
    assert set(counts) == SEED_TOPICS
    # 15 ticks: /clock and /tf every tick, the camera every 2nd (ticks 0, 2, ..., 14).
    assert counts["/clock"] == counts["/tf"] == 15 and counts["/tf_static"] == 1
    for stream in ("rgb", "depth", "pointcloud", "camera_info"):
        assert counts[f"/floating_camera_{stream}"] == 8


def test_seed_frames_and_a_cloud_that_lands_in_the_warehouse(repeat_dir: Path) -> None:
    tfs, clouds = transforms(repeat_dir / "run_1")
    assert set(tfs) == {("world", "floating_camera"), ("floating_camera", "floating_camera_world")}
    cam_t, cam_r = pose(tfs[("world", "floating_camera")][0])
    np.testing.assert_allclose(cam_t, [-3.11, -1.87, 1.0], atol=1e-9)
    # The optical frame of a camera looking along world +X: ROS's standard (x, y, z, w) =
    # (-0.5, 0.5, -0.5, 0.5) = rpy (-90, 0, -90) deg.
    standard = Rotation.from_euler("xyz", [-90, 0, -90], degrees=True)
    assert (cam_r.inv() * standard).magnitude() < 1e-9
    _, static_r = pose(tfs[("floating_camera", "floating_camera_world")][0])
    assert (cam_r * static_r).magnitude() < 1e-9  # floating_camera_world = the seed's identity
    pts = cam_r.apply(cloud_points(clouds[0])) + cam_t
    assert len(pts) > 0.5 * 256 * 256  # the sky (top third) has no depth
    # Inside the hall (walls at x = -15, y = +-10) or the trailer seen through the dock door
    # (default dock at x = 12, 12 m long).
    assert (pts[:, 2] > -0.02).all() and (np.abs(pts[:, 1]) < 10.02).all()
    assert (pts[:, 0] > -15.02).all() and (pts[:, 0] < 24.1).all()
    assert np.mean(np.abs(pts[:, 2]) < 0.02) > 0.25  # the floor in the lower part
    # The forklift, parked side-on at x = 1.5, fills the middle of the image.
    centre = cloud_points(clouds[0])
    on_axis = centre[np.argmin(np.hypot(centre[:, 0], centre[:, 1]))]
    world_hit = cam_r.apply(on_axis) + cam_t
    assert 0.5 < world_hit[0] < 1.5 and abs(world_hit[1] + 1.87) < 0.05


# ----------------------------------------------------------------------------- known geometry

HALL = WorldSpec(size=(30.0, 20.0), wall_height=4.0, shelves=(), dock=DockSpec(enabled=False))


def test_point_cloud_moved_by_the_published_tf_lies_on_the_floor_and_walls(
        tmp_path: Path) -> None:
    """A camera 1.5 m up at (10, 0), pitched down 20 deg and yawed 40 deg, sees only the floor
    (z = 0), the east wall (x = 15) and the north wall (y = 10). Every point of every cloud,
    moved into the world with the /tf transform of the same stamp, lies on one of them; and
    world → cam → cam_world composes to the camera's world-axes pose."""
    cam = CameraSpec(name="cam", spawn=Pose(position=(10.0, 0.0, 1.5), rpy_deg=(0.0, 20.0, 40.0)),
                     resolution=(64, 48), fps=30.0,
                     outputs=("rgb", "depth", "pointcloud", "camera_info"))
    sc = Scenario(format_version=1, name="hall_cloud", world=HALL, cameras=(cam,), duration=0.05)
    res = api.run_scenario(sc, out=tmp_path / "run")
    assert res.verdict == "UNSCORED" and res.exit_code == 1
    tfs, clouds = transforms(res.run_dir)
    assert len(clouds) == 2  # ticks 0 and 2 of 3
    for cloud in clouds:
        t, r = pose(at_stamp(tfs[("world", "cam")], cloud.header.stamp))
        pts = r.apply(cloud_points(cloud)) + t
        floor = np.abs(pts[:, 2]) < 0.02
        east = np.abs(pts[:, 0] - 15.0) < 0.02
        north = np.abs(pts[:, 1] - 10.0) < 0.02
        assert (floor | east | north).all()
        assert min(floor.sum(), east.sum(), north.sum()) > 50
    _, static_r = pose(tfs[("cam", "cam_world")][0])
    world_axes = Rotation.from_euler("xyz", [0, 20, 40], degrees=True)
    assert ((r * static_r).inv() * world_axes).magnitude() < 1e-9
    np.testing.assert_allclose(static_r.as_quat(), [0.5, -0.5, 0.5, 0.5])


# ----------------------------------------------------------------------------- seed 001 port

def seed_simulation() -> Simulation:
    """The seed's scene without srr's own clock and camera TF graphs (the seed makes both)."""
    sc = api.load(SCENARIOS / "camera_publishing.yaml", overrides=["clock.enabled=false"])
    sim = Simulation(sc)
    sim.stage.delete_graph(camera_tf.GRAPH_PATH)
    seed001.extra_prims[:] = [sim.world.has_prim]  # the camera prim is a world prim here
    return sim


def tf_by_frames(sim: Simulation, ticks: int) -> dict[tuple[str, str], list[Any]]:
    out: dict[tuple[str, str], list[Any]] = {}

    def tap(env: Any) -> None:
        if env.topic == "/tf":
            for t in env.msg.transforms:
                out.setdefault((t.header.frame_id, t.child_frame_id), []).append(t)

    sim.add_tap(tap)
    sim.run(ticks)
    return out


def test_seed_publish_camera_tf_verbatim_reports_its_typo_and_still_publishes_the_camera(
        capsys: pytest.CaptureFixture[str]) -> None:
    sim = seed_simulation()
    try:
        with sim.stage:
            publish_camera_tf(Camera("/World/floating_camera"))
        printed = capsys.readouterr().out
        assert "PublishRawTF_floating_cameraworld" in printed
        assert "did you mean 'PublishRawTFfloating_cameraworld'" in printed
        tfs = tf_by_frames(sim, 2)
        (first, _) = tfs[("world", "floating_camera")]
        _, r = pose(first)
        assert (r.inv() * Rotation.from_euler("xyz", [-90, 0, -90], degrees=True)) \
            .magnitude() < 1e-9
    finally:
        sim.close()


def test_seed_publish_camera_tf_with_its_typo_fixed_gives_the_seed_frames() -> None:
    sim = seed_simulation()
    try:
        source = Path(seed001.__file__).read_text()
        fixed = source[source.index("def publish_camera_tf("):]
        assert '"PublishRawTF_"+' in fixed
        fixed = fixed.replace('"PublishRawTF_"+', '"PublishRawTF"+')
        namespace: dict[str, Any] = dict(vars(seed001))
        exec(compile(fixed, "<seed 001 fixed>", "exec"), namespace)
        with sim.stage:
            namespace["publish_camera_tf"](Camera("/World/floating_camera"))
        tfs = tf_by_frames(sim, 2)
        assert set(tfs) == {("world", "floating_camera"),
                            ("floating_camera", "floating_cameraworld")}
        (_, raw) = tfs[("floating_camera", "floating_cameraworld")]
        (_, cam) = tfs[("world", "floating_camera")]
        assert raw.header.stamp.nanosec == 1_000_000_000 // 60  # timeStamp connected
        _, cam_r = pose(cam)
        _, raw_r = pose(raw)
        assert (cam_r * raw_r).magnitude() < 1e-9  # world axes of a camera with zero rotation
    finally:
        sim.close()
