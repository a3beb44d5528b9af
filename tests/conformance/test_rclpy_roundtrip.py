"""Recorded messages against the real ROS 2 Jazzy rclpy (the ``ros2`` extra).

For every bundled scenario (``scenarios/*.yaml``, run for at most 2 s) every recorded message
whose type rclpy has (common_interfaces and the core interface packages) goes through:

1. ``rclpy.serialization.deserialize_message(recorded bytes)``; its values must equal what
   rosbags decodes from the same bytes, field by field, floats bit for bit;
2. ``serialize_message`` of that: the same length as recorded, the same encapsulation, and
   the bytes decode with rosbags to values equal to the recorded ones. Padding is never
   compared: Fast CDR leaves it uninitialised. "Same length" is exact, with the one known
   difference spelt out: rclpy (rmw_fastrtps) reports its size *estimate*, which can add
   trailing uninitialised bytes (std_msgs/Bool: 8 bytes where CDR needs 5), so the recorded
   length must equal the exact CDR size and rclpy's the Fast CDR estimate, both computed from
   the values (``cdr_size.py``); for most types the two are the same number. The trailing
   bytes are cut off before rosbags decodes rclpy's output, and rosbags refuses a buffer whose
   content does not end there, so they cannot hide a value.

Types rclpy cannot load are listed, with the reason, in ``NOT_IN_RCLPY``; a recorded type that
is neither checkable nor listed fails, and so does a common_interfaces type that is not
checkable. Messages of a listed type still have their message-typed fields checked (a
``tf2_msgs/TFMessage``'s ``geometry_msgs/TransformStamped`` elements). ``tf2_msgs``, which
the wheels lack, is built for rclpy first (:mod:`harness.ros2.tf2_msgs`, needs a compiler; CI
has one), so ``TFMessage`` is checked whole; only without a compiler is it listed.

Without the extra the module is skipped; ``SRR_REQUIRE_ROS2=1`` (CI) turns that skip into an
error so the check cannot quietly vanish.
"""

from __future__ import annotations

import importlib
import json
import os
import struct
import sys
import time
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader

from harness import api
from harness.serde.messages import TYPESTORE
from tests.conformance.cdr_size import exact_size, fastrtps_size
from tests.conformance.synth import random_message
from tests.conformance.values import message_fields, value_diff
from tests.log_sections import add as log_line

if os.environ.get("SRR_REQUIRE_ROS2") == "1":
    import rclpy  # noqa: F401  (an ImportError here is a collection error, never a skip)
pytest.importorskip("rclpy", reason="needs the ros2 extra: pip install -e '.[dev,ros2]'")
# Imported for real (no importorskip): if rclpy is installed but its C extension cannot load
# (e.g. the ros_wheels_bootstrapper re-exec did not happen), that must be an error.
from rclpy.serialization import deserialize_message, serialize_message

from tests.conftest import ModuleTmp

pytestmark = [pytest.mark.ros2]

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
SCENARIO_FILES = sorted(SCENARIOS.glob("*.yaml"))
FORKLIFT = SCENARIOS / "forklift_warehouse.yaml"
MAX_DURATION_S = 2.0

# ROS 2 Jazzy common_interfaces (ros2/common_interfaces): a recorded type from one of these
# packages must be checked, never skipped.
COMMON_INTERFACES = frozenset({
    "actionlib_msgs", "diagnostic_msgs", "geometry_msgs", "nav_msgs", "sensor_msgs",
    "shape_msgs", "std_msgs", "std_srvs", "stereo_msgs", "trajectory_msgs",
    "visualization_msgs",
})

def _tf2_msgs_for_rclpy() -> bool:
    """Build (once, cached) and load tf2_msgs for rclpy; under SRR_REQUIRE_ROS2=1 a failure
    is an error, elsewhere (no compiler) TFMessage falls back to its elements."""
    from harness.ros2.errors import Ros2SetupError
    from harness.ros2.tf2_msgs import ensure_tf2_msgs

    if os.environ.get("SRR_REQUIRE_ROS2") == "1":
        return ensure_tf2_msgs(build=True)
    try:
        return ensure_tf2_msgs(build=True)
    except Ros2SetupError:
        return False


TF2_MSGS = _tf2_msgs_for_rclpy()

# The one place that lists recorded types rclpy cannot check, and why.
NOT_IN_RCLPY: dict[str, str] = {} if TF2_MSGS else {
    "tf2_msgs/msg/TFMessage": (
        "no tf2_msgs wheel among the ros-jazzy-* wheels on PyPI and it could not be built "
        "here; its geometry_msgs/TransformStamped elements are checked one by one instead"),
}


def rclpy_class(typename: str) -> type[Any] | None:
    """rclpy's class for ``pkg/msg/Name``, or None when rclpy has no package ``pkg``."""
    pkg, kind, name = typename.split("/")
    try:
        module = importlib.import_module(f"{pkg}.{kind}")
    except ModuleNotFoundError as err:
        if err.name in (pkg, f"{pkg}.{kind}"):
            return None
        raise
    cls: type[Any] = getattr(module, name)
    return cls


def real_type_hash(typename: str) -> str | None:
    """The RIHS01 hash the installed ROS 2 package generated for ``typename``."""
    pkg, kind, name = typename.split("/")
    path = Path(sys.prefix) / "share" / pkg / kind / f"{name}.json"
    if not path.is_file():  # a package built by srr (tf2_msgs): <prefix>/python/<pkg>/
        spec = importlib.util.find_spec(pkg)
        if spec is None or spec.origin is None:
            return None
        path = Path(spec.origin).parents[2] / "share" / pkg / kind / f"{name}.json"
    if not path.is_file():
        return None
    hashes = json.loads(path.read_text(encoding="utf-8"))["type_hashes"]
    return next((h["hash_string"] for h in hashes if h["type_name"] == typename), None)


def roundtrip_problems(typename: str, raw: bytes, cls: type[Any]) -> tuple[list[str], int]:
    """Everything that does not survive recorded bytes → rclpy → bytes → rosbags.

    Returns the problems and the trailing slack (re-serialized length minus recorded length)."""
    ours = TYPESTORE.deserialize_cdr(raw, typename)
    theirs = deserialize_message(raw, cls)
    problems = [f"rclpy decodes {d}" for d in value_diff(theirs, ours)]
    out = bytes(serialize_message(theirs))
    if out[:2] != raw[:2]:
        problems.append(f"encapsulation {out[:4].hex()} != recorded {raw[:4].hex()}")
    slack = len(out) - len(raw)
    exact, estimate = exact_size(typename, ours), fastrtps_size(typename, ours)
    if len(raw) != exact:
        problems.append(f"recorded length {len(raw)} != exact CDR size {exact}")
    if len(out) != estimate:
        problems.append(f"re-serialized length {len(out)} != recorded {len(raw)} "
                        f"(Fast CDR's estimate: {estimate})")
    try:  # the bytes past the exact size are the estimate's uninitialised slack
        back = TYPESTORE.deserialize_cdr(out[:exact], typename)
    except Exception as err:  # rosbags raises several kinds; any is a failed round trip
        problems.append(f"rosbags cannot decode rclpy's bytes: {err!r}")
    else:
        problems += [f"re-serialized {d}" for d in value_diff(back, ours)]
    return problems, slack


def nested_messages(msg: Any) -> Iterator[tuple[str, Any]]:
    """(type name, value) of a rosbags message's message-typed fields, lists flattened."""
    _consts, fields = TYPESTORE.fielddefs[msg.__msgtype__]
    for name, _ in fields:
        value = getattr(msg, name)
        for item in value if isinstance(value, list) else [value]:
            if message_fields(item) is not None:
                yield item.__msgtype__, item


@dataclass
class ScenarioCheck:
    name: str
    messages: int = 0
    checked: Counter[str] = field(default_factory=Counter)
    skipped: Counter[str] = field(default_factory=Counter)
    nested: Counter[str] = field(default_factory=Counter)
    slack: dict[str, set[int]] = field(default_factory=dict)
    unlisted: set[str] = field(default_factory=set)
    problems: list[str] = field(default_factory=list)
    type_hashes: dict[str, str] = field(default_factory=dict)  # from metadata.yaml
    run_s: float = 0.0
    check_s: float = 0.0

    def add_problems(self, where: str, problems: list[str]) -> None:
        if len(self.problems) < 50:
            self.problems += [f"{where}: {p}" for p in problems]

    def line(self) -> str:
        slack = {t: sorted(s) for t, s in self.slack.items() if s != {0}}
        return (f"{self.name}: {self.messages} messages; checked {sum(self.checked.values())} "
                f"of {len(self.checked)} types {dict(sorted(self.checked.items()))}; "
                f"skipped {dict(self.skipped)} "
                f"({'; '.join(NOT_IN_RCLPY.get(t, 'NOT LISTED') for t in self.skipped)}); "
                f"nested elements checked {dict(self.nested)}; "
                f"trailing slack {slack or 'none'}; run {self.run_s:.2f} s, "
                f"check {self.check_s:.2f} s")


def check_run(name: str, run_dir: Path) -> ScenarioCheck:
    result = ScenarioCheck(name)
    classes: dict[str, type[Any] | None] = {}

    def check(typename: str, raw: bytes, where: str, cls: type[Any]) -> None:
        problems, slack = roundtrip_problems(typename, raw, cls)
        result.slack.setdefault(typename, set()).add(slack)
        if problems:
            result.add_problems(where, problems)

    (bag,) = sorted((run_dir / "bag").glob("*.mcap"))
    start = time.perf_counter()
    with bag.open("rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            assert schema is not None and schema.encoding == "ros2msg"
            assert channel.message_encoding == "cdr"
            typename, raw = schema.name, bytes(message.data)
            result.messages += 1
            if typename not in classes:
                classes[typename] = rclpy_class(typename)
            cls = classes[typename]
            where = f"{channel.topic} #{message.sequence} ({typename})"
            if cls is not None:
                result.checked[typename] += 1
                check(typename, raw, where, cls)
                continue
            result.skipped[typename] += 1
            if typename not in NOT_IN_RCLPY:
                result.unlisted.add(typename)
            for i, (subtype, sub) in enumerate(nested_messages(
                    TYPESTORE.deserialize_cdr(raw, typename))):
                subcls = classes.setdefault(subtype, rclpy_class(subtype))
                if subcls is not None:
                    result.nested[subtype] += 1
                    check(subtype, bytes(TYPESTORE.serialize_cdr(sub, subtype)),
                          f"{where} element {i}", subcls)
    result.check_s = time.perf_counter() - start
    meta = yaml.safe_load((run_dir / "bag" / "metadata.yaml").read_text(encoding="utf-8"))
    for entry in meta["rosbag2_bagfile_information"]["topics_with_message_count"]:
        topic = entry["topic_metadata"]
        result.type_hashes[topic["type"]] = topic.get("type_description_hash", "")
    return result


@pytest.fixture(scope="module")
def scenario_check(module_tmp: ModuleTmp) -> Callable[[Path], ScenarioCheck]:
    """Runs a bundled scenario (≤ 2 s) once per module and checks its bag."""
    cache: dict[Path, ScenarioCheck] = {}

    def get(path: Path) -> ScenarioCheck:
        if path not in cache:
            duration = min(MAX_DURATION_S, api.load(path).duration)
            scenario = api.load(path, duration=duration)
            out = module_tmp(f"ros2_{path.stem}") / "run"
            start = time.perf_counter()
            run = api.run_scenario(scenario, source=str(path), out=out)
            run_s = time.perf_counter() - start
            # the verdict is not this test's business (short runs may trip rate gates); the
            # bag is, and an INVALID run still has a complete one
            cache[path] = check_run(f"{path.stem} ({run.verdict})", run.run_dir)
            cache[path].run_s = run_s
            log_line("ROS 2 conformance (real rclpy)", cache[path].line())
        return cache[path]

    return get


def test_scenarios_are_found() -> None:
    assert FORKLIFT in SCENARIO_FILES


@pytest.mark.parametrize("path", SCENARIO_FILES, ids=lambda p: p.stem)
@pytest.mark.slow
def test_recorded_messages_round_trip_through_rclpy(
        path: Path, scenario_check: Callable[[Path], ScenarioCheck]) -> None:
    result = scenario_check(path)
    assert not result.problems, "\n".join(result.problems)


@pytest.mark.parametrize("path", SCENARIO_FILES, ids=lambda p: p.stem)
@pytest.mark.slow
def test_every_recorded_type_is_checked_or_listed(
        path: Path, scenario_check: Callable[[Path], ScenarioCheck]) -> None:
    result = scenario_check(path)
    assert result.messages > 0
    assert result.checked, "no recorded message could be checked with rclpy"
    assert not result.unlisted, (
        f"types neither in rclpy nor in NOT_IN_RCLPY: {sorted(result.unlisted)}")
    skipped_common = {t for t in result.skipped if t.split("/")[0] in COMMON_INTERFACES}
    assert not skipped_common, f"common_interfaces types rclpy could not load: {skipped_common}"
    assert sum(result.checked.values()) + sum(result.skipped.values()) == result.messages


@pytest.mark.parametrize("path", SCENARIO_FILES, ids=lambda p: p.stem)
@pytest.mark.slow
def test_recorded_type_hashes_are_the_real_ones(
        path: Path, scenario_check: Callable[[Path], ScenarioCheck]) -> None:
    """The RIHS01 hash rosbags wrote into metadata.yaml is the one ROS 2 Jazzy generated."""
    result = scenario_check(path)
    wrong = {}
    for typename, recorded in result.type_hashes.items():
        real = real_type_hash(typename)
        if real is None:
            assert typename in NOT_IN_RCLPY, f"no type description installed for {typename}"
            continue
        if recorded != real or TYPESTORE.hash_rihs01(typename) != real:
            wrong[typename] = (recorded, real)
    assert not wrong, wrong


@pytest.mark.slow
def test_forklift_checks_odometry_twist_clock_and_tf_elements(
        scenario_check: Callable[[Path], ScenarioCheck]) -> None:
    result = scenario_check(FORKLIFT)
    assert {"nav_msgs/msg/Odometry", "geometry_msgs/msg/Twist",
            "rosgraph_msgs/msg/Clock"} <= set(result.checked)
    assert result.checked["nav_msgs/msg/Odometry"] >= 100  # 2 s at 60 Hz
    if TF2_MSGS:  # /tf and /tf_static checked whole with rclpy's tf2_msgs
        assert result.checked["tf2_msgs/msg/TFMessage"] >= 100
        assert not result.skipped
    else:
        assert result.nested["geometry_msgs/msg/TransformStamped"] >= 100
        assert set(result.skipped) == {"tf2_msgs/msg/TFMessage"}


def test_not_in_rclpy_lists_no_common_interfaces_type() -> None:
    for typename in NOT_IN_RCLPY:
        assert typename.split("/")[0] not in COMMON_INTERFACES
        assert rclpy_class(typename) is None, f"{typename} is in rclpy now: check it"


# Every message type of these packages that both rosbags and rclpy know, with seeded awkward
# values in every field: covers types before a scenario records them (Image, CameraInfo, ...).
SYNTH_TYPES = sorted(
    t for t in TYPESTORE.types
    if t.split("/")[1] == "msg"
    and t.split("/")[0] in COMMON_INTERFACES | {"builtin_interfaces", "rosgraph_msgs"})


@pytest.mark.parametrize("typename", SYNTH_TYPES)
def test_seeded_messages_of_every_common_interfaces_type_round_trip(typename: str) -> None:
    cls = rclpy_class(typename)
    assert cls is not None, f"rclpy has no {typename}"
    for seed in range(12):
        msg = random_message(typename, np.random.default_rng(seed))
        raw = bytes(TYPESTORE.serialize_cdr(msg, typename))
        assert value_diff(TYPESTORE.deserialize_cdr(raw, typename), msg) == []
        problems, _slack = roundtrip_problems(typename, raw, cls)
        assert not problems, f"seed {seed}: " + "\n".join(problems)


def test_seeded_types_include_the_sensor_messages() -> None:
    assert {"sensor_msgs/msg/Image", "sensor_msgs/msg/CameraInfo", "sensor_msgs/msg/PointCloud2",
            "sensor_msgs/msg/LaserScan", "sensor_msgs/msg/Imu", "std_msgs/msg/Bool",
            "visualization_msgs/msg/MarkerArray"} <= set(SYNTH_TYPES)


# -- the check can fail -------------------------------------------------------------------------

_MARK_X = 1234.5678


def _odometry_bytes() -> bytes:
    from harness.serde.messages import odometry

    msg = odometry(1_500_000_000, "odom", "base_link", [_MARK_X, -2.0, 0.0],
                   [0.0, 0.0, 0.38268343236, 0.92387953251], [1.5, 0.0, 0.0], [0.0, 0.0, 0.2])
    msg.pose.covariance[:] = np.arange(36) * 0.01
    return bytes(TYPESTORE.serialize_cdr(msg, "nav_msgs/msg/Odometry"))


def test_intact_odometry_round_trips() -> None:
    from nav_msgs.msg import Odometry

    problems, slack = roundtrip_problems("nav_msgs/msg/Odometry", _odometry_bytes(), Odometry)
    assert problems == [] and slack == 0


def test_a_corrupted_byte_in_odometry_is_caught() -> None:
    """Flip the middle byte of pose.pose.position.x in recorded bytes: rclpy decodes a
    different value and the rclpy-vs-rosbags comparison must name the field."""
    from nav_msgs.msg import Odometry

    raw = bytearray(_odometry_bytes())
    at = raw.find(struct.pack("<d", _MARK_X))
    assert at > 0 and raw.find(struct.pack("<d", _MARK_X), at + 1) == -1
    raw[at + 4] ^= 0x5A
    theirs = deserialize_message(bytes(raw), Odometry)
    ours = TYPESTORE.deserialize_cdr(_odometry_bytes(), "nav_msgs/msg/Odometry")
    diff = value_diff(theirs, ours)
    assert len(diff) == 1 and diff[0].startswith("pose.pose.position.x:"), diff


def test_a_corrupted_covariance_byte_is_caught() -> None:
    from nav_msgs.msg import Odometry

    raw = bytearray(_odometry_bytes())
    at = raw.find(struct.pack("<d", 35 * 0.01))  # pose.covariance[35], set in _odometry_bytes
    assert at > 0
    raw[at + 3] ^= 0x01
    theirs = deserialize_message(bytes(raw), Odometry)
    ours = TYPESTORE.deserialize_cdr(_odometry_bytes(), "nav_msgs/msg/Odometry")
    diff = value_diff(theirs, ours)
    assert len(diff) == 1 and diff[0].startswith("pose.covariance[35]:"), diff


def test_rclpy_reports_fast_cdr_estimate_not_the_exact_size() -> None:
    """Why "same length" is checked against two computed sizes (cdr_size.py)."""
    from std_msgs.msg import Bool, Float64MultiArray

    for cls, typename, exact, estimate in [(Bool, "std_msgs/msg/Bool", 5, 8),
                                           (Float64MultiArray, "std_msgs/msg/Float64MultiArray",
                                            16, 20)]:
        out = bytes(serialize_message(cls()))
        ours = TYPESTORE.deserialize_cdr(out[:exact], typename)
        assert len(out) == estimate == fastrtps_size(typename, ours)
        assert exact == exact_size(typename, ours)
        assert len(TYPESTORE.serialize_cdr(ours, typename)) == exact


def test_a_recording_with_trailing_bytes_is_caught() -> None:
    from nav_msgs.msg import Odometry

    raw = _odometry_bytes() + b"\0\0"  # rosbags still decodes it (< 4 trailing bytes)
    problems, slack = roundtrip_problems("nav_msgs/msg/Odometry", raw, Odometry)
    assert problems == ["recorded length 726 != exact CDR size 724"] and slack == -2


def test_a_corrupted_padding_byte_is_not_a_difference() -> None:
    """Padding carries no value (Fast CDR leaves it uninitialised): changing it is no diff."""
    from nav_msgs.msg import Odometry

    raw = bytearray(_odometry_bytes())
    at = raw.find(struct.pack("<d", _MARK_X))
    # the string "base_link\0" ends 6 bytes before position.x, which is 8-aligned
    assert raw[at - 16:at - 6] == b"base_link\0" and raw[at - 6:at] == bytes(6)
    raw[at - 3] = 0x55
    problems, slack = roundtrip_problems("nav_msgs/msg/Odometry", bytes(raw), Odometry)
    assert problems == [] and slack == 0
