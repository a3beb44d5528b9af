"""The live view: a real foxglove-sdk server fed from a real bus, read by a real WebSocket
client (tests/live/foxglove_client.py); its configuration checks and its pacing."""

from __future__ import annotations

import json
import socket
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from mcap.records import Schema
from mcap_ros2.decoder import DecoderFactory
from websockets.exceptions import InvalidStatus

from harness.bus import TRANSIENT_LOCAL, Bus
from harness.bus.bus import Envelope
from harness.live.errors import LiveViewError
from harness.live.view import LiveConfig, LiveView, Pacer
from harness.serde.messages import clock, serialize, tf_message, transform_stamped
from tests.live.foxglove_client import LEGACY_SUBPROTOCOL, SUBPROTOCOL, LiveClient, open_client

TF = "tf2_msgs/msg/TFMessage"
CLOCK = "rosgraph_msgs/msg/Clock"
IMAGE = "sensor_msgs/msg/Image"


@pytest.fixture
def view() -> Iterator[tuple[LiveView, list[str]]]:
    notices: list[str] = []
    v = LiveView.start(LiveConfig(port=0, wait_s=20.0), notice=notices.append)
    try:
        yield v, notices
    finally:
        v.close()


def _until(cond: Callable[[], bool], timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not cond():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.01)


def _static(ns: int, parent: str, child: str) -> object:
    return tf_message([transform_stamped(ns, parent, child, (1.0, 2.0, 0.0),
                                         (0.0, 0.0, 0.0, 1.0))])


def test_a_late_subscriber_gets_every_latched_tf_static(
        view: tuple[LiveView, list[str]]) -> None:
    """Three publishers share /tf_static (depth 1 each, as ROS latches per publisher): a client
    that subscribes after all of them were published gets all three, with their bytes and
    simulation times; a volatile topic published before it subscribed is not replayed."""
    live, notices = view
    now = [0]
    bus = Bus(lambda: now[0])
    bus.add_tap(live)
    statics = [_static(0, "world", "odom"), _static(0, "cam_l", "cam_l_world"),
               _static(0, "cam_r", "cam_r_world")]
    pub = bus.advertise("/tf_static", TF, TRANSIENT_LOCAL)
    live.advertise({"/tf": TF, "/tf_static": TF}, bus.qos)
    for msg in statics:
        pub.publish(msg)
    now[0] = 5_000_000
    bus.publish("/tf", TF, _static(now[0], "odom", "base_link"))

    client = LiveClient(live.port, ["/tf", "/tf_static"]).start()  # /tf is registered first
    _until(lambda: len(client.got.messages.get("/tf_static", [])) == 3)
    now[0] = 6_000_000
    late_tf = _static(now[0], "odom", "base_link")
    bus.publish("/tf", TF, late_tf)
    _until(lambda: len(client.got.messages.get("/tf", [])) == 1)
    live.close()
    got = client.join()
    assert notices[0] == f"live view on ws://127.0.0.1:{live.port} (Foxglove: Open connection " \
        "→ Foxglove WebSocket)"
    assert got.messages["/tf_static"] == [(0, serialize(m, TF)) for m in statics]
    assert got.messages["/tf"] == [(6_000_000, serialize(late_tf, TF))]
    ch = got.channels["/tf_static"]
    assert (ch["encoding"], ch["schemaEncoding"], ch["schemaName"]) == ("cdr", "ros2msg", TF)
    assert "geometry_msgs/TransformStamped[] transforms" in ch["schema"]


def test_wait_holds_until_a_client_subscribes_and_time_follows_the_simulation(
        view: tuple[LiveView, list[str]]) -> None:
    live, notices = view
    now = [0]
    bus = Bus(lambda: now[0])
    bus.advertise("/clock", CLOCK)
    live.advertise({t: i.msgtype for t, i in bus.topics().items()}, bus.qos)
    bus.add_tap(live)
    client = LiveClient(live.port, ["/clock"]).start()
    t0 = time.monotonic()
    assert live.wait_for_client() is True
    assert time.monotonic() - t0 < 15.0
    assert live.has_client
    for k in range(5):
        now[0] = k * 16_666_666
        bus.publish("/clock", CLOCK, clock(now[0]))
        live.tick()
    _until(lambda: len(client.got.times) == 5 and len(client.got.messages.get("/clock", [])) == 5)
    live.close()
    got = client.join()
    assert got.server_info["op"] == "serverInfo" and "time" in got.server_info["capabilities"]
    assert got.times == [k * 16_666_666 for k in range(5)]
    assert [t for t, _ in got.messages["/clock"]] == got.times
    assert notices[-1] == "a Foxglove client is connected; running"


def test_clients_of_either_protocol_name_receive_and_decode_the_topics(
        view: tuple[LiveView, list[str]]) -> None:
    """One client offers only the specification's name (foxglove.websocket.v1: Lichtblick,
    @foxglove/ws-protocol), one only the SDK's (foxglove.sdk.v1): each is answered with the
    name it offered and gets every message, its bytes decoding with the advertised schema."""
    live, _notices = view
    now = [0]
    bus = Bus(lambda: now[0])
    bus.add_tap(live)
    live.advertise({"/clock": CLOCK, "/tf": TF}, bus.qos)
    clients = {name: LiveClient(live.port, ["/clock", "/tf"], subprotocol=name,
                                confirm=True).start()
               for name in (LEGACY_SUBPROTOCOL, SUBPROTOCOL)}
    for c in clients.values():  # the server took both subscriptions of each
        assert c.confirmed.wait(30)
        assert c.got.error is None, c.got.error
    sent: dict[str, list[tuple[int, bytes]]] = {"/clock": [], "/tf": []}
    for k in range(1, 4):
        now[0] = k * 10_000_000
        bus.publish("/clock", CLOCK, clock(now[0]))
        tf = _static(now[0], "odom", "base_link")
        bus.publish("/tf", TF, tf)
        live.tick()
        sent["/clock"].append((now[0], serialize(clock(now[0]), CLOCK)))
        sent["/tf"].append((now[0], serialize(tf, TF)))
    for c in clients.values():
        _until(lambda c=c: len(c.got.messages.get("/tf", [])) == 3)  # type: ignore[misc]
    live.close()
    for name, c in clients.items():
        got = c.join()
        assert got.subprotocol == name
        assert got.server_info["name"] == "srr" and "time" in got.server_info["capabilities"]
        assert got.messages["/clock"] == sent["/clock"], name
        assert got.messages["/tf"] == sent["/tf"], name
        ch = got.channels["/tf"]
        decode = DecoderFactory().decoder_for(ch["encoding"], Schema(
            id=0, name=ch["schemaName"], encoding=ch["schemaEncoding"],
            data=ch["schema"].encode()))
        assert decode is not None
        tfs = [decode(data).transforms[0] for _, data in got.messages["/tf"]]
        assert [(t.header.frame_id, t.child_frame_id, t.transform.translation.x) for t in tfs] \
            == [("odom", "base_link", 1.0)] * 3
        assert [t.header.stamp.nanosec for t in tfs] == [10_000_000, 20_000_000, 30_000_000]
        assert got.times[-3:] == [10_000_000, 20_000_000, 30_000_000]


def test_a_client_offering_neither_name_is_refused(view: tuple[LiveView, list[str]]) -> None:
    live, _notices = view
    with pytest.raises(InvalidStatus, match="HTTP 400"):
        open_client(live.port, 10.0, "foxglove.websocket.v2")


def test_wait_gives_up_after_its_time_and_says_so() -> None:
    notices: list[str] = []
    with LiveView.start(LiveConfig(port=0, wait_s=0.2), notice=notices.append) as live:
        t0 = time.monotonic()
        assert live.wait_for_client() is False
        assert 0.2 <= time.monotonic() - t0 < 5.0
    assert notices[-2:] == [f"waiting up to 0.2 s for a Foxglove client on {live.url}",
                            "no Foxglove client subscribed to a topic within 0.2 s; "
                            "running anyway"]


def test_a_wait_of_zero_is_no_wait_and_says_nothing() -> None:
    # it said "waiting up to 0 s for a Foxglove client", then that none came
    notices: list[str] = []
    with LiveView.start(LiveConfig(port=0, wait_s=0.0), notice=notices.append) as live:
        assert live.wait_for_client() is False
    assert not [n for n in notices if "waiting" in n or "no Foxglove client" in n], notices


@pytest.mark.slow
def test_a_client_that_stops_reading_does_not_hold_the_end_of_the_run(
        view: tuple[LiveView, list[str]]) -> None:
    """A client subscribed to a camera that stops reading (a frozen app, a sleeping laptop):
    closing the view ends its connection within a few seconds; foxglove-sdk's own stop waited
    about 45 s for it."""
    live, _notices = view
    live.advertise({"/cam_rgb": IMAGE})
    with open_client(live.port) as ws:
        while (msg := json.loads(ws.recv(timeout=10)))["op"] != "advertise":
            pass
        ws.send(json.dumps({"op": "subscribe", "subscriptions": [
            {"id": 1, "channelId": msg["channels"][0]["id"]}]}))
        _until(lambda: live.has_client)
        frame = bytes(640 * 480 * 3)
        for k in range(150):  # 138 MB, far beyond what the sockets buffer
            live.log(Envelope("/cam_rgb", IMAGE, k * 33_333_333, k, None, raw=frame), frame)
            time.sleep(0.002)
        t0 = time.monotonic()
        live.close()
        assert time.monotonic() - t0 < 10.0


def test_a_port_in_use_is_one_clear_error() -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        with pytest.raises(LiveViewError, match=rf"cannot listen on 127\.0\.0\.1:{port}: .*in "
                           "use.*--foxglove-port"):
            LiveView.start(LiveConfig(port=port))


@pytest.mark.parametrize(("kwargs", "flag"), [
    ({"port": 65536}, "--foxglove-port"), ({"port": -1}, "--foxglove-port"),
    ({"host": " "}, "--foxglove-host"), ({"wait_s": -1.0}, "--foxglove-wait"),
    ({"wait_s": float("nan")}, "--foxglove-wait"), ({"rate": 0.0}, "--rate"),
    ({"rate": float("inf")}, "--rate"),
])
def test_config_refuses_bad_values(kwargs: dict[str, object], flag: str) -> None:
    with pytest.raises(LiveViewError, match=f"^{flag}: must"):
        LiveConfig(**kwargs)  # type: ignore[arg-type]


def test_pacer_sleeps_only_while_ahead_of_the_rate() -> None:
    wall = [100.0]
    slept: list[float] = []

    def sleep(s: float) -> None:
        slept.append(s)
        wall[0] += s

    pacer = Pacer(2.0, clock=lambda: wall[0], sleep=sleep)
    pacer.start()
    assert pacer.pace(1_000_000_000) == pytest.approx(0.5)  # 1 s sim at rate 2 is due at 0.5 s
    wall[0] += 3.0  # the computation fell behind
    assert pacer.pace(2_000_000_000) == 0.0
    assert slept == [pytest.approx(0.5)]
    # the ticks after a late one are paced from it, not raced through to catch up
    assert pacer.pace(2_500_000_000) == pytest.approx(0.25)
    assert Pacer(None).pace(10**12) == 0.0  # no rate: never sleeps


def test_pacer_paces_from_a_slow_first_tick() -> None:
    """The first tick (the first render) may come long after the wait for a client ended:
    the simulated second after it still takes a wall-clock second at rate 1 (it took 0.07 s:
    the first second of a watched run flew by)."""
    wall = [100.0]
    pacer = Pacer(1.0, clock=lambda: wall[0], sleep=lambda s: wall.__setitem__(0, wall[0] + s))
    pacer.start()
    wall[0] += 1.3  # building the first frame
    assert pacer.pace(0) == 0.0
    assert sum(pacer.pace(k * 16_666_667) for k in range(1, 61)) == pytest.approx(1.0)


@pytest.mark.slow
def test_a_run_stopped_while_it_waits_for_a_client_leaves_nothing(tmp_path: Path) -> None:
    """SIGTERM while ``--foxglove-wait`` holds the first tick: nothing was recorded, so, as
    for any stop before the first tick, exit 130 and no run directory (it once wrote a whole
    INTERRUPTED run of 0 s)."""
    import os
    import signal
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[2]
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "new" / "run"  # under a folder srr makes: it goes too
    proc = subprocess.Popen(
        [sys.executable, "-m", "harness.cli", "run", str(root / "scenarios" /
         "forklift_warehouse.yaml"), "--duration", "2", "-q", "--out", str(out), "--foxglove",
         "--foxglove-port", str(port), "--foxglove-wait", "120"],
        cwd=root, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "PYTHONPATH": str(root)})
    assert proc.stderr is not None
    for line in proc.stderr:  # the notice comes once the client is waited for
        if "waiting up to" in line:
            break
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == (
        f"srr run: interrupted; before the first tick: nothing was recorded and {out} was "
        "removed"), err
    assert list(tmp_path.iterdir()) == []
