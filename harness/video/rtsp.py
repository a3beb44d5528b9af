"""RTSP servers for camera streams: GStreamer's gst-rtsp-server, fed with srr's own h264.

One :class:`RtspHub` per run owns a GLib main loop on a thread of its own and one
``GstRTSPServer`` per port (several mount paths may share a port). Each client of a mount gets
a pipeline of its own, ``appsrc ! rtph264pay``: the access units come ready-made from the
mount's one :class:`~harness.video.codec.H264Encoder` (with their simulation-time SEI), so
GStreamer only packetizes them into RTP (RFC 6184) and serves RTSP (RTP over UDP or
interleaved in the RTSP TCP connection, as the client asks). Nothing is re-encoded, resampled
or repeated: each frame pushed goes on the wire once per client.

Every client starts at a keyframe, at the next frame: its pipeline is made when it asks
(DESCRIBE), which asks the encoder for a keyframe (:meth:`RtspStream.wants_keyframe`; the
other clients get that keyframe too), and :meth:`RtspStream.push` hands a pipeline nothing
before its first keyframe. The pipelines are not shared on purpose: with one pipeline for all
clients (gst-rtsp-server's shared media) a later client is added to the running pipeline and
gets whatever it sends next, frames queued before the client came included, so it would start
on frames that refer to pictures it never had.

The RTP timestamps of a client's stream start at its first frame and advance by simulation
time (90 kHz clock); the SEI carries the absolute simulation time (:mod:`harness.video.sei`).
Servers listen on ``127.0.0.1`` unless told otherwise, only while a run that asked for them
is going; a port that cannot be bound is a :class:`~harness.video.errors.StreamError` naming it.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

from harness.video import gst
from harness.video.codec import EncodedFrame
from harness.video.errors import StreamError

__all__ = ["DEFAULT_HOST", "RtspHub", "RtspStream", "StreamConfig"]

DEFAULT_HOST = "127.0.0.1"
#: Threads serving one port's RTSP clients, at most (each client has one while it is there).
CLIENT_THREADS = 64
_LAUNCH = ("( appsrc name=src is-live=true format=time do-timestamp=false "
           "caps=video/x-h264,stream-format=byte-stream,alignment=au "
           "! rtph264pay name=pay0 pt=96 config-interval=-1 )")


@dataclass(frozen=True)
class StreamConfig:
    """Where one camera is served: ``rtsp://<host>:<port><mount_path>`` (port 0: a free port
    the system picks, see :attr:`RtspStream.port`). ``where`` names the setting in errors
    (``scenarios/x.yaml: cameras[1].port``)."""

    port: int
    mount_path: str
    host: str = DEFAULT_HOST
    where: str = "rtsp"

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"rtsp://{host}:{self.port}{self.mount_path}"


class _Media:
    """One prepared pipeline of a mount: one client's."""

    __slots__ = ("appsrc", "base_ns", "last_pts", "start_wall", "started")

    def __init__(self, appsrc: Any) -> None:
        self.appsrc = appsrc
        self.started = False  # has had its first (key)frame
        self.base_ns = 0
        self.start_wall = 0.0  # monotonic time of the first frame
        self.last_pts = 0

    def backlog_s(self, now: float) -> float:
        """Stream time pushed but not yet due: the servers send at the stream's own pace."""
        return max(0.0, self.last_pts / 1e9 - (now - self.start_wall)) if self.started \
            else 0.0


class RtspStream:
    """One mount point. :meth:`push` hands it an encoded frame for every client."""

    def __init__(self, hub: RtspHub, config: StreamConfig) -> None:
        self.hub = hub
        self.config = config
        self._lock = threading.Lock()
        self._medias: list[_Media] = []
        self._need_key = False
        self.frames_pushed = 0
        self.frames_sent = 0  # summed over clients

    @property
    def port(self) -> int:
        """The port served: ``config.port``, or the one the system picked for port 0."""
        return self.hub._bound[self.config.port]

    @property
    def url(self) -> str:
        return self.config.url if self.config.port else replace(self.config, port=self.port).url

    @property
    def clients(self) -> int:
        """Clients now (one pipeline each).

        A pipeline exists from a client's DESCRIBE on; the server answers that DESCRIBE only
        once a keyframe has gone through the payloader (the SDP carries the stream's SPS and
        PPS), so frames must flow for a client to get to PLAY."""
        with self._lock:
            return len(self._medias)

    def wants_keyframe(self) -> bool:
        """True when a client arrived since the last keyframe: encode the next frame as one."""
        with self._lock:
            return self._need_key

    def push(self, frame: EncodedFrame) -> int:
        """Send ``frame`` to every client that has started (a new one starts at a keyframe);
        returns the number of pipelines it went to. Never blocks on a client."""
        G = self.hub.gst.Gst
        with self._lock:
            medias = list(self._medias)
            if frame.keyframe:
                self._need_key = False
        self.frames_pushed += 1
        sent = 0
        for m in medias:
            if not m.started:
                if not frame.keyframe:
                    continue
                m.started, m.base_ns, m.start_wall = True, frame.time_ns, time.monotonic()
            buf = G.Buffer.new_wrapped(frame.data)
            buf.pts = buf.dts = m.last_pts = max(0, frame.time_ns - m.base_ns)
            m.appsrc.emit("push-buffer", buf)
            sent += 1
        self.frames_sent += sent
        return sent

    # -- GLib thread ------------------------------------------------------------------------
    def _configure(self, _factory: Any, media: Any) -> None:
        appsrc = media.get_element().get_by_name("src")
        m = _Media(appsrc)

        def unprepared(_media: Any) -> None:
            with self._lock:
                if m in self._medias:
                    self._medias.remove(m)

        media.connect("unprepared", unprepared)
        with self._lock:
            self._medias.append(m)
            self._need_key = True

    def _end(self) -> list[_Media]:
        with self._lock:
            medias = list(self._medias)
        for m in medias:
            m.appsrc.emit("end-of-stream")
        return medias


class RtspHub:
    """The run's RTSP servers. :meth:`stream` binds a port (at once: a port in use is an
    error before anything runs); :meth:`close` ends every stream and stops the servers.

    ``rate`` paces the run: :meth:`pace` sleeps so that simulated time goes at most ``rate``
    times as fast as the wall clock (None: as fast as it computes). The wall clock decides
    only how long to sleep; nothing it reads reaches the simulation or the recording."""

    def __init__(self, rate: float | None = None) -> None:
        self.gst = gst.load()
        G = self.gst
        self.rate = rate
        self._context = G.GLib.MainContext.new()
        self._loop = G.GLib.MainLoop.new(self._context, False)
        self._thread = threading.Thread(target=self._loop.run, name="srr-rtsp", daemon=True)
        self._thread.start()
        self._servers: dict[int, tuple[Any, Any]] = {}  # port → (server, source)
        self._streams: dict[tuple[int, str], RtspStream] = {}
        self._host: dict[int, str] = {}
        self._bound: dict[int, int] = {}  # configured port → bound port (port 0: any free one)
        self._t0: float | None = None
        self._closed = False

    @property
    def streams(self) -> list[RtspStream]:
        return list(self._streams.values())

    def stream(self, config: StreamConfig) -> RtspStream:
        """The stream at ``config``'s port and mount path, served from now on (made and bound
        on the first call)."""
        key = (config.port, config.mount_path)
        found = self._streams.get(key)
        if found is not None:
            return found
        if self._closed:
            raise StreamError(f"{config.where}: the RTSP servers are closed")
        G = self.gst
        if not config.mount_path.startswith("/"):
            raise StreamError(f"{config.where}: mount path must start with '/', got "
                              f"{config.mount_path!r}")
        entry = self._servers.get(config.port)
        if entry is not None and self._host[config.port] != config.host:
            raise StreamError(f"{config.where}: port {config.port} is already served on "
                              f"{self._host[config.port]}, not {config.host}")
        if entry is None:
            server = G.GstRtspServer.RTSPServer.new()
            # A client's DESCRIBE waits for the mount's first keyframe (the SDP carries its
            # SPS and PPS), which comes only once the run starts; with the server's default
            # one thread for all its clients, that wait would hold every other client of the
            # port (other mounts' included) until then.
            server.get_thread_pool().set_max_threads(CLIENT_THREADS)
            server.set_address(config.host)
            server.set_service(str(config.port))
            try:
                source = server.create_source(None)
            except G.GLib.Error as err:
                raise StreamError(f"{config.where}: cannot serve {config.url}: "
                                  f"{err.message}") from err
            source.attach(self._context)
            entry = self._servers[config.port] = (server, source)
            self._bound[config.port] = int(server.get_bound_port())
            self._host[config.port] = config.host
        stream = RtspStream(self, config)
        factory = G.GstRtspServer.RTSPMediaFactory.new()
        factory.set_launch(_LAUNCH)
        factory.set_shared(False)  # a pipeline per client: each starts at a keyframe
        factory.connect("media-configure", stream._configure)
        entry[0].get_mount_points().add_factory(config.mount_path, factory)
        self._streams[key] = stream
        return stream

    def wait_for_clients(self, timeout_s: float, *, poll_s: float = 0.02) -> list[str]:
        """Wait until every stream has a client (see :attr:`RtspStream.clients`), at most
        ``timeout_s`` wall-clock seconds; returns the URLs still without one."""
        deadline = time.monotonic() + timeout_s
        while True:
            waiting = [s.url for s in self._streams.values() if s.clients == 0]
            if not waiting or time.monotonic() >= deadline:
                return waiting
            time.sleep(poll_s)

    def pace(self, time_ns: int) -> None:
        """Sleep until ``time_ns`` of simulated time is due at ``rate`` (see the class)."""
        if self.rate is None:
            return
        now = time.monotonic()
        if self._t0 is None:
            self._t0 = now - time_ns / 1e9 / self.rate
        ahead = self._t0 + time_ns / 1e9 / self.rate - now
        if ahead > 0:
            time.sleep(ahead)

    def _in_loop(self, fn: Callable[[], None], timeout_s: float = 5.0) -> None:
        done = threading.Event()

        def run(*_args: Any) -> bool:
            try:
                fn()
            finally:
                done.set()
            return False

        source = self.gst.GLib.idle_source_new()
        source.set_callback(run)
        source.attach(self._context)
        done.wait(timeout_s)

    def close(self, drain_s: float = 2.0) -> None:
        """End every stream, disconnect the clients and stop the servers (idempotent).

        The servers send each stream at its own pace (RTP timestamps follow simulation time),
        so a run faster than real time leaves frames queued: clients get them, then the end
        of the stream, for at most the queued stream time plus ``drain_s`` seconds."""
        if self._closed:
            return
        self._closed = True
        medias = [m for s in self._streams.values() for m in s._end()]
        now = time.monotonic()
        deadline = now + drain_s + max((m.backlog_s(now) for m in medias), default=0.0)
        while medias and time.monotonic() < deadline and any(
                int(m.appsrc.get_property("current-level-bytes")) > 0 for m in medias):
            time.sleep(0.01)
        if medias:  # the last frames leave the payloader and the sockets
            now = time.monotonic()
            time.sleep(min(max(deadline - now, 0.0),
                           0.1 + max(m.backlog_s(now) for m in medias)))
        remove = self.gst.GstRtspServer.RTSPFilterResult.REMOVE

        def stop() -> None:
            for server, source in self._servers.values():
                server.client_filter(lambda _server, _client: remove)
                source.destroy()

        self._in_loop(stop)
        self._loop.quit()
        self._thread.join(5.0)
        self._servers.clear()

    def __enter__(self) -> RtspHub:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()
