"""The recorder: order-preserving background writes, and write failures as one clear error."""

from __future__ import annotations

import hashlib
from functools import partial
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from harness.bus import Bus, Deferred
from harness.bus.bus import TRANSIENT_LOCAL, Qos
from harness.cli import main
from harness.errors import SimulationError
from harness.recording import Recorder
from harness.recording.errors import BagError
from harness.recording.recorder import digest_update, topic_meta
from harness.serde.messages import clock, serialize, tf_message_of

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "forklift_warehouse.yaml"


def test_counts_and_digests_follow_publication_order(tmp_path: Path) -> None:
    now = [0]
    bus = Bus(lambda: now[0])
    rec = Recorder(tmp_path / "bag", queue_size=2)  # a tiny queue: the producer must block
    rec.open(bus.qos)
    bus.add_tap(rec)
    for i in range(50):
        now[0] = i * 1000
        bus.publish("/clock", "rosgraph_msgs/msg/Clock", clock(now[0]))
    stats = rec.close()
    assert stats["/clock"].count == 50 and stats["/clock"].first_ns == 0
    assert stats["/clock"].last_ns == 49_000

    again = Recorder(tmp_path / "bag2")
    bus2 = Bus(lambda: now[0])
    again.open(bus2.qos)
    bus2.add_tap(again)
    for i in range(50):
        now[0] = i * 1000
        bus2.publish("/clock", "rosgraph_msgs/msg/Clock", clock(now[0]))
    assert again.close()["/clock"].sha256 == stats["/clock"].sha256


def test_each_channel_is_described_as_topic_meta_describes_its_topic(tmp_path: Path) -> None:
    # Topics sharing a type and a QoS, and one sharing the type with another QoS: the
    # recorder makes each part of a description once, the channels must not show it.
    bus = Bus(lambda: 0)
    topics = {"/a": Qos(), "/b": Qos(), "/c": TRANSIENT_LOCAL, "/clock": Qos()}
    rec = Recorder(tmp_path / "bag")
    rec.open(topics.__getitem__)
    bus.add_tap(rec)
    for topic, qos in topics.items():
        msgtype = "rosgraph_msgs/msg/Clock" if topic == "/clock" else "tf2_msgs/msg/TFMessage"
        bus.advertise(topic, msgtype, qos).publish(
            clock(0) if topic == "/clock" else tf_message_of(0, []))
    rec.close()
    with (tmp_path / "bag" / "bag.mcap").open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    described = {}
    for channel in summary.channels.values():
        schema = summary.schemas[channel.schema_id]
        described[channel.topic] = (schema.name, schema.data.decode(), channel.metadata)
    for topic, qos in topics.items():
        name, definition, metadata = described[topic]
        meta = topic_meta(topic, name, qos)
        assert definition == meta.schema.decode()
        assert metadata == {"offered_qos_profiles": meta.qos, "topic_type_hash": meta.type_hash}
    assert "transient_local" in described["/c"][2]["offered_qos_profiles"]
    assert described["/a"][2] == described["/b"][2] != described["/clock"][2]


@pytest.mark.slow
def test_a_failing_disk_is_one_line_and_leaves_no_run(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str],
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    from harness.recording.mcap_writer import McapWriter

    calls = {"n": 0}
    real = McapWriter.flush  # where a closed chunk goes to the file

    def failing(self: McapWriter) -> None:
        calls["n"] += 1
        if calls["n"] > 1:
            raise OSError(28, "No space left on device")
        real(self)

    monkeypatch.setattr(McapWriter, "flush", failing)
    out = tmp_path / "r"
    code = main(["run", str(SCENARIO), "--duration", "3", "--out", str(out), "-q"])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert "No space left on device" in err and "cannot record" in err
    assert not out.exists()  # nothing half-written is left looking valid



def _image(ns: int, n: int) -> object:
    from harness.graph.nodes.camera import rgb_image_message

    rng = np.random.default_rng(n)
    return rgb_image_message(ns, "cam", rng.integers(0, 255, (120, 200, 3), dtype=np.uint8))


def test_deferred_and_large_messages_give_the_bytes_of_the_plain_path(tmp_path: Path) -> None:
    """Images built on the pool and digested on hash threads, interleaved with small messages
    on the caller's thread: the same per-topic digests and the same file order as publishing
    every message built (independent reader: the mcap library)."""
    from mcap.reader import make_reader

    def record(name: str, deferred: bool) -> tuple[dict[str, str], list[tuple[str, int]]]:
        now = [0]
        bus = Bus(lambda: now[0])
        rec = Recorder(tmp_path / name, queue_size=4)
        rec.open(bus.qos)
        bus.add_tap(rec)
        for i in range(40):
            now[0] = i * 1000
            bus.publish("/clock", "rosgraph_msgs/msg/Clock", clock(now[0]))
            for cam in ("/a", "/b", "/c"):
                msg = partial(_image, now[0], i * 7 + len(cam) + ord(cam[1]))
                bus.publish(cam, "sensor_msgs/msg/Image", Deferred(msg) if deferred else msg())
        stats = rec.close()
        assert rec.bytes_serialized == sum(s.bytes for s in stats.values())
        with (tmp_path / name / f"{name}.mcap").open("rb") as f:
            order = [(c.topic, m.log_time) for _, c, m in make_reader(f).iter_messages(
                log_time_order=False)]
        return {t: s.sha256 for t, s in stats.items()}, order

    digests, order = record("plain", deferred=False)
    assert record("deferred", deferred=True) == (digests, order)
    h = hashlib.sha256()
    for i in range(40):
        digest_update(h, i * 1000, serialize(_image(i * 1000, i * 7 + 2 + ord("b")),
                                             "sensor_msgs/msg/Image"))
    assert digests["/b"] == h.hexdigest()  # the hash thread's digest is the documented one


def test_a_deferred_message_that_fails_is_one_clear_error(tmp_path: Path) -> None:
    bus = Bus(lambda: 0)
    rec = Recorder(tmp_path / "bag")
    rec.open(bus.qos)
    bus.add_tap(rec)

    def broken() -> object:
        raise SimulationError("rendering camera 3 failed: lost the GPU")

    bus.publish("/cam_rgb", "sensor_msgs/msg/Image", Deferred(broken))
    with pytest.raises(BagError, match="cannot record /cam_rgb: rendering camera 3 failed"):
        rec.close()
