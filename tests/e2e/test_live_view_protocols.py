"""``--foxglove`` serves clients of either name of the Foxglove WebSocket protocol: a real run of
the dock scene watched at once by a client offering only ``foxglove.websocket.v1`` (what
Lichtblick and ``@foxglove/ws-protocol`` offer) and one offering only ``foxglove.sdk.v1``."""

from __future__ import annotations

import re
import threading
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.records import Schema
from mcap_ros2.decoder import DecoderFactory

from harness import api
from tests.e2e.bagread import mcap_file
from tests.live.foxglove_client import LEGACY_SUBPROTOCOL, SUBPROTOCOL, LiveClient, Received

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "dock_worker_crossing.yaml"
WATCHED = ["/clock", "/tf", "/tf_static", "/odom", "/dock_cam_left_rgb", "/perception/tracks"]


@pytest.mark.slow
def test_clients_of_both_protocol_names_watch_one_run(tmp_path: Path) -> None:
    clients: dict[str, LiveClient] = {}
    ready = threading.Event()

    def notice(line: str) -> None:
        # the server is up (on the port the system picked, port 0): both clients connect and
        # subscribe, and the run waits here until the server took every subscription
        found = re.match(r"live view on ws://127\.0\.0\.1:(\d+) ", line)
        if found is None:
            return
        for name in (LEGACY_SUBPROTOCOL, SUBPROTOCOL):
            clients[name] = LiveClient(int(found.group(1)), WATCHED, subprotocol=name,
                                       confirm=True).start()
        for c in clients.values():
            c.confirmed.wait(60)
        ready.set()

    scenario = api.load(SCENARIO, overrides=["duration=1"])
    api.run_scenario(scenario, source=str(SCENARIO), out=tmp_path / "run", notice=notice,
                     live=api.LiveConfig(port=0, wait_s=60.0))
    assert ready.is_set() and set(clients) == {LEGACY_SUBPROTOCOL, SUBPROTOCOL}
    got: dict[str, Received] = {name: c.join() for name, c in clients.items()}

    recorded: dict[str, list[tuple[int, bytes]]] = {}
    with mcap_file(tmp_path / "run").open("rb") as f:
        for _, channel, message in make_reader(f).iter_messages(log_time_order=False):
            recorded.setdefault(channel.topic, []).append((message.log_time, message.data))
    for name, rec in got.items():
        assert rec.subprotocol == name
        assert not [t for t in rec.texts if t["op"] == "status"], (name, rec.texts)
        for topic in WATCHED:  # every message, in order, the recorded bytes at their times
            assert rec.messages[topic] == recorded[topic], (name, topic)
        for topic in ("/odom", "/dock_cam_left_rgb"):
            ch = rec.channels[topic]
            decode = DecoderFactory().decoder_for(ch["encoding"], Schema(
                id=0, name=ch["schemaName"], encoding=ch["schemaEncoding"],
                data=ch["schema"].encode()))
            assert decode is not None
            for t_ns, data in rec.messages[topic]:
                msg = decode(data)
                assert msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec == t_ns
        image = decode(rec.messages["/dock_cam_left_rgb"][-1][1])
        assert len(image.data) == image.height * image.step > 0
