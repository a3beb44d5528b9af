"""The single-pass renderer: linear depth against known geometry, intrinsics, sky, purity."""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.errors import SimulationError
from harness.geometry import quat_wxyz_conj, quat_wxyz_rotate
from harness.scenario.schema import (
    CameraSpec,
    DockSpec,
    Pose,
    RobotSpec,
    SafetyIndicatorSpec,
    Scenario,
    WorldSpec,
)
from harness.sim import World
from harness.sim.cameras import optical_quat
from harness.sim.render import Intrinsics, Renderer, depth_from_buffer, points_from_depth

# An empty 30 x 20 m hall: walls' inner faces at x = ±15, y = ±10; floor at z = 0.
HALL = WorldSpec(size=(30.0, 20.0), wall_height=4.0, shelves=(), dock=DockSpec(enabled=False))
W, H = 64, 48


def cam(name: str, position: tuple[float, float, float], rpy: tuple[float, float, float],
        **kw: object) -> CameraSpec:
    return CameraSpec(name=name, spawn=Pose(position=position, rpy_deg=rpy),
                      resolution=(W, H), **kw)  # type: ignore[arg-type]


@pytest.fixture(scope="module")
def hall() -> World:
    cameras = (
        cam("east", (10.0, 0.0, 1.0), (0.0, 0.0, 0.0)),       # faces the east wall, 5 m away
        cam("down", (0.0, 0.0, 1.5), (0.0, 90.0, 0.0)),       # looks straight down, 1.5 m up
        cam("up", (0.0, 0.0, 1.0), (0.0, -90.0, 0.0)),        # looks at the sky (no roof)
        cam("tilted", (10.0, 0.0, 1.5), (0.0, 20.0, 0.0)),    # floor and east wall
        CameraSpec(name="odd", spawn=Pose(position=(10.0, 0.0, 1.0)), resolution=(65, 49)),
    )
    return World.build(Scenario(format_version=1, name="hall", world=HALL, cameras=cameras))


@pytest.fixture(scope="module")
def renderer(hall: World) -> Renderer:
    r = Renderer(hall.model, hall.data)
    yield r  # type: ignore[misc]
    r.close()


def cam_id(world: World, name: str) -> int:
    return world.prim_ref(f"/World/{name}").id


def test_depth_is_linear_metres_to_a_wall_and_the_floor(hall: World, renderer: Renderer) -> None:
    east = renderer.render(cam_id(hall, "east"), W, H)
    assert east.depth.dtype == np.float32 and east.depth.shape == (H, W)
    # 1 m up, 5 m from the wall: rays above the axis hit the wall below its 4 m top, and the
    # wall is a plane perpendicular to the axis, so its depth is 5 m in every such pixel.
    centre = east.depth[H // 2 - 1:H // 2 + 1, W // 2 - 1:W // 2 + 1]
    np.testing.assert_allclose(centre, 5.0, atol=0.01)
    wall_rows = east.depth[: H // 2]
    np.testing.assert_allclose(wall_rows, 5.0, atol=0.01)
    down = renderer.render(cam_id(hall, "down"), W, H)
    np.testing.assert_allclose(down.depth, 1.5, atol=0.01)


def test_centre_pixel_of_an_odd_image_is_on_the_optical_axis(hall: World,
                                                             renderer: Renderer) -> None:
    frame = renderer.render(cam_id(hall, "odd"), 65, 49)
    assert frame.intrinsics.cx == 32.0 and frame.intrinsics.cy == 24.0
    assert frame.depth[24, 32] == pytest.approx(5.0, abs=0.01)


def test_images_are_top_row_first(hall: World, renderer: Renderer) -> None:
    """Pitched down towards the wall: the top row sees the far wall, the bottom row the floor
    close below the camera."""
    frame = renderer.render(cam_id(hall, "tilted"), W, H)
    assert frame.depth[-1].mean() < frame.depth[0].mean()  # bottom row: floor, near


def test_sky_is_infinite_depth(hall: World, renderer: Renderer) -> None:
    frame = renderer.render(cam_id(hall, "up"), W, H)
    assert np.isinf(frame.depth).all() and (frame.depth > 0).all()
    assert frame.rgb.reshape(-1, 3).std(axis=0).max() < 40  # a smooth gradient, drawn
    assert points_from_depth(frame.depth, frame.intrinsics).shape == (0, 3)


def test_floor_and_wall_pixels_back_project_onto_the_geometry(hall: World,
                                                              renderer: Renderer) -> None:
    """Intrinsics (fy, cy and square pixels) checked per pixel: every point from the tilted
    camera's depth, moved into the world with the camera pose, lies on z = 0 or x = 15."""
    frame = renderer.render(cam_id(hall, "tilted"), W, H)
    pts = points_from_depth(frame.depth, frame.intrinsics).astype(np.float64)
    assert len(pts) == W * H
    pos, q_world_conv = hall.prim_pose("/World/tilted")
    q_opt = optical_quat(q_world_conv)
    world_pts = np.array([quat_wxyz_rotate(q_opt, p) for p in pts]) + pos
    on_floor = np.abs(world_pts[:, 2]) < 0.02
    on_wall = np.abs(world_pts[:, 0] - 15.0) < 0.02
    assert (on_floor | on_wall).all()
    assert on_floor.sum() > 200 and on_wall.sum() > 200


def test_intrinsics_from_fovy() -> None:
    intr = Intrinsics.from_fovy(64, 48, 60.0)
    f = 24.0 / math.tan(math.radians(30.0))
    assert (intr.fx, intr.fy, intr.cx, intr.cy) == pytest.approx((f, f, 31.5, 23.5))
    assert intr.k == pytest.approx((f, 0, 31.5, 0, f, 23.5, 0, 0, 1))
    assert intr.p == pytest.approx((f, 0, 31.5, 0, 0, f, 23.5, 0, 0, 0, 1, 0))
    np.testing.assert_allclose(intr.project([[0.0, 0.0, 3.0], [1.0, -0.5, 2.0]]),
                               [[31.5, 23.5], [31.5 + f / 2, 23.5 - f / 4]])
    with pytest.raises(SimulationError):
        Intrinsics.from_fovy(0, 48, 60.0)


def test_depth_buffer_conversion() -> None:
    near, far = 0.1, 100.0
    z = np.array([near, 1.0, 10.0, 99.0])
    d = near * (far - z) / (z * (far - near))  # reversed-Z window depth
    np.testing.assert_allclose(depth_from_buffer(d, near, far), z, rtol=1e-6)
    assert np.isinf(depth_from_buffer(np.array([0.0]), near, far)).all()
    assert np.isinf(depth_from_buffer(d, near, far, z_limit=9.0)[2:]).all()


def test_render_is_a_pure_function_of_the_state(hall: World, renderer: Renderer) -> None:
    cid = cam_id(hall, "tilted")
    a = renderer.render(cid, W, H)
    renderer.render(cam_id(hall, "up"), W, H)
    renderer.render(cid, 32, 24)  # another resolution (another context) in between
    b = renderer.render(cid, W, H)
    assert a.rgb.tobytes() == b.rgb.tobytes() and a.depth.tobytes() == b.depth.tobytes()
    assert not a.rgb.flags.writeable and not a.depth.flags.writeable
    with Renderer(hall.model, hall.data) as fresh:
        c = fresh.render(cid, W, H)
        assert fresh.renders == 1
    assert c.rgb.tobytes() == a.rgb.tobytes() and c.depth.tobytes() == a.depth.tobytes()
    with pytest.raises(SimulationError, match="closed"):
        fresh.render(cid, W, H)
    with pytest.raises(SimulationError, match="no camera"):
        renderer.render(99, W, H)


def test_safety_indicator_is_orange_where_the_intrinsics_project_it() -> None:
    """An overhead camera off to one side of a parked forklift: the indicator disk's centre,
    projected with K and the camera pose, lands on orange pixels; the floor beside it not."""
    forklift = RobotSpec(name="forklift", model="forklift",
                         spawn=Pose(position=(0.0, 0.0, 0.0), rpy_deg=(0.0, 0.0, 0.0)),
                         safety_indicator=SafetyIndicatorSpec(enabled=True))
    overhead = CameraSpec(name="overhead", spawn=Pose(position=(1.0, 0.8, 6.0),
                                                      rpy_deg=(0.0, 90.0, 0.0)),
                          resolution=(96, 72), fovy_deg=50.0)
    world = World.build(Scenario(format_version=1, name="ind", world=HALL,
                                 robots=(forklift,), cameras=(overhead,)))
    with Renderer(world.model, world.data) as r:
        frame = r.render(world.prim_ref("/World/overhead").id, 96, 72)
    indicator = "/World/forklift/body/body/safety_indicator"
    disk, _ = world.prim_pose(indicator)
    pos, q = world.prim_pose("/World/overhead")
    p_opt = quat_wxyz_rotate(quat_wxyz_conj(optical_quat(q)), disk - pos)
    (u, v), = frame.intrinsics.project(p_opt)
    assert 5 < u < 90 and 5 < v < 66 and abs(u - 47.5) > 5  # off-centre, inside the image
    r_, g, b = (int(c) for c in frame.rgb[round(v), round(u)])
    assert r_ > 150 and b < 60 and r_ > 1.8 * g, (r_, g, b)
    assert frame.depth[round(v), round(u)] == pytest.approx(p_opt[2], abs=0.03)
    assert not (frame.rgb[2, 2, 0] > 150 and frame.rgb[2, 2, 2] < 60)  # a corner: floor
