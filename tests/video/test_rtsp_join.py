"""A client that joins an RTSP stream mid-way starts at a keyframe at the next frame.

Real parts only: srr's h264 encoder (x264 through PyAV), the RTSP hub (gst-rtsp-server) on a
port the system picks, and two FFmpeg RTSP clients (PyAV) over RTP/TCP. The keyframe interval
is far longer than the test, so the only keyframes are the ones the clients' arrivals ask for.
The second client is started only once the first has decoded some frames (an event, not a
sleep), and the frames stop once the second has what it needs."""

from __future__ import annotations

import socket
import threading
from dataclasses import dataclass, field

import av
import numpy as np
import pytest

from harness.video import H264Encoder, H264Settings, psnr, read_sim_time, sim_time_of_user_data
from harness.video.rtsp import RtspHub, StreamConfig
from harness.video.sei import nal_units

FPS = 30
PERIOD_NS = 1_000_000_000 // FPS
W, H = 160, 120
SETTINGS = H264Settings(keyframe_interval=100_000, crf=18, threads=1)
FIRST_FRAMES = 10  # frames client 1 decodes before client 2 starts
SECOND_PACKETS = 5  # packets client 2 reads before the frames stop
MAX_FRAMES = 30 * FPS  # bounds a failing test; a passing one stops far earlier


def picture(index: int) -> np.ndarray:
    """A smooth picture that moves with ``index`` (each frame differs from the last)."""
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    r = 128 + 100 * np.sin((x + 3 * index) / 17.0)
    g = 128 + 100 * np.cos((y - 2 * index) / 13.0)
    b = 128 + 60 * np.sin((x + y + index) / 23.0)
    return np.stack([r, g, b], axis=-1).astype(np.uint8)


@dataclass
class Client:
    """What one RTSP client got: per packet (keyframe, SEI index); per frame (key, SEI index,
    PSNR against the picture of that index)."""

    packets: list[tuple[bool, int | None]] = field(default_factory=list)
    frames: list[tuple[bool, int, float]] = field(default_factory=list)
    first_nals: set[int] = field(default_factory=set)  # NAL unit types of the first packet
    error: str | None = None
    decoded: threading.Event = field(default_factory=threading.Event)  # FIRST_FRAMES reached
    enough: threading.Event = field(default_factory=threading.Event)  # SECOND_PACKETS reached


def read(url: str, out: Client) -> None:
    try:
        container = av.open(url, options={"rtsp_transport": "tcp"}, timeout=20)
    except av.error.FFmpegError as err:
        out.error = f"no connection: {err}"
        out.enough.set()
        out.decoded.set()
        return
    try:
        stream = container.streams.video[0]
        for packet in container.demux(stream):
            if packet.size == 0:
                continue
            data = bytes(packet)
            if not out.packets:
                out.first_nals = {data[head] & 0x1F for _, head, _ in nal_units(data)}
            sim = read_sim_time(data)
            out.packets.append((bool(packet.is_keyframe), sim.index if sim else None))
            for frame in packet.decode():
                (sei,) = [t for sd in frame.side_data
                          if (t := sim_time_of_user_data(bytes(sd))) is not None]
                out.frames.append((bool(frame.key_frame), sei.index,
                                   psnr(frame.to_ndarray(format="rgb24"), picture(sei.index))))
            if len(out.frames) >= FIRST_FRAMES:
                out.decoded.set()
            if len(out.packets) >= SECOND_PACKETS:
                out.enough.set()
    except av.error.EOFError:
        pass
    except Exception as err:  # reported by the test
        out.error = f"{type(err).__name__}: {err}"
    finally:
        container.close()
        out.decoded.set()
        out.enough.set()


def produce(hub: RtspHub, config: StreamConfig, stop: threading.Event) -> int:
    """The RTSP node's loop: paced at real time, a frame only while someone watches, a
    keyframe when the stream asks for one. Returns the frames encoded."""
    stream = hub.stream(config)
    encoder = H264Encoder(W, H, FPS, SETTINGS, "test")
    encoded = 0
    for index in range(MAX_FRAMES):
        if stop.is_set():
            break
        hub.pace(index * PERIOD_NS)
        if stream.clients == 0:
            continue
        for unit in encoder.encode(picture(index), index * PERIOD_NS,
                                   keyframe=stream.wants_keyframe(), index=index):
            stream.push(unit)
        encoded += 1
    return encoded


@pytest.mark.slow
def test_a_client_joining_mid_stream_decodes_its_first_frame() -> None:
    hub = RtspHub(rate=1.0)
    config = StreamConfig(0, "/cam")  # port 0: the system picks, the stream tells which
    stream = hub.stream(config)
    assert stream.port > 0
    first, second = Client(), Client()
    stop = threading.Event()
    readers: list[threading.Thread] = []
    encoded: list[int] = []
    producer = threading.Thread(target=lambda: encoded.append(produce(hub, config, stop)),
                                daemon=True)
    try:
        producer.start()
        readers.append(threading.Thread(target=read, args=(stream.url, first), daemon=True))
        readers[0].start()
        assert first.decoded.wait(60), "client 1 decoded nothing"
        assert first.error is None, first.error
        readers.append(threading.Thread(target=read, args=(stream.url, second), daemon=True))
        readers[1].start()
        assert second.enough.wait(60), "client 2 got nothing"
        stop.set()
        producer.join(30)
    finally:
        stop.set()
        hub.close()
        for t in readers:
            t.join(30)
    assert first.error is None, first.error
    assert second.error is None, second.error
    assert not producer.is_alive() and encoded[0] < MAX_FRAMES

    # client 1: from its first (key)frame on, every frame once, all decoded well
    key, start = first.packets[0]
    assert key and start is not None
    assert [i for _, i, _ in first.frames] == list(range(start, start + len(first.frames)))
    assert min(s for _, _, s in first.frames) >= 30.0

    # client 2 joined mid-stream, and its very first packet is a keyframe that decodes
    key, joined = second.packets[0]
    assert key, second.packets[:SECOND_PACKETS]
    assert {7, 8, 5} <= second.first_nals  # in-band SPS and PPS, then the IDR slice
    assert joined is not None and joined >= start + FIRST_FRAMES
    assert second.frames[0][:2] == (True, joined)
    assert second.frames[0][2] >= 30.0, second.frames[0]
    assert [i for _, i, _ in second.frames] == list(range(joined, joined + len(second.frames)))
    assert min(s for _, _, s in second.frames) >= 30.0
    # that keyframe went to client 1 as well, which kept every frame
    assert (True, joined) in [(k, i) for k, i, _ in first.frames]


def test_port_zero_serves_on_the_port_the_system_picked() -> None:
    with RtspHub() as hub:
        stream = hub.stream(StreamConfig(0, "/cam"))
        other = hub.stream(StreamConfig(0, "/other"))  # port 0 again: the same server
        assert stream.port > 0 and other.port == stream.port
        assert stream.url == f"rtsp://127.0.0.1:{stream.port}/cam"
        assert hub.stream(StreamConfig(0, "/cam")) is stream


def _describe(url: str, port: int) -> socket.socket:
    """Connect and send a DESCRIBE without waiting for its answer (which the server gives only
    once a keyframe has flowed)."""
    sock = socket.create_connection(("127.0.0.1", port), timeout=10)
    sock.sendall(f"DESCRIBE {url} RTSP/1.0\r\nCSeq: 1\r\nAccept: application/sdp\r\n\r\n"
                 .encode())
    return sock


def test_clients_of_two_mounts_on_one_port_wait_for_the_run_together() -> None:
    # rtsp.wait_s holds the run until every mount has a client; a client's DESCRIBE waits for
    # the first keyframe, which only the run makes. With one thread for all of a port's
    # clients, the first DESCRIBE held the second mount's client until the wait ran out.
    with RtspHub() as hub:
        a = hub.stream(StreamConfig(0, "/camA"))
        b = hub.stream(StreamConfig(0, "/cams/b"))
        socks = [_describe(s.url, s.port) for s in (a, b)]
        try:
            assert hub.wait_for_clients(5.0) == []
            assert (a.clients, b.clients) == (1, 1)
        finally:
            for sock in socks:
                sock.close()
