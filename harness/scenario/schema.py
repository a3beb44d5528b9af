"""Typed, frozen model of a scenario file.

The loader (:mod:`harness.scenario.loader`) reads raw YAML into these dataclasses through
:mod:`harness.validation`, by their type hints and the ``meta`` of each field (range checks,
choices). Blocks follow the
shape of the forklift seed's ``robots.yaml`` / ``cameras.yaml``: every block has an ``enabled``
flag and the per-robot graphs read their settings from ``control``, ``odometry`` and
``safety_indicator``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

from harness.scenario.origins import origin_of

__all__ = [
    "BUILTIN_JOINTS",
    "FORMAT_VERSION",
    "ROBOT_MODELS",
    "CameraRecordSpec",
    "CameraSpec",
    "ClockSpec",
    "ControlScoring",
    "DiffDriveControl",
    "DockSpec",
    "DriveSpec",
    "ForkliftControl",
    "GraphSpec",
    "H264Spec",
    "HealthScoring",
    "ImuSpec",
    "LidarSpec",
    "ModelFile",
    "OdometrySpec",
    "OutputSpec",
    "PerceptionScoring",
    "PhysicsSpec",
    "Pose",
    "RecordingSpec",
    "RenderSpec",
    "ReverseLogic",
    "RobotCameraSpec",
    "RobotSpec",
    "RouteSpec",
    "RtspSpec",
    "SafetyIndicatorSpec",
    "SafetyScoring",
    "Scenario",
    "ScoringSpec",
    "SensorsSpec",
    "ShelfSpec",
    "StlSpec",
    "SutSpec",
    "TfTreeSpec",
    "ToleranceSpec",
    "TripwireSpec",
    "WorkerSpec",
    "WorldModel",
    "WorldSpec",
    "ZonesSpec",
    "gate_step",
    "gated_rate",
]

FORMAT_VERSION = 1
ROBOT_MODELS = ("forklift", "turtlebot3_waffle_pi")
#: The joints a built-in model always has, whatever its ``control:`` names (the forklift's
#: swivel and drive joints are named by its ``control:`` block; the TurtleBot3 has only these).
BUILTIN_JOINTS: dict[str, tuple[str, ...]] = {
    "forklift": ("front_left_wheel_joint", "front_right_wheel_joint"),
    "turtlebot3_waffle_pi": ("wheel_left_joint", "wheel_right_joint"),
}

Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]


def _range(lo: float | None = None, hi: float | None = None, *, lo_open: bool = False) -> Any:
    """Field metadata read by :mod:`harness.validation`: an inclusive (or open at ``lo``)
    numeric range."""
    return {"range": (lo, hi, lo_open)}


def num(default: float | None, lo: float | None = None, hi: float | None = None,
        *, lo_open: bool = False) -> Any:
    return field(default=default, metadata=_range(lo, hi, lo_open=lo_open))


def polygon() -> Any:
    """A polygon field (world XY points in order around it), empty for none: three points or
    more (the JSON Schema says so; :mod:`harness.scenario.checks` also refuses one that has
    no area or crosses itself)."""
    return field(default=(), metadata={"polygon": True})


def gate_step(tick_hz: int, fps: float) -> int:
    """A sensor publishes every ``gate_step``-th tick (its SimulationGate's ``step``):
    ``round(tick_hz / fps)``, >= 1 (seed 001's ``step_size = int(60 / freq)``, rounded
    instead of truncated)."""
    return max(1, round(tick_hz / fps))


def gated_rate(tick_hz: int, fps: float) -> float:
    """The rate (Hz) a sensor asked for ``fps`` really publishes at on a ``tick_hz`` tick."""
    return tick_hz / gate_step(tick_hz, fps)


@dataclass(frozen=True)
class Pose:
    """A pose in the world frame (or, as a sensor's ``offset``, in its link's or site's
    frame): position in metres, roll/pitch/yaw in degrees (extrinsic XYZ)."""

    position: Vec3 = (0.0, 0.0, 0.0)
    rpy_deg: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class PhysicsSpec:
    """Playback tick and physics step: ``dt = 1 / (tick_hz * substeps)``."""

    tick_hz: int = num(60, 1, 1000)
    substeps: int = num(4, 1, 100)
    integrator: Literal["implicitfast", "euler", "rk4", "implicit"] = "implicitfast"
    solver_iterations: int = num(50, 1, 1000)


@dataclass(frozen=True)
class RecordingSpec:
    """``recording:`` block: how the bag is written and the disk-space guard.

    A chunk of the MCAP file is closed (written and flushed) when it holds ``chunk_mb`` MB or
    spans ``chunk_s`` seconds of simulated time, whichever comes first: that bounds what a
    crash can lose. ``fsync`` also forces each closed chunk to the disk (only power loss needs
    it). A run refuses to start when the free space is below its estimated bag size plus
    ``min_free_mb``, and stops at a tick boundary (INVALID, exit 3) when free space falls below
    ``min_free_mb`` while it runs. MB are 10^6 bytes. ``compression`` compresses each chunk
    (MCAP chunk compression, as rosbag2's MCAP storage presets do; readers undo it and the
    messages, their digests and the bag's metadata.yaml are the same).
    """

    chunk_mb: float = num(8.0, 0.0, 4096.0, lo_open=True)
    chunk_s: float = num(1.0, 0.0, 3600.0, lo_open=True)
    fsync: bool = False
    min_free_mb: float = num(256.0, 0.0, 1e9)
    compression: Literal["none", "zstd", "lz4"] = "none"


@dataclass(frozen=True)
class OutputSpec:
    """``output:`` block: which ROS the recording speaks, decided once per run.

    ``ros``: 2 records a rosbag2 directory (MCAP, CDR, ROS 2 Jazzy messages); 1 records ROS 1
    (Noetic message definitions and serialization), as a ``.bag`` (``format: bag``) or as
    MCAP with the ``ros1`` profile (``format: mcap``, the default). Left out (null), it
    follows the bridge nodes the ``graphs:`` builders create: ``omni.isaac.ros_bridge.ROS1*``
    node types mean ROS 1, anything else ROS 2; ``format: bag`` alone means ROS 1."""

    ros: Literal[1, 2] | None = None
    format: Literal["mcap", "bag"] | None = None


@dataclass(frozen=True)
class RenderSpec:
    """``render:`` block: how every camera draws the scene (what its images cost and look like).

    ``shadows`` switches on the shadow pass of the scene's shadow-casting light (the warehouse's
    sun), drawn from a ``shadow_size`` x ``shadow_size`` shadow map; ``reflections`` the mirror
    pass of reflective materials (the warehouse floor); ``lights`` is ``all`` (the sun, the
    ceiling spots and the trailer light) or ``sun`` (directional lights only); the headlight
    always shines. These change colour images only: depth images are the same to within
    rasterization (the mirror pass can move a pixel's depth by ~1e-5 m). The defaults are the
    cheapest (on a CPU renderer the shadow and mirror passes cost about 4x the image itself).

    ``overlap: true`` renders on a background thread and builds, serializes, writes and
    digests the images there and on a few helper threads, so that the tick loop waits only for
    the renderer; a consumer inside the run (a system under test subscribing to an image) still
    gets it in the same tick. ``false`` renders on the loop's thread. ``auto`` (the default):
    overlapped with a GPU, not with a software renderer (Mesa's llvmpipe already renders on
    every core; overlapping it with the loop was 8 % slower on 2 cores). It changes no byte.
    """

    shadows: bool = False
    shadow_size: int = num(1024, 64, 16384)
    reflections: bool = False
    lights: Literal["all", "sun"] = "sun"
    overlap: Literal["auto", True, False] = "auto"


@dataclass(frozen=True)
class ShelfSpec:
    """A rack of shelving: centre on the floor, footprint ``size`` (length, depth, height)."""

    position: Vec2 = (0.0, 0.0)
    size: Vec3 = field(default=(6.0, 1.0, 2.5), metadata=_range(0.0, 1000.0, lo_open=True))
    yaw_deg: float = 0.0


@dataclass(frozen=True)
class DockSpec:
    """A trailer backed up to a dock door. ``position`` is the trailer's open end."""

    enabled: bool = True
    position: Vec2 = (12.0, 0.0)
    yaw_deg: float = 0.0
    length: float = num(12.0, 2.0, 20.0)
    width: float = num(2.6, 1.5, 4.0)
    height: float = num(2.8, 1.5, 5.0)


@dataclass(frozen=True)
class WorldModel:
    """A world described by a file: ``world.model: {mjcf: PATH}`` or ``{urdf: PATH}``.

    ``mode: replace`` (default): the file is the whole world and the procedural warehouse's
    fields (``size``, ``wall_height``, ``shelves``, ``dock``) are not used; srr adds a ground
    plane when the file has none and a sun when it has no light. ``mode: extend``: the
    procedural warehouse plus everything in the file but its ground planes. ``pose`` places
    the file's world frame in the scene and ``prim`` is where its bodies' prims go. Paths
    resolve like a robot model file's (:class:`ModelFile`). See :mod:`harness.sim.world_file`.
    """

    mjcf: str | None = None
    urdf: str | None = None
    mode: Literal["replace", "extend"] = "replace"
    package_paths: tuple[str, ...] = ()
    pose: Pose = Pose()
    prim: str = "/World/Environment"  # the file's bodies are prims <prim>/<body name>

    @property
    def kind(self) -> Literal["urdf", "mjcf"]:
        """Which format the file is in (the loader makes sure exactly one is set)."""
        return "urdf" if self.urdf is not None else "mjcf"

    @property
    def path(self) -> str:
        """The file as written in the scenario."""
        return self.urdf if self.urdf is not None else self.mjcf or ""


@dataclass(frozen=True)
class WorldSpec:
    """The warehouse: floor of ``size`` metres centred on the origin, walls, shelving, dock;
    or (``model``) a world from a file, instead of it or in it."""

    size: Vec2 = field(default=(30.0, 20.0), metadata=_range(0.0, 10000.0, lo_open=True))
    wall_height: float = num(4.0, 0.5, 20.0)
    shelves: tuple[ShelfSpec, ...] = (
        ShelfSpec(position=(-6.0, 6.0)),
        ShelfSpec(position=(2.0, 6.0)),
        ShelfSpec(position=(-6.0, -6.0)),
        ShelfSpec(position=(2.0, -6.0)),
    )
    dock: DockSpec = DockSpec()
    model: WorldModel | None = None

    @property
    def procedural(self) -> bool:
        """True when the procedural warehouse is built (no world file, or ``mode: extend``)."""
        return self.model is None or self.model.mode == "extend"


@dataclass(frozen=True)
class ClockSpec:
    """The top-level ``clock:`` block of the forklift scene's robots.yaml."""

    enabled: bool = True
    clock_topic: str = "clock"


@dataclass(frozen=True)
class ReverseLogic:
    """Vehicle-frame vs ROS-frame sign flips applied by the swivel-drive IK."""

    flip_linear_x: bool = True
    flip_angular_z: bool = True


@dataclass(frozen=True)
class ForkliftControl:
    """Forklift ``control:`` block: cmd_vel → swivel-drive IK → articulation (seed defaults)."""

    enabled: bool = True
    cmd_vel_topic: str = "cmd_vel"
    wheelbase: float = num(1.49, 0.0, 10.0, lo_open=True)
    wheel_radius: float = num(0.15, 0.0, 2.0, lo_open=True)
    max_steer_deg: float = num(45.0, 0.0, 89.0, lo_open=True)
    drive_joint: str = "back_wheel_drive"
    swivel_joint: str = "back_wheel_swivel"
    reverse_logic: ReverseLogic = ReverseLogic()


@dataclass(frozen=True)
class DiffDriveControl:
    """Differential-drive ``control:`` block (TurtleBot3 Waffle Pi defaults)."""

    enabled: bool = True
    cmd_vel_topic: str = "cmd_vel"
    joint_names: tuple[str, ...] = ("wheel_left_joint", "wheel_right_joint")
    wheel_distance: float = num(0.287, 0.0, 5.0, lo_open=True)
    wheel_radius: float = num(0.033, 0.0, 1.0, lo_open=True)
    max_linear_speed: float = num(0.26, 0.0, 10.0, lo_open=True)
    max_angular_speed: float = num(1.82, 0.0, 20.0, lo_open=True)


@dataclass(frozen=True)
class OdometrySpec:
    """``odometry:`` block: nav_msgs/Odometry plus the odom → base TF."""

    enabled: bool = True
    odom_topic: str = "odom"
    tf_topic: str = "tf"
    # The chassis axis that points forward; it needs a part along the floor (odometry turns
    # it onto +x as a yaw). None: the model's own.
    robot_front: Vec3 | None = None
    odom_frame: str = "odom"
    # The child frame of odom → base: the root link of the robot's link tree, so that the
    # tree hangs from odom (another frame is warned of). None: the model's base frame.
    base_frame: str | None = None


@dataclass(frozen=True)
class TfTreeSpec:
    """``tf_tree:`` block: world → odom (static) and the robot's link tree."""

    enabled: bool = True
    world_frame: str = "world"
    static_topic: str = "tf_static"
    dynamic_topic: str = "tf"


@dataclass(frozen=True)
class SafetyIndicatorSpec:
    """``safety_indicator:`` block: ``/safety/is_muted`` recolours a disk on the robot."""

    enabled: bool = False
    muted_topic: str = "/safety/is_muted"
    indicator_prim: str | None = None


@dataclass(frozen=True)
class H264Spec:
    """h264 encoder settings (:class:`harness.video.codec.H264Settings`).

    ``encoder``: ``x264`` (CPU; with a fixed ``threads`` the bytes are the same on every
    run) or ``nvenc`` (an NVIDIA GPU's video engine). ``keyframe_interval`` in frames.
    ``crf``: constant quality, 0-51, lower is better (NVENC: ``cq``), unless
    ``bitrate_kbps`` asks for a constant bit rate. ``preset``: the encoder's speed preset
    (x264 ``ultrafast`` … ``veryslow``, NVENC ``p1`` … ``p7``; None: ``veryfast`` / ``p4``)."""

    encoder: Literal["x264", "nvenc"] = "x264"
    keyframe_interval: int = num(30, 1, 100000)
    crf: int = num(23, 0, 51)
    bitrate_kbps: int | None = num(None, 1, 1000000)
    threads: int = num(1, 1, 64)
    preset: str | None = None


@dataclass(frozen=True)
class CameraRecordSpec:
    """``record:`` of a camera: what the bag holds of its images.

    ``rgb``: any of ``raw`` (the rgb topic, sensor_msgs/Image), ``h264`` (``<rgb
    topic>/h264``, foxglove_msgs/CompressedVideo) and one of ``jpeg`` or ``png`` (``<rgb
    topic>/compressed``, sensor_msgs/CompressedImage). ``depth``: ``raw`` (the depth topic,
    32FC1) and/or ``png`` (``<depth topic>/compressed``, 16-bit millimetres). The topics are
    a fixed camera's ``<cam>_rgb`` and ``<cam>_depth``, a robot camera's ``topic`` and
    ``depth_topic`` (in the robot's namespace). A raw stream left out is still published to
    the systems under test in the run, just not recorded. ``jpeg_qscale``: JPEG quality as
    FFmpeg's ``-q:v`` (2 best … 31)."""

    rgb: tuple[Literal["raw", "h264", "jpeg", "png"], ...] = ("raw",)
    depth: tuple[Literal["raw", "png"], ...] = ("raw",)
    h264: H264Spec = H264Spec()
    jpeg_qscale: int = num(3, 2, 31)


@dataclass(frozen=True)
class RobotCameraSpec:
    """A camera mounted on a robot link. ``graph: false`` mounts it (its prim exists, with
    this ``fovy_deg``) but builds no graph: a ``graphs:`` builder publishes it. ``record``
    says how the bag holds its images, as a fixed camera's does."""

    enabled: bool = True
    graph: bool = True
    link: str = "camera_link"
    site: str | None = None
    offset: Pose = Pose()
    topic: str = "camera/color"
    info_topic: str = "camera/camera_info"
    depth_topic: str | None = None
    frame_id: str = "camera"
    resolution: tuple[int, int] = field(default=(320, 240), metadata=_range(1, 8192))
    fovy_deg: float = num(60.0, 1.0, 170.0)
    fps: float = num(30.0, 0.0, 60.0, lo_open=True)
    record: CameraRecordSpec = CameraRecordSpec()


@dataclass(frozen=True)
class LidarSpec:
    """A planar lidar published as ``sensor_msgs/LaserScan``. ``graph: false`` mounts it
    (beams, ranges and noise still apply) but builds no graph: a ``graphs:`` builder
    publishes it."""

    enabled: bool = True
    graph: bool = True
    link: str = "base_scan"
    site: str | None = None
    offset: Pose = Pose()
    topic: str = "scan"
    frame_id: str = "base_scan"
    type: Literal["laser_scan", "point_cloud"] = "laser_scan"
    beams: int = num(360, 1, 4096)
    range_min: float = num(0.12, 0.0)
    range_max: float = num(3.5, 0.0, 1000.0, lo_open=True)
    fps: float = num(5.0, 0.0, 60.0, lo_open=True)
    noise_std: float = num(0.0, 0.0, 1.0)


@dataclass(frozen=True)
class ImuSpec:
    """An IMU published as ``sensor_msgs/Imu``. ``graph: false`` mounts it but builds no
    graph: a ``graphs:`` builder publishes it."""

    enabled: bool = True
    graph: bool = True
    link: str = "imu_link"
    site: str | None = None
    offset: Pose = Pose()
    topic: str = "imu"
    frame_id: str = "imu_link"
    fps: float = num(60.0, 0.0, 1000.0, lo_open=True)


@dataclass(frozen=True)
class SensorsSpec:
    """A robot's mounted sensors. Each sits on ``link`` (a link of the robot) or, for a
    model file, on ``site`` (a site the file names; its link is the site's body), moved by
    ``offset`` (in the link's or the site's frame). A sensor whose ``frame_id`` is not its
    link's frame gets a static TF ``<link> → <frame_id>`` with its pose in the link; a sensor
    off its link's origin must have such a frame of its own."""

    camera: RobotCameraSpec | None = None
    lidar: LidarSpec | None = None
    imu: ImuSpec | None = None


@dataclass(frozen=True)
class DriveSpec:
    """How srr drives one joint of a model file that has no actuator on it (``model.drives``).

    For a joint the ``control:`` block drives, the controller decides the kind: wheels and a
    swivel-drive's drive joint get a velocity servo (``kv``), a swivel joint a position servo
    (``kp``, with ``kv`` as its damping). Any other hinge or slide joint listed here gets the
    servo ``mode`` says (default: velocity for a joint that turns freely, position
    otherwise), for a graph's ``ArticulationController`` to command by joint name.
    Unset values are scaled from the model's mass (see :mod:`harness.sim.robots.imported`).
    ``max_force`` limits the torque (N·m; N for a slide joint), ``armature`` adds rotor
    inertia to the joint (kg·m²)."""

    mode: Literal["position", "velocity"] | None = None
    kp: float | None = num(None, 0.0, 1e9, lo_open=True)
    kv: float | None = num(None, 0.0, 1e9, lo_open=True)
    max_force: float | None = num(None, 0.0, 1e9, lo_open=True)
    armature: float | None = num(None, 0.0, 1e6)


@dataclass(frozen=True)
class ModelFile:
    """A robot described by a file: ``model: {urdf: PATH}``, ``model: {mjcf: PATH}`` or
    ``model: {xacro: PATH, args: {NAME: VALUE}}`` (a ``.xacro`` file the ``xacro`` package
    expands to URDF, given ``args`` for its ``$(arg NAME)``; its ``$(find PKG)`` is the
    package's directory on the package path below).

    Paths are relative to the scenario file the robot entry is written in, or ``package://``
    URIs looked up in ``package_paths`` (relative to the same file), then ``SRR_PACKAGE_PATH``
    and ``ROS_PACKAGE_PATH``. ``drive`` says which controller the ``control:`` block belongs
    to: ``diff_drive`` (a :class:`DiffDriveControl`: wheel joint names, radius, distance) or
    ``swivel_drive`` (a :class:`ForkliftControl`: drive and swivel joints, wheelbase).
    ``drives``: per joint, how srr drives a controlled joint the file has no actuator on.
    ``frictionless_links``: links whose collision shapes slide on the floor without friction
    (ball casters, which URDF cannot describe). ``footprint_radius``: the circle the scoring
    uses for clearance and collisions (metres)."""

    urdf: str | None = None
    mjcf: str | None = None
    xacro: str | None = None
    args: dict[str, str | int | float | bool] = field(default_factory=dict)
    drive: Literal["diff_drive", "swivel_drive"] = "diff_drive"
    package_paths: tuple[str, ...] = ()
    drives: dict[str, DriveSpec] = field(default_factory=dict)
    frictionless_links: tuple[str, ...] = ()
    footprint_radius: float = num(0.5, 0.0, 50.0, lo_open=True)

    @property
    def kind(self) -> Literal["urdf", "mjcf", "xacro"]:
        """Which format the file is in (the loader makes sure exactly one is set)."""
        if self.xacro is not None:
            return "xacro"
        return "urdf" if self.urdf is not None else "mjcf"

    @property
    def path(self) -> str:
        """The file as written in the scenario."""
        if self.xacro is not None:
            return self.xacro
        return self.urdf if self.urdf is not None else self.mjcf or ""

    @property
    def xacro_args(self) -> dict[str, str]:
        """``args`` as the text xacro substitutes (``true``/``false`` for booleans)."""
        return {k: (str(v).lower() if isinstance(v, bool) else str(v))
                for k, v in self.args.items()}


@dataclass(frozen=True)
class RobotSpec:
    """One block of the ``robots:`` list (the forklift scene's robots.yaml shape)."""

    name: str
    model: Literal["forklift", "turtlebot3_waffle_pi"] | ModelFile
    enabled: bool = True
    articulation_prim: str | None = None  # default /World/<name>
    # ROS namespace of the robot's relative topics, and the prefix of its frame ids (as
    # robot_state_publisher's frame_prefix). None: the loader fills them in — the robot's name
    # when the scene has more than one enabled robot, nothing when it has one.
    namespace: str | None = None
    frame_prefix: str | None = None
    spawn: Pose = Pose()
    control: ForkliftControl | DiffDriveControl | None = None  # None: the model's default
    odometry: OdometrySpec = OdometrySpec()
    tf_tree: TfTreeSpec = TfTreeSpec()
    safety_indicator: SafetyIndicatorSpec = SafetyIndicatorSpec()
    sensors: SensorsSpec = SensorsSpec()

    @property
    def prim(self) -> str:
        return self.articulation_prim or f"/World/{self.name}"

    @property
    def ns(self) -> str:
        """The namespace the robot's relative topics resolve in ("" is the root)."""
        return self.namespace or ""

    def frame(self, name: str) -> str:
        """The robot's frame id for ``name``: its ``frame_prefix`` + ``name``."""
        return f"{self.frame_prefix or ''}{name}"

    @property
    def model_file(self) -> ModelFile | None:
        """The model file block, or None for a built-in model."""
        return self.model if isinstance(self.model, ModelFile) else None

    @property
    def model_name(self) -> str:
        """The built-in model's name, or ``urdf:PATH`` / ``mjcf:PATH`` for a model file."""
        if isinstance(self.model, ModelFile):
            return f"{self.model.kind}:{self.model.path}"
        return self.model

    @property
    def swivel_drive(self) -> bool:
        """True when the robot is driven by the forklift's swivel-drive controller."""
        if isinstance(self.model, ModelFile):
            return self.model.drive == "swivel_drive"
        return self.model == "forklift"

    @property
    def control_spec(self) -> ForkliftControl | DiffDriveControl:
        """The ``control:`` block, or the model's default when the scenario leaves it out."""
        if self.control is not None:
            return self.control
        return ForkliftControl() if self.swivel_drive else DiffDriveControl()


@dataclass(frozen=True)
class CameraSpec:
    """One entry of ``cameras:`` (the forklift scene's cameras.yaml shape) for a fixed camera.

    ``port`` and ``mount_path`` (default ``/<name>``) serve the camera over RTSP when the
    ``rtsp:`` block is enabled; ``record`` says how the bag holds its images. ``outputs``
    left out publishes rgb, depth and camera_info: a point cloud (16 bytes a pixel, four
    times the depth image it is computed from) only when asked for."""

    name: str
    enabled: bool = True
    camera_prim: str | None = None  # default /World/<name>
    spawn: Pose = Pose(position=(0.0, 0.0, 3.0))
    resolution: tuple[int, int] = field(default=(256, 256), metadata=_range(1, 8192))
    fovy_deg: float = num(60.0, 1.0, 170.0)
    fps: float = num(30.0, 0.0, 60.0, lo_open=True)
    outputs: tuple[Literal["rgb", "depth", "pointcloud", "camera_info"], ...] = (
        "rgb", "depth", "camera_info")
    port: int | None = num(None, 1, 65535)
    mount_path: str | None = None
    record: CameraRecordSpec = CameraRecordSpec()

    @property
    def prim(self) -> str:
        return self.camera_prim or f"/World/{self.name}"

    @property
    def mount(self) -> str:
        """The RTSP mount path: ``mount_path`` or ``/<name>``."""
        return self.mount_path or f"/{self.name}"


@dataclass(frozen=True)
class RouteSpec:
    """A polyline in the world frame (metres)."""

    waypoints: tuple[Vec2, ...]


@dataclass(frozen=True)
class SutSpec:
    """A system under test, loaded from a ``"module:Class"`` string.

    ``robot`` binds it to a robot: its relative topics resolve in that robot's namespace and
    it gets the robot's frame prefix. ``namespace`` (None: the robot's, else the root) sets the
    namespace directly; ``remap`` renames topics after resolution, as ROS 2 remapping rules do
    (``{cmd_vel: /fleet/a/cmd_vel}``: keys and values resolve in the namespace).
    """

    name: str
    plugin: str
    enabled: bool = True
    robot: str = ""
    namespace: str | None = None
    remap: dict[str, str] = field(default_factory=dict)
    params: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class GraphSpec:
    """One entry of ``graphs:``: a builder function (``"module:function"``) run on the stage
    at build time, after the built-in graphs (see :mod:`harness.builders.custom`).

    ``name`` (default: the function's name, or the module's last component for ``build``)
    gives the builder its predictable path ``/World/<name>Graph``; ``robot`` (default: the
    only enabled robot) is the robot the builder's context puts first; ``params`` are
    handed to it as they are.
    """

    builder: str
    name: str | None = None
    enabled: bool = True
    robot: str = ""
    params: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class WorkerSpec:
    """A person on foot walking a polyline ``route`` (world XY, metres) at ``speed``.

    ``loop``: ``once`` stops at the last waypoint, ``back_and_forth`` walks the route back to
    its start and again, ``cycle`` walks back from the last waypoint straight to the first;
    ``pause_s`` is spent standing at each turn. ``variation`` scales the speed by a factor drawn
    once per worker from U(1 - variation, 1 + variation), seeded by the scenario seed. The
    name (default ``character_<i>``) names the prim ``/World/Characters/<name>``; ground truth
    is always ``/gt/character_<i>/tf`` with ``i`` the index in ``workers``.
    """

    route: tuple[Vec2, ...]
    name: str = ""
    enabled: bool = True
    speed: float = num(1.2, 0.0, 5.0, lo_open=True)
    start_delay: float = num(0.0, 0.0, 3600.0)
    loop: Literal["once", "back_and_forth", "cycle"] = "back_and_forth"
    pause_s: float = num(0.0, 0.0, 3600.0)
    height: float = num(1.75, 0.5, 2.5)
    radius: float = num(0.25, 0.05, 0.8)
    variation: float = num(0.0, 0.0, 0.9)


@dataclass(frozen=True)
class TripwireSpec:
    """A directed line ``a → b``; the forklift is inside the trailer when its ground-truth
    position is on the ``inside`` side. Left is seen from above (+Z), walking from ``a`` to
    ``b``: the side ``b - a`` turned +90° (counter-clockwise) points to; for ``a → b`` along
    +x, left is +y."""

    a: Vec2
    b: Vec2
    inside: Literal["left", "right"] = "left"


@dataclass(frozen=True)
class ZonesSpec:
    """Zones the safety scoring uses: the loading ROI polygon (empty: none) and the trailer
    tripwire (None: none). Geometry (edges included or not) is :mod:`harness.sut.zones`."""

    loading_roi: tuple[Vec2, ...] = polygon()
    trailer_tripwire: TripwireSpec | None = None


@dataclass(frozen=True)
class ToleranceSpec:
    """How far a metric may move in its worse direction before it counts as regressed:
    ``max(abs, rel * |baseline|)``."""

    abs: float | None = num(None, 0.0)
    rel: float | None = num(None, 0.0)


@dataclass(frozen=True)
class ControlScoring:
    """Score a robot's drive against a route (needs ``/gt/<robot>/tf``, i.e. ``srr_gt``).

    ``scoring.control`` is one block (metrics ``control.<metric>``) or a list of blocks, one
    per robot (metrics ``control.<robot>.<metric>``). ``robot`` left out: the only enabled
    robot (a scene with several must name it)."""

    enabled: bool = True
    robot: str = ""
    route: str = ""
    goal_tolerance: float = num(0.5, 0.0, 100.0, lo_open=True)


@dataclass(frozen=True)
class PerceptionScoring:
    """Score tracked objects (MarkerArray) against ``/gt/character_<i>/tf``."""

    enabled: bool = True
    marker_topics: tuple[str, ...] = ()
    classes: tuple[str, ...] = ("person",)
    gate: float = num(1.0, 0.0, 100.0, lo_open=True)
    # Evaluation area (world XY polygon): ground truth and tracks outside it are not scored,
    # so objects the cameras cannot see do not count as misses. Empty: everywhere.
    area: tuple[tuple[float, float], ...] = polygon()


@dataclass(frozen=True)
class SafetyScoring:
    """The forklift SIL's mute scoring: expected muted state vs ``/safety/is_muted``.
    ``robot`` left out: the only enabled robot (a scene with several must name it)."""

    enabled: bool = True
    robot: str = ""
    muted_topic: str = "/safety/is_muted"
    min_window_s: float = num(0.5, 0.0, 60.0)


@dataclass(frozen=True)
class HealthScoring:
    """Health gates: topics at their rate, SUT outputs alive."""

    rate_fraction: float = num(0.9, 0.0, 1.0)
    expected_rates: dict[str, float] = field(default_factory=dict)
    sut_outputs: dict[str, float] = field(default_factory=dict)  # topic → max silence (s)


@dataclass(frozen=True)
class ScoringSpec:
    """What to score and how much each metric may move (keys: metric names or globs).
    ``record_only``: the scenario records on purpose and scores nothing (no control,
    perception or safety block): its verdict is RECORDED, exit 0, when every health gate
    holds (without it, a scenario that scores nothing is UNSCORED, exit 1)."""

    control: ControlScoring | tuple[ControlScoring, ...] | None = None
    perception: PerceptionScoring | None = None
    safety: SafetyScoring | None = None
    health: HealthScoring = HealthScoring()
    tolerances: dict[str, ToleranceSpec] = field(default_factory=dict)
    record_only: bool = False

    @property
    def control_blocks(self) -> tuple[ControlScoring, ...]:
        """The enabled control blocks, whichever form ``control`` was written in."""
        c = self.control
        blocks = () if c is None else (c,) if isinstance(c, ControlScoring) else c
        return tuple(b for b in blocks if b.enabled)

    def control_prefix(self, robot: str) -> str:
        """Metric-name prefix of a control block: ``control.`` for the single-block form,
        ``control.<robot>.`` for the list form."""
        return "control." if isinstance(self.control, ControlScoring) else f"control.{robot}."


@dataclass(frozen=True)
class StlSpec:
    """One entry of ``specs:``: a signal temporal logic ``formula`` over srr's signals
    (ground-truth clearance, speed and zones, the safety topics, tracking errors, recorded
    topic fields; :mod:`harness.scenario.specs`), evaluated on the tick grid of the recorded
    run. It gives the metric ``spec.<name>.robustness`` (negative: violated) with the
    windows where it is violated. ``required``: a violation (or a formula that cannot be
    evaluated) fails the run whatever the baseline says; false: the robustness is only
    scored and compared with the baseline."""

    name: str
    formula: str
    required: bool = True
    enabled: bool = True


@dataclass(frozen=True)
class Ros2QosSpec:
    """QoS of one topic on the live ROS 2 graph (``ros2.qos``), overriding the default."""

    reliability: Literal["reliable", "best_effort"] | None = None
    durability: Literal["volatile", "transient_local"] | None = None
    depth: int | None = num(None, 1, 10000)


@dataclass(frozen=True)
class Ros2OutputSpec:
    """A topic external ROS 2 nodes publish into the run (``ros2.outputs``).

    Lockstep: simulation time advances past a tick only when every output due at that tick
    has arrived. ``rate_hz`` set: one message is due per period of simulated time (at the
    first tick of each period). Otherwise the message type must have a ``header``, and a
    message stamped at or after the tick's time is due at every tick."""

    topic: str
    type: str
    rate_hz: float | None = num(None, 0.0, 10000.0, lo_open=True)


@dataclass(frozen=True)
class Ros2ProcessSpec:
    """An external process that runs the nodes under test (``ros2.external``): started in
    its own process group with the run's ROS_DOMAIN_ID before the first tick, waited for
    until each output (and ``ready_topic``, when set) has a publisher, stopped at the end
    (SIGINT, then SIGTERM, then SIGKILL). ``use_sim_time`` appends
    ``--ros-args -p use_sim_time:=true`` to ``cmd``."""

    cmd: tuple[str, ...]
    name: str = ""
    ready_topic: str | None = None
    ready_timeout: float = num(30.0, 0.0, 3600.0, lo_open=True)
    use_sim_time: bool = True
    env: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Ros2Spec:
    """``ros2:`` block: a live ROS 2 graph beside the run (``srr run --ros2``).

    Every recorded topic is also published there from its CDR bytes; ``outputs`` come back
    from external nodes in lockstep (``timeout``: wall-clock seconds one tick may wait before
    the run stops INVALID). ``domain_id`` None takes a free one per run; discovery stays on
    localhost unless ``localhost_only`` is false."""

    enabled: bool = False
    domain_id: int | None = num(None, 0, 232)
    localhost_only: bool = True
    timeout: float = num(10.0, 0.0, 3600.0, lo_open=True)
    outputs: tuple[Ros2OutputSpec, ...] = ()
    external: tuple[Ros2ProcessSpec, ...] = ()
    qos: dict[str, Ros2QosSpec] = field(default_factory=dict)


@dataclass(frozen=True)
class RtspSpec:
    """``rtsp:`` block: every enabled camera with a ``port`` streams h264 over RTSP at
    ``rtsp://<host>:<port><mount_path>`` (the forklift scene's ``/World/RTSPMultiGraph``).

    ``fps``: the rate of the graph's one simulation gate (``step = round(tick_hz / fps)``),
    hence of every stream. ``wait_s``: hold the first tick until every stream has a client,
    at most this long (None: do not wait). ``rate``: pace the run so that simulated time goes
    at most ``rate`` times as fast as the wall clock (None: as fast as it computes; the
    servers still send each stream at its own pace)."""

    enabled: bool = False
    host: str = "127.0.0.1"
    fps: float = num(30.0, 0.0, 1000.0, lo_open=True)
    wait_s: float | None = num(None, 0.0, 3600.0)
    rate: float | None = num(None, 0.0, 1000.0, lo_open=True)
    h264: H264Spec = H264Spec()


@dataclass(frozen=True)
class Scenario:
    """A whole scenario, resolved: includes expanded, defaults filled, overrides applied."""

    format_version: int
    name: str
    duration: float = num(30.0, 0.0, 3600.0, lo_open=True)
    description: str = ""
    seed: int = num(0, 0, 2**32 - 1)
    srr_gt: bool = False
    physics: PhysicsSpec = PhysicsSpec()
    world: WorldSpec = WorldSpec()
    clock: ClockSpec = ClockSpec()
    robots: tuple[RobotSpec, ...] = ()
    cameras: tuple[CameraSpec, ...] = ()
    routes: dict[str, RouteSpec] = field(default_factory=dict)
    workers: tuple[WorkerSpec, ...] = ()
    zones: ZonesSpec = ZonesSpec()
    systems_under_test: tuple[SutSpec, ...] = ()
    graphs: tuple[GraphSpec, ...] = ()
    scoring: ScoringSpec = ScoringSpec()
    specs: tuple[StlSpec, ...] = ()
    recording: RecordingSpec = RecordingSpec()
    output: OutputSpec = OutputSpec()
    render: RenderSpec = RenderSpec()
    ros2: Ros2Spec = Ros2Spec()
    rtsp: RtspSpec = RtspSpec()
    baseline: str | None = None  # which baselines/<name>.json to compare with (default: name)
    # The baselines folder, relative to the scenario file (default: found from the scenario
    # file's folder, harness.api.baselines_dir).
    baselines: str | None = None
    # Parameters ``srr suite`` sweeps: ``--set`` path → list of values or {from, to, step}
    # (checked by harness.suite.sweep; ``srr run`` runs the scenario as written).
    sweep: dict[str, Any] = field(default_factory=dict)
    # Which file each top-level key or list item ("robots", "robots[1]") came from, or which
    # flag each field a --set gave ("robots[0].spawn": "--set"), for error messages after
    # loading. Filled by the loader; not part of the scenario's content.
    origins: dict[str, str] = field(default_factory=dict, compare=False, repr=False,
                                    metadata={"internal": True})
    # The ``--set`` overrides the loader applied, (dotted path, value) in order: what a run's
    # command line needs to reproduce it. Filled by the loader; not part of the content.
    overrides: tuple[tuple[str, Any], ...] = field(default=(), compare=False, repr=False,
                                                  metadata={"internal": True})

    @property
    def tick_ns(self) -> int:
        return 1_000_000_000 // self.physics.tick_hz

    @property
    def n_ticks(self) -> int:
        return round(self.duration * self.physics.tick_hz)

    @property
    def camera_count(self) -> int:
        """Enabled cameras: fixed ones and those on enabled robots (a run renders if any)."""
        return sum(c.enabled for c in self.cameras) + sum(
            r.enabled and r.sensors.camera is not None and r.sensors.camera.enabled
            for r in self.robots)

    def worker_name(self, index: int) -> str:
        """Name of ``workers[index]``: its ``name`` or ``character_<index>``."""
        return self.workers[index].name or f"character_{index}"

    def robot(self, name: str) -> RobotSpec:
        for r in self.robots:
            if r.name == name:
                return r
        raise KeyError(name)

    def robot_index(self, name: str) -> int:
        """Index of robot ``name`` in ``robots`` (for field paths such as ``robots[1]``)."""
        for i, r in enumerate(self.robots):
            if r.name == name:
                return i
        raise KeyError(name)

    def file_for(self, path: str, default: str) -> str:
        """The file the value at field ``path`` (``robots[1].odometry``) came from, or
        ``--set`` where that flag gave it: the most specific entry of ``origins`` (a field a
        ``--set`` gave, a list item, then a top-level key), else ``default`` (also for a
        graph node's attribute path, ``/World/...``, which no origin names)."""
        return origin_of(self.origins, path) or default

    def source_file(self, path: str, default: str) -> str:
        """The file the value at field ``path`` was read from, what relative paths in it are
        relative to: :meth:`file_for`, but for a value a ``--set`` gave the file it was set
        on (never the flag)."""
        return origin_of(self.origins, path, files_only=True) or default
