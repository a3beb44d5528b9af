"""Seed 002's RTSP multi-camera graph end to end: a two-camera scene served by GStreamer's RTSP
server, each URL read by a real RTSP client (FFmpeg's, through PyAV, over RTP/TCP), every frame
decoded and checked against the raw frame rendered at the same simulation time."""

from __future__ import annotations

import socket
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import av
import numpy as np
import pytest

from harness import api
from harness.cli import main
from harness.graph.nodes.video import RTSP_HUB
from harness.video import psnr, read_sim_time, sim_time_of_user_data
from harness.video.errors import StreamError
from tests.conftest import ModuleTmp
from tests.e2e.bagread import decoded

SCENARIO = Path(__file__).with_name("rtsp_two_cameras.yaml")
FPS = 10
PERIOD_NS = 1_000_000_000 // FPS  # the gate's step (6 ticks of 60 Hz) in simulation time
DURATION_S = 1.5


def _unused_ports(n: int) -> list[int]:
    """``n`` ports that no socket here held a moment ago. Scenario ports are 1..65535 (no 0
    for "any"), so a server binding them later may find one taken by then: see
    :func:`streamed` picks others then."""
    socks = []
    for _ in range(n):
        s = socket.socket()
        s.bind(("127.0.0.1", 0))
        socks.append(s)
    ports = [int(s.getsockname()[1]) for s in socks]
    for s in socks:
        s.close()
    return ports


@dataclass
class Received:
    """What one RTSP client got: per frame (SEI simulation time, SEI index, pts, RGB)."""

    url: str
    frames: list[tuple[int, int, int | None, np.ndarray]] = field(default_factory=list)
    size: tuple[int, int] | None = None
    codec: str = ""
    error: str | None = None


def _client(url: str, out: Received, deadline: float) -> None:
    """Connect (retrying until the server is up), read and decode until the stream ends."""
    container: Any = None
    while container is None:
        try:
            container = av.open(url, options={"rtsp_transport": "tcp"}, timeout=10)
        except (av.error.ConnectionRefusedError, av.error.OSError) as err:
            if time.monotonic() > deadline:
                out.error = f"no connection: {err}"
                return
            time.sleep(0.05)
    try:
        stream = container.streams.video[0]
        out.codec = stream.codec_context.name
        for packet in container.demux(stream):
            if packet.size == 0:
                continue
            for frame in packet.decode():
                out.size = (frame.width, frame.height)
                # the decoder hands over the SEI as side data, however RTP split the frame
                (sei,) = [t for sd in frame.side_data
                          if (t := sim_time_of_user_data(bytes(sd))) is not None]
                in_packet = read_sim_time(bytes(packet))
                assert in_packet in (None, sei)
                out.frames.append((sei.time_ns, sei.index, frame.pts,
                                   frame.to_ndarray(format="rgb24")))
    except av.error.EOFError:
        pass
    except Exception as err:  # reported by the test
        out.error = f"{type(err).__name__}: {err}"
    finally:
        container.close()


def _serve(run_dir: Path, ports: list[int]) -> tuple[dict[str, Received], Any] | None:
    """Run the two-camera scene serving on ``ports``, with a client per URL started once the
    run serves them all (so a client never reaches another server); None when a port was
    taken by then (the run stopped before writing anything)."""
    scenario = api.load(SCENARIO, overrides=[
        f"cameras.0.port={ports[0]}", f"cameras.1.port={ports[1]}", "rtsp.wait_s=60"])
    urls = [f"rtsp://127.0.0.1:{ports[0]}/dock_cam_left",
            f"rtsp://127.0.0.1:{ports[1]}/right/camera"]
    got = {u: Received(u) for u in urls}
    threads = [threading.Thread(target=_client, args=(u, got[u], time.monotonic() + 60),
                                daemon=True) for u in urls]
    notices: list[str] = []

    def notice(text: str) -> None:
        notices.append(text)
        if text.startswith("rtsp: serving "):  # every port is bound now
            for t in threads:
                t.start()

    try:
        res = api.run_scenario(scenario, source=str(SCENARIO), out=run_dir, notice=notice)
    except StreamError as err:
        if "Address already in use" not in str(err):
            raise
        return None
    for t in threads:
        t.join(30)
    assert any("serving " + urls[0] in n for n in notices), notices
    return got, res.summary


@pytest.fixture(scope="module")
def streamed(module_tmp: ModuleTmp) -> tuple[dict[str, Received], Path, dict[str, Any]]:
    run_dir = module_tmp("rtsp") / "run"
    for _ in range(5):  # a port taken since it was picked: pick others
        served = _serve(run_dir, _unused_ports(2))
        if served is not None:
            return served[0], run_dir, served[1]
    pytest.fail("five pairs of ports were all taken before the run could bind them")


def _raw_frames(run_dir: Path) -> dict[str, dict[int, np.ndarray]]:
    out: dict[str, dict[int, np.ndarray]] = {}
    for topic, _schema, t, msg in decoded(run_dir):
        if topic.endswith("_rgb"):
            img = np.frombuffer(bytes(msg.data), np.uint8).reshape(msg.height, msg.width, 3)
            out.setdefault(topic.strip("/").removesuffix("_rgb"), {})[t] = img
    return out


@pytest.mark.slow
def test_each_url_streams_h264_at_the_configured_rate(streamed: Any) -> None:
    got, _run_dir, summary = streamed
    n = round(DURATION_S * FPS)
    assert "/World/RTSPMultiGraph" in summary["graphs"]
    for url, rec in got.items():
        assert rec.error is None, f"{url}: {rec.error}"
        assert rec.codec == "h264"
        assert rec.size == (160, 120), url
        times = [t for t, _, _, _ in rec.frames]
        # every gated tick once, none twice, none lost: the gate's rate on the wire
        assert times == [k * PERIOD_NS for k in range(n)], (url, times)
        assert [i for _, i, _, _ in rec.frames] == list(range(n))
        pts = [p for _, _, p, _ in rec.frames if p is not None]
        assert len(pts) >= n - 1
        # RTP timestamps (90 kHz) advance by the frame period: 10 frames per second of stream
        assert set(np.diff(pts).tolist()) == {90_000 // FPS}, pts


@pytest.mark.slow
def test_frames_match_the_raw_frames_rendered_at_the_same_time(streamed: Any) -> None:
    got, run_dir, _summary = streamed
    raw = _raw_frames(run_dir)
    for url, rec in got.items():
        cam = "dock_cam_left" if url.endswith("/dock_cam_left") else "dock_cam_right"
        scores = [psnr(img, raw[cam][t]) for t, _, _, img in rec.frames]
        assert len(scores) == round(DURATION_S * FPS)
        assert min(scores) >= 30.0, (url, [round(s, 1) for s in scores])
        # and the frames differ from each other (the worker walks): not one frame repeated
        first, last = rec.frames[0][3], rec.frames[-1][3]
        assert psnr(first, last) < min(scores)


def test_a_port_in_use_is_one_clear_line(tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    with socket.socket() as blocker:
        blocker.bind(("127.0.0.1", 0))
        blocker.listen()
        busy = blocker.getsockname()[1]
        code = main(["run", str(SCENARIO), "--out", str(tmp_path / "run"), "-q",
                     "--set", f"cameras.1.port={busy}"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1, err
    assert err == (f"srr run: {SCENARIO}: cameras[1].port: cannot serve "
                   f"rtsp://127.0.0.1:{busy}/right/camera: Error binding to address "
                   f"127.0.0.1:{busy}: Address already in use")
    assert not (tmp_path / "run").exists()


def test_the_graph_has_the_seed_shape() -> None:
    scenario = api.load(SCENARIO)
    sim = api.build_graphs(scenario, str(SCENARIO))
    try:
        graph = sim.stage.graph("/World/RTSPMultiGraph")
        names = sorted(n.name for n in graph.nodes)
        assert names == sorted(["OnPlaybackTick", "IsaacSimulationGate",
                                "RP_dock_cam_left", "RTSP_dock_cam_left",
                                "RP_dock_cam_right", "RTSP_dock_cam_right"])
        assert RTSP_HUB not in sim.ctx.extras  # nothing listens before a run
    finally:
        sim.close()
