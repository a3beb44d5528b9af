"""Open-loop replay: a recorded bag played back, tick by tick, into systems under test.

:class:`Playback` reads a run's MCAP in file order — the order the recorder wrote, which is the
order the messages were published — and groups the messages by log time, which is always a
tick's simulation time. :class:`Replay` owns the loop the way :class:`~harness.engine.Simulation`
does, without a world or graphs: per tick ``k`` (time ``k * 1e9 // tick_hz``)

1. every recorded message of that time is published again, with its recorded bytes, except
   the topics the systems under test publish (those are produced again, live);
2. the bus delivers; each system under test steps; the bus delivers again.

That is the closed loop's order (graphs publish, deliver, step, deliver), so unchanged systems
under test see the same messages in the same order and publish the same bytes. What the
systems under test publish does not feed back into the scene: the replay is open loop.

A camera that recorded its images only compressed (its ``record`` block) still feeds systems
under test that read the raw topic: each compressed message is decoded (h264 in stream
order, JPEG, PNG; depth PNG back to 32FC1 metres) and published as a ``sensor_msgs/Image`` on
the raw topic right after it. Decoded h264 and JPEG frames are close to the rendered ones,
not equal to them, and depth comes back on the millimetre grid: a system under test reading
them may publish other bytes than in the recorded run.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness import yamlio
from harness.bus import Bus, Qos
from harness.camera_topics import CompressedStream, compressed_streams, recorded_cameras
from harness.engine import Joined, join
from harness.errors import reason
from harness.graph.nodes.camera import depth_image_message, rgb_image_message
from harness.output import ROS2_OUTPUT, OutputKind
from harness.recording.bagread import (
    DECODE_ERRORS,
    deserialize,
    open_recording,
    reading,
    ros1_recording,
    rosbag2_metadata,
)
from harness.recording.errors import BagError
from harness.scenario import Scenario
from harness.serde.ros1 import ros1_type
from harness.sut.base import SutContext, load_suts, setup_suts, step_suts
from harness.sut.participant import Participant
from harness.video.codec import H264Decoder, decode_depth_png, decode_rgb
from harness.video.errors import VideoError

__all__ = ["Playback", "RecordedTopic", "Replay"]

IMAGE = "sensor_msgs/msg/Image"


@dataclass(frozen=True)
class RecordedTopic:
    topic: str
    msgtype: str
    qos: Qos


def _key(node: Any, key: str) -> Any:
    """``node[key]`` of a parsed ``metadata.yaml``; ``ValueError`` naming the key when
    ``node`` is not a mapping that has it."""
    if not isinstance(node, dict) or key not in node:
        raise ValueError(repr(key))
    return node[key]


def _items(node: Any, key: str) -> list[Any]:
    """The list ``node[key]`` of a parsed ``metadata.yaml`` (``ValueError`` if it is not
    one)."""
    value = _key(node, key)
    if not isinstance(value, list):
        raise ValueError(f"{key}: not a list")
    return value


def _qos(profiles: Any) -> Qos:
    """The first offered QoS profile of a rosbag2 ``topic_metadata`` (a list of mappings in
    metadata version 9, a YAML string in older ones); ``ValueError`` (or a YAML error) for
    one that is neither."""
    if isinstance(profiles, str):
        profiles = yamlio.load(profiles)
    if not profiles:
        return Qos()
    if not isinstance(profiles, list):
        raise ValueError("offered_qos_profiles: not a list")
    p = profiles[0]
    depth = p.get("depth", 10) if isinstance(p, dict) else None
    if not isinstance(depth, int | float | str):
        raise ValueError(f"offered_qos_profiles: depth {depth!r} is not a number")
    return Qos(durability="transient_local" if str(_key(p, "durability")).lower() in (
                   "transient_local", "1") else "volatile",
               reliability="best_effort" if str(_key(p, "reliability")).lower() in (
                   "best_effort", "2") else "reliable",
               depth=max(int(depth), 1))


#: A latched ROS 1 topic is played back transient-local, keeping as many messages as srr's
#: own static TF publishers do (a ROS 1 bag does not say how many).
_LATCHED = Qos(durability="transient_local", depth=100)


class Playback:
    """The messages of a rosbag2 directory with one MCAP file, in publication order — or of a
    ROS 1 run's ``bag/`` (``.bag``, or MCAP with the ``ros1`` profile), whose messages are
    played back as they were recorded and decoded into ROS 2 messages for the systems under
    test. A ``.bag`` gives the messages of one tick by topic, not in publication order (its
    reader orders them by time only); a topic's own order is kept either way."""

    def __init__(self, bag_dir: Path) -> None:
        self.bag_dir = Path(bag_dir)
        self.output: OutputKind = ROS2_OUTPUT
        ros1 = ros1_recording(self.bag_dir)
        if ros1 is not None:
            self._open_ros1(ros1)
            return
        if not (self.bag_dir / "metadata.yaml").is_file():
            raise BagError(f"{self.bag_dir}: metadata.yaml: missing (not a rosbag2 directory)")
        meta_file = self.bag_dir / "metadata.yaml"
        info = rosbag2_metadata(self.bag_dir)  # each field's type checked, as every reader does
        with reading(meta_file, "not a rosbag2 metadata file"):
            self.topics = {}
            for entry in _items(info, "topics_with_message_count"):
                t = _key(entry, "topic_metadata")
                name, msgtype = str(_key(t, "name")), str(_key(t, "type"))
                self.topics[name] = RecordedTopic(name, msgtype,
                                                  _qos(t.get("offered_qos_profiles")))
            files = [self.bag_dir / str(p) for p in _items(info, "relative_file_paths")]
        if len(files) != 1 or files[0].suffix != ".mcap":
            raise BagError(f"{self.bag_dir}: expected one .mcap file, found "
                           f"{', '.join(p.name for p in files) or 'none'}")
        self.file = files[0]

    def _open_ros1(self, file: Path) -> None:
        self.file = file
        with open_recording(file, what="cannot read recording") as rec:
            self.topics = {c.topic: RecordedTopic(c.topic, c.msgtype,
                                                  _LATCHED if c.latched else Qos())
                           for c in rec.connections}
        self.output = OutputKind(1, "bag" if file.suffix == ".bag" else "mcap",
                                 f"the recording {file.name} is ROS 1")

    def _messages(self) -> Iterator[tuple[str, int, bytes]]:
        """(topic, log time, payload) in file order (a .bag: in time order)."""
        with open_recording(self.file, what="cannot read recording") as rec:
            for conn, t, raw in rec.messages():
                yield conn.topic, t, raw

    def by_time(self) -> Iterator[tuple[int, list[tuple[str, str, bytes]]]]:
        """(log time, [(topic, type, raw bytes), ...]) in file order, one group per log
        time; the type is the bus's (ROS 2) name."""
        where = "metadata.yaml" if self.output.ros == 2 else "the recording's index"
        stamp: int | None = None
        group: list[tuple[str, str, bytes]] = []
        for topic, log_time, data in self._messages():
            if stamp is not None and log_time != stamp:
                if log_time < stamp:
                    raise BagError(f"{self.file}: log time goes back from {stamp} to "
                                   f"{log_time} ns (not an srr recording)")
                yield stamp, group
                group = []
            stamp = log_time
            rec = self.topics.get(topic)
            if rec is None:
                raise BagError(f"{self.file}: topic {topic} is not in {where}")
            group.append((topic, rec.msgtype, data))
        if stamp is not None:
            yield stamp, group


class _RawFromCompressed:
    """Decodes one compressed camera topic back to ``sensor_msgs/Image`` messages."""

    def __init__(self, stream: CompressedStream) -> None:
        self.stream = stream
        self._h264 = H264Decoder() if stream.format == "h264" else None

    def images(self, msg: Any) -> list[Any]:
        s = self.stream
        if self._h264 is not None:
            stamp = msg.timestamp
            frames = self._h264.decode(bytes(msg.data))
        else:
            stamp = msg.header.stamp
            data = bytes(msg.data)
            if s.stream == "depth":
                frames = [decode_depth_png(data)]
            else:
                frames = [decode_rgb(data, "mjpeg" if s.format == "jpeg" else "png")]
        ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
        frame_id = str(msg.frame_id if self._h264 is not None else msg.header.frame_id)
        if s.stream == "depth":
            return [depth_image_message(ns, frame_id, f) for f in frames]
        return [rgb_image_message(ns, frame_id, f) for f in frames]


def _decoder(file: Path, now_ns: Callable[[], int], ros1: bool = False
             ) -> Callable[[bytes, str], Any]:
    """``deserialize_cdr`` (``ros1``: ROS 1 deserialization and conversion to the ROS 2
    message) that reports a message the recording holds but cannot decode as one BagError
    line naming the file, the type and the time."""
    def decode(raw: bytes, msgtype: str) -> Any:
        try:
            if ros1:
                return deserialize(raw, ros1_type(msgtype), "ros1")
            return deserialize(raw, msgtype, "cdr")
        except DECODE_ERRORS as err:
            raise BagError(f"{file}: a {msgtype} message at {now_ns() / 1e9:.3f} s does not "
                           f"decode: {reason(err)}") from err
    return decode


class Replay:
    """The recorded run of ``playback`` played into ``scenario``'s systems under test.

    ``withheld``: recorded topics not played back (what systems under test publish).
    ``joined`` step after the scenario's systems under test, as in a simulation (the ROS 2
    bridge, which stands for external nodes: the played-back messages of a tick go out on
    the ROS 2 graph as they are published, and the tick waits for the nodes' outputs)."""

    def __init__(self, scenario: Scenario, playback: Playback, withheld: set[str],
                 source: str = "<scenario>", joined: Sequence[Joined] = ()) -> None:
        self.scenario = scenario
        self.playback = playback
        self.withheld = withheld
        self.tick_index = 0
        self.time_ns = 0
        self.bus = Bus(lambda: self.time_ns)
        self.suts: list[tuple[str, Participant, SutContext]] = load_suts(
            scenario, self.bus, source)
        self.suts += join(joined, scenario, self.bus)
        self._groups: Iterator[tuple[int, list[tuple[str, str, bytes]]]] = iter(())
        self._decode = _decoder(playback.file, lambda: self.time_ns,
                                ros1=playback.output.ros == 1)
        self._pending: tuple[int, list[tuple[str, str, bytes]]] | None = None
        self._started = False
        # compressed topic → its decoder, for raw camera topics read but not recorded
        self._decoders: dict[str, _RawFromCompressed] = {}

    @property
    def decoded(self) -> set[str]:
        """Raw camera topics the replay decodes from compressed ones (after :meth:`start`)."""
        return {d.stream.raw_topic for d in self._decoders.values()}

    def start(self) -> None:
        setup_suts(self.suts)
        wanted = self.bus.subscribed()
        for cam in recorded_cameras(self.scenario):
            for cs in compressed_streams(cam):
                if (cs.raw_topic in wanted and cs.raw_topic not in self.playback.topics
                        and cs.topic in self.playback.topics
                        and cs.raw_topic not in self.decoded):
                    self._decoders[cs.topic] = _RawFromCompressed(cs)
        self._groups = self.playback.by_time()
        self._pending = next(self._groups, None)
        self._started = True

    def step_tick(self) -> None:
        """One tick: the recorded messages of its time, delivery, the systems under test."""
        if not self._started:
            self.start()
        hz = self.scenario.physics.tick_hz
        k = self.tick_index
        self.time_ns = k * 1_000_000_000 // hz
        pending = self._pending
        if pending is not None and pending[0] < self.time_ns:
            raise BagError(f"{self.playback.file}: messages at {pending[0]} ns fall between "
                           f"ticks of {hz} Hz (recorded with another tick rate?)")
        if pending is not None and pending[0] == self.time_ns:
            for topic, msgtype, raw in pending[1]:
                if topic not in self.withheld:
                    self.bus.publish_raw(topic, msgtype, raw, self._decode,
                                         self.playback.topics[topic].qos,
                                         "ros1" if self.playback.output.ros == 1 else "cdr")
                dec = self._decoders.get(topic)
                if dec is not None:
                    try:
                        images = dec.images(self._decode(raw, msgtype))
                    except VideoError as err:
                        raise BagError(f"{self.playback.file}: {topic} at "
                                       f"{self.time_ns / 1e9:.3f} s: {err}") from err
                    for image in images:
                        self.bus.publish(dec.stream.raw_topic, IMAGE, image)
            self._pending = next(self._groups, None)
        self.bus.spin()
        step_suts(self.suts, self.time_ns)
        self.bus.spin()
        self.tick_index = k + 1

    def close(self) -> None:
        for _, sut, _ in self.suts:
            sut.shutdown()
