"""Two decoded messages walked side by side: field paths, arrays, what is not numeric."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from harness.diff.fields import walk
from harness.serde.messages import (
    deserialize,
    header,
    make,
    serialize,
    tf_message,
    transform_stamped,
)


class Record:
    def __init__(self) -> None:
        self.scalars: list[tuple[str, float, float]] = []
        self.arrays: list[tuple[str, np.ndarray, np.ndarray]] = []
        self.mismatches: list[tuple[str, str]] = []
        self.order: list[str] = []

    def scalar(self, path: str, a: float, b: float) -> None:
        self.scalars.append((path, a, b))
        self.order.append(path)

    def array(self, path: str, a: np.ndarray, b: np.ndarray) -> None:
        self.arrays.append((path, a, b))
        self.order.append(path)

    def mismatch(self, path: str, detail: str) -> None:
        self.mismatches.append((path, detail))
        self.order.append(path)


def _roundtrip(msg: Any, typename: str) -> Any:
    """As the diff sees it: decoded from CDR."""
    return deserialize(serialize(msg, typename), typename)


def _tf(x: float, child: str = "base_link") -> Any:
    ts = transform_stamped(1_000, "odom", child, [x, 2.0, 0.0], [0.0, 0.0, 0.0, 1.0])
    return _roundtrip(tf_message([ts]), "tf2_msgs/msg/TFMessage")


def test_paths_follow_the_message_in_field_order() -> None:
    rec = Record()
    walk(_tf(1.0), _tf(1.5), rec)
    paths = [p for p, _, _ in rec.scalars]
    assert paths[:2] == ["transforms[0].header.stamp.sec", "transforms[0].header.stamp.nanosec"]
    assert paths[2:5] == [f"transforms[0].transform.translation.{k}" for k in "xyz"]
    assert paths[5:] == [f"transforms[0].transform.rotation.{k}" for k in "xyzw"]
    assert ("transforms[0].transform.translation.x", 1.0, 1.5) in rec.scalars
    assert rec.mismatches == [] and rec.arrays == []


def test_strings_and_lengths_are_mismatches() -> None:
    rec = Record()
    walk(_tf(1.0, "base_link"), _tf(1.0, "base_footprint"), rec)
    assert rec.mismatches == [("transforms[0].child_frame_id",
                               "'base_link' vs 'base_footprint'")]
    rec = Record()
    two = tf_message([transform_stamped(0, "a", "b", [0, 0, 0], [0, 0, 0, 1])] * 2)
    one = tf_message([transform_stamped(0, "a", "b", [0, 0, 0], [0, 0, 0, 1])])
    walk(_roundtrip(one, "tf2_msgs/msg/TFMessage"), _roundtrip(two, "tf2_msgs/msg/TFMessage"),
         rec)
    assert rec.mismatches[0] == ("transforms", "length 1 vs 2")
    # the common prefix is still compared
    assert any(p.startswith("transforms[0].") for p, _, _ in rec.scalars)


def _image(values: np.ndarray, encoding: str) -> Any:
    raw = np.ascontiguousarray(values).view(np.uint8).reshape(-1)
    msg = make("sensor_msgs/msg/Image", header=header(0, "cam"), height=values.shape[0],
               width=values.shape[1], encoding=encoding, is_bigendian=0,
               step=raw.size // values.shape[0], data=raw)
    return _roundtrip(msg, "sensor_msgs/msg/Image")


def test_depth_images_compare_in_metres_not_bytes() -> None:
    a = np.full((2, 3), 2.0, dtype="<f4")
    b = a.copy()
    b[1, 2] = 2.5
    rec = Record()
    walk(_image(a, "32FC1"), _image(b, "32FC1"), rec)
    ((path, va, vb),) = rec.arrays
    assert path == "data" and va.size == 6 and va.dtype == np.float32
    assert float(vb[5] - va[5]) == 0.5
    rgb = np.zeros((2, 3, 3), dtype=np.uint8)
    rec = Record()
    walk(_image(rgb, "rgb8"), _image(rgb, "rgb8"), rec)
    ((path, va, _),) = rec.arrays
    assert path == "data" and va.dtype == np.uint8 and va.size == 18


def test_a_boolean_field_that_differs_shows_as_false_vs_true(tmp_path: Path) -> None:
    """``srr diff`` of a std_msgs/Bool (or any bool field): ``false vs true``, not ``0 vs 1``."""
    from harness.bus import Bus
    from harness.diff.topics import diff_bags
    from harness.recording import Recorder

    for name, values in (("a", [False, False]), ("b", [False, True])):
        now = [0]
        bus = Bus(lambda now=now: now[0])
        rec = Recorder(tmp_path / name)
        rec.open(bus.qos)
        bus.add_tap(rec)
        for i, value in enumerate(values):
            now[0] = i * 1000
            bus.publish("/safety/alarm", "std_msgs/msg/Bool", make("std_msgs/msg/Bool",
                                                                    data=value))
        rec.close()
    (alarm,) = diff_bags(tmp_path / "a", tmp_path / "b")
    assert alarm.first is not None
    assert (alarm.first.index, alarm.first.path, alarm.first.detail) == (1, "data",
                                                                         "false vs true")
