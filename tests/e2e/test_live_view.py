"""``srr run --foxglove``: a real run of the dock scene (cameras, TF, markers, ground truth)
served over the Foxglove WebSocket protocol to a real client, and bad live-view input."""

from __future__ import annotations

import json
import os
import re
import socket
import subprocess
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from mcap.records import Schema
from mcap_ros2.decoder import DecoderFactory

from harness.cli import main
from tests.conftest import ModuleTmp
from tests.e2e.bagread import mcap_file
from tests.live.foxglove_client import LiveClient, Received

ROOT = Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "scenarios" / "dock_worker_crossing.yaml"
SHORT = ["--set", "duration=2", "-q"]
WATCHED = ["/clock", "/tf", "/tf_static", "/odom", "/dock_cam_left_rgb", "/gt/forklift/tf",
           "/perception/tracks"]


@dataclass(frozen=True)
class LiveRun:
    code: int
    summary: dict[str, Any]
    run_dir: Path
    got: Received
    plain: dict[str, Any]  # the summary of the same run without --foxglove


@pytest.fixture(scope="module")
def live_run(module_tmp: ModuleTmp) -> Iterator[LiveRun]:
    tmp = module_tmp("live")
    # port 0: the live view binds a port the system picks and says which (a port picked here
    # beforehand could be taken by another process before the run binds it); the client
    # connects once it is known, while the run waits for it
    proc = subprocess.Popen([sys.executable, "-m", "harness.cli", "run", str(SCENARIO),
                             "--out", str(tmp / "live"), *SHORT, "--foxglove",
                             "--foxglove-port", "0", "--foxglove-wait", "30", "--rate", "4"],
                            cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert proc.stderr is not None
    said = []
    for line in proc.stderr:
        said.append(line)
        if (bound := re.search(r"live view on ws://127\.0\.0\.1:(\d+)", line)) is not None:
            break
    assert bound is not None, "".join(said) + proc.communicate()[1]
    client = LiveClient(int(bound.group(1)), WATCHED).start()
    said.append(proc.communicate()[1])
    code = proc.returncode
    assert code in (0, 1), "".join(said)
    got = client.join()
    assert main(["run", str(SCENARIO), "--out", str(tmp / "plain"), *SHORT]) == code
    yield LiveRun(code, json.loads((tmp / "live" / "summary.json").read_text()), tmp / "live",
                  got, json.loads((tmp / "plain" / "summary.json").read_text()))


def _recorded(run_dir: Path) -> dict[str, list[tuple[int, bytes]]]:
    out: dict[str, list[tuple[int, bytes]]] = {}
    with mcap_file(run_dir).open("rb") as f:
        for _, channel, message in make_reader(f).iter_messages(log_time_order=False):
            out.setdefault(channel.topic, []).append((message.log_time, message.data))
    return out


def _decoder(channel: dict[str, Any]) -> Callable[[bytes], Any]:
    """mcap-ros2-support's decoder for an advertised channel, from its advertised schema."""
    schema = Schema(id=0, name=channel["schemaName"], encoding=channel["schemaEncoding"],
                    data=channel["schema"].encode())
    decode = DecoderFactory().decoder_for(channel["encoding"], schema)
    assert decode is not None
    return decode


@pytest.mark.slow
def test_the_client_sees_every_topic_advertised_as_ros2_cdr(live_run: LiveRun) -> None:
    got = live_run.got
    assert got.server_info["name"] == "srr" and "time" in got.server_info["capabilities"]
    assert not [t for t in got.texts if t["op"] == "status"], got.texts  # no "Unknown channel"
    topics = live_run.summary["topics"]
    assert set(got.channels) == set(topics)  # all of them, /gt/* and both cameras included
    for name, ch in got.channels.items():
        assert (ch["encoding"], ch["schemaEncoding"]) == ("cdr", "ros2msg"), name
        assert ch["schemaName"] == topics[name]["type"], name
    with mcap_file(live_run.run_dir).open("rb") as f:  # the schema text the bag has
        schemas = {s.name: s.data.decode() for s in make_reader(f).get_summary().schemas.values()}
    assert all(ch["schema"] == schemas[ch["schemaName"]] for ch in got.channels.values())


@pytest.mark.slow
def test_subscribed_topics_carry_the_recorded_bytes_at_simulation_time(
        live_run: LiveRun) -> None:
    """Every message of the watched topics arrives, in order, with the recorded CDR bytes and
    the recorded log time (simulation ns); /tf_static's three publishers all arrive."""
    recorded = _recorded(live_run.run_dir)
    for topic in WATCHED:
        assert live_run.got.messages[topic] == recorded[topic], topic
    assert len(live_run.got.messages["/tf_static"]) == 3
    odom_decode = _decoder(live_run.got.channels["/odom"])
    for t_ns, data in live_run.got.messages["/odom"]:
        odom = odom_decode(data)
        assert odom.header.stamp.sec * 10**9 + odom.header.stamp.nanosec == t_ns
    image_decode = _decoder(live_run.got.channels["/dock_cam_left_rgb"])
    first = image_decode(live_run.got.messages["/dock_cam_left_rgb"][0][1])
    assert len(first.data) == first.height * first.step > 0


@pytest.mark.slow
def test_time_broadcast_is_the_simulation_clock(live_run: LiveRun) -> None:
    times = live_run.got.times
    ticks = live_run.summary["ticks"]
    hz = live_run.summary["tick_hz"]
    assert times == [k * 1_000_000_000 // hz for k in range(ticks)]


@pytest.mark.slow
def test_the_recording_is_the_same_with_and_without_the_live_view(live_run: LiveRun) -> None:
    assert live_run.code == 1  # MISMATCH: the shipped baseline is for the 36 s scene
    assert live_run.summary["digest"] == live_run.plain["digest"]
    assert {t: v["sha256"] for t, v in live_run.summary["topics"].items()} == \
        {t: v["sha256"] for t, v in live_run.plain["topics"].items()}


def test_a_port_in_use_exits_2_with_one_line(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        code = main(["run", str(SCENARIO), "--out", str(tmp_path / "r"), *SHORT, "--foxglove",
                     "--foxglove-port", str(port)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "Traceback" not in err
    assert err.startswith(f"srr run: --foxglove: cannot listen on 127.0.0.1:{port}: ")
    assert "in use" in err
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize("out", [None, "a/b/r"])
def test_a_refused_run_leaves_no_folder_behind(out: str | None, tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    # the default run directory (reports/<scenario>/<run id>) or one under folders that do
    # not exist yet: refused once the scene is built, it left reports/<scenario>/ (or a/b/)
    monkeypatch.chdir(tmp_path)
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        code = main(["run", str(SCENARIO), *(["--out", out] if out else []), *SHORT,
                     "--foxglove", "--foxglove-port", str(port)])
    assert code == 2, capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("args", "message"), [
    (["--foxglove", "--foxglove-port", "70000"],
     "srr run: --foxglove-port: must be a port number 0..65535, got 70000"),
    (["--foxglove", "--rate", "0"], "srr run: --rate: must be > 0"),
    (["--rate", "2"], "srr run: --rate: only with --foxglove (the live view)"),
    (["--foxglove", "--repeat", "2"], "srr run: --foxglove: watch one run, not a --repeat"),
])
def test_bad_live_options_exit_2_with_one_line(args: list[str], message: str, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", str(SCENARIO), "--out", str(tmp_path / "r"), *SHORT, *args])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and err.startswith(message)
    assert not (tmp_path / "r").exists()
