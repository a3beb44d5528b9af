"""Serve a run live over the Foxglove WebSocket protocol (``srr run --foxglove``).

:class:`LiveView` is a bus tap: every published message goes, as the same CDR bytes and with
the same ``ros2msg`` schema text the recorder writes into the MCAP, to a channel of a
`foxglove-sdk <https://pypi.org/project/foxglove-sdk/>`_ WebSocket server, with the simulation
time as log time. The server broadcasts the simulation time (the protocol's ``time``
capability), so Foxglove's clock follows the run, not the wall clock. Transient-local topics
(``/tf_static``) are latched: the SDK has no latching, so their recent messages are logged
again whenever a client subscribes to them.

Nothing here changes what is recorded: the view only reads the bytes the recorder serialized,
and pacing (``rate``) only sleeps between ticks. The server listens on localhost unless told
otherwise, and only while a run that asked for it is going. Clients reach it through
:class:`~harness.live.wsfront.SubprotocolFront`, so those offering only the protocol's older
name, ``foxglove.websocket.v1`` (Lichtblick), connect as well as Foxglove's.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable, Mapping
from typing import Any

from harness.bus.bus import Envelope, Qos
from harness.live.config import DEFAULT_PORT, LiveConfig
from harness.live.errors import LiveViewError
from harness.live.wsfront import SubprotocolFront
from harness.recording.recorder import cdr_bytes, topic_meta

__all__ = ["DEFAULT_PORT", "LATCHED_KEEP", "LiveConfig", "LiveView", "Pacer"]

# After a client's first subscription, --foxglove-wait starts the run once no new subscription
# came for this long.
SETTLE_S = 0.5
# Messages kept per transient-local topic for late subscribers. The bus latches one message per
# topic, but several publishers share /tf_static (one per camera, one for world → odom) and a
# subscriber must get all of them, as each ROS publisher latches its own.
LATCHED_KEEP = 64
# How long closing waits for the server to end its connections before ending them itself.
STOP_GRACE_S = 2.0

Notice = Callable[[str], None]


class Pacer:
    """Sleeps so that simulated time runs at most ``rate`` × wall time from :meth:`start`.
    A tick that comes late (a slow first render, a heavy tick) moves the start on: the ticks
    after it are paced from it, not raced through to make the lost time up.

    It reads the wall clock only to decide how long to sleep between ticks; nothing it reads
    reaches the simulation or the recording."""

    def __init__(self, rate: float | None,
                 clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], None] = time.sleep) -> None:
        self.rate = rate
        self._clock = clock
        self._sleep = sleep
        self._t0: float | None = None

    def start(self) -> None:
        self._t0 = self._clock()

    def pace(self, sim_ns: int) -> float:
        """Sleep until ``sim_ns`` of simulated time is due; return the seconds slept."""
        if self.rate is None:
            return 0.0
        if self._t0 is None:
            self.start()
        assert self._t0 is not None
        ahead = self._t0 + sim_ns / 1e9 / self.rate - self._clock()
        if ahead > 0:
            self._sleep(ahead)
            return ahead
        self._t0 -= ahead  # late: this tick is the new start
        return 0.0


class LiveView:
    """A Foxglove WebSocket server fed from the bus. Start it with :meth:`start`; feed it
    ``(envelope, CDR bytes)`` with :meth:`log` (or use it as a plain bus tap, which serializes
    itself); call :meth:`tick` after each tick; :meth:`close` it (also a context manager).

    ``notice`` receives one-line messages for the user (where it listens, whether a client
    came); library code prints nothing itself."""

    def __init__(self, config: LiveConfig, server: Any, context: Any, foxglove: Any,
                 notice: Notice | None = None) -> None:
        self.config = config
        self._server = server
        self._context = context
        self._fg = foxglove
        self._notice = notice or (lambda _msg: None)
        self._channels: dict[str, Any] = {}
        self._qos_of: Callable[[str], Qos] = lambda _topic: Qos()
        # topic → its recent messages for late subscribers (None: not transient-local)
        self._latched: dict[str, deque[tuple[int, bytes]] | None] = {}
        self._lock = threading.Lock()  # channels and latched messages: the SDK calls back
        self._client = threading.Event()
        self._last_subscribe = 0.0  # monotonic time of the latest subscription
        self._now_ns = 0
        self._pacer = Pacer(config.rate)
        self._closed = False
        self._port = config.port
        self._front: SubprotocolFront | None = None

    # -- life cycle ---------------------------------------------------------------------------
    @classmethod
    def start(cls, config: LiveConfig, *, topics: Mapping[str, str] | None = None,
              notice: Notice | None = None, name: str = "srr") -> LiveView:
        """Create a channel for each of ``topics`` (topic → message type: what the run will
        publish), then start the server (:class:`~harness.live.errors.LiveViewError` when the SDK
        is missing or the address cannot be bound).

        Channels made before the server starts reach a client in the one ``advertise`` it gets
        on connecting. A channel made while a client is connected is advertised to it before
        the SDK (0.30) records it as advertised, so a client quick enough to subscribe in
        between is told "Unknown channel ID": hence as many channels as possible up front."""
        try:
            import foxglove
            from foxglove.websocket import Capability, ChannelView, Client, ServerListener
        except ImportError as err:
            raise LiveViewError("--foxglove needs the foxglove-sdk package: pip install "
                                "'srr[live]' (or foxglove-sdk)") from err
        context = foxglove.Context()
        view = cls(config, None, context, foxglove, notice)
        view.advertise(topics or {})

        class Listener(ServerListener):
            """The SDK's server callbacks; they run on the SDK's thread."""

            def on_subscribe(self, client: Client, channel: ChannelView) -> None:
                view._subscribed(channel.topic)

        # The SDK's server listens on a loopback port of its own, behind srr's front on the
        # address asked for, which also lets in clients of the protocol's older name
        # (foxglove.websocket.v1: Lichtblick, @foxglove/ws-protocol); see harness.live.wsfront.
        try:
            view._server = foxglove.start_server(
                name=name, host="127.0.0.1", port=0, capabilities=[Capability.Time],
                server_listener=Listener(), context=context)
            view._front = SubprotocolFront(config.host, config.port, int(view._server.port))
            view._port = view._front.port
        except (RuntimeError, OSError, OverflowError, ValueError) as err:
            if view._server is not None:
                view._server.stop()
            text = (err.strerror if isinstance(err, OSError) and err.strerror else
                    str(err).removeprefix("FoxgloveError: "))
            hint = ("; another srr run or a Foxglove bridge may be using it: pick another "
                    "--foxglove-port" if "in use" in text else "")
            raise LiveViewError(f"--foxglove: cannot listen on {config.host}:{config.port}: "
                                f"{text}{hint}") from err
        view._notice(f"live view on {view.url} (Foxglove: Open connection → Foxglove "
                     "WebSocket)")
        if config.host not in ("127.0.0.1", "localhost", "::1"):
            view._notice(f"warning: the live view listens on {config.host}, not only on this "
                         "machine; anyone who can reach it sees the run")
        return view

    @property
    def port(self) -> int:
        """The port the server listens on (the one the system chose for port 0)."""
        return self._port

    @property
    def url(self) -> str:
        host = f"[{self.config.host}]" if ":" in self.config.host else self.config.host
        return f"ws://{host}:{self.port}"

    def close(self) -> None:
        """Stop the server (clients see the connection close). Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        if self._front is not None:
            self._front.stop_accepting()
        if self._server is not None:
            # foxglove-sdk's stop() waits, about 45 s, for a client that stopped reading (a
            # frozen app, a sleeping laptop) to take what it was sent: past STOP_GRACE_S,
            # end the connections at the front, which lets the server's sends fail at once
            stopper = threading.Thread(target=self._server.stop, name="srr-live-stop",
                                       daemon=True)
            stopper.start()
            stopper.join(STOP_GRACE_S)
            if stopper.is_alive() and self._front is not None:
                self._front.cut()
            stopper.join()
        if self._front is not None:
            self._front.close()  # its connections end as the server closed them

    def __enter__(self) -> LiveView:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- channels -----------------------------------------------------------------------------
    def advertise(self, topics: Mapping[str, str],
                  qos_of: Callable[[str], Qos] | None = None) -> None:
        """Create a channel for each ``topic → message type``, so a client sees (and can
        subscribe to) them before their first message: the bus's topics and the wiring plan's
        published ones. A topic first seen in :meth:`log` gets its channel then. ``qos_of``
        gives a topic's QoS when its first message arrives (the bus's
        :meth:`~harness.bus.Bus.qos`): transient-local topics are latched."""
        if qos_of is not None:
            self._qos_of = qos_of
        for topic, msgtype in sorted(topics.items()):
            self._channel(topic, msgtype)

    def _channel(self, topic: str, msgtype: str) -> Any:
        channel = self._channels.get(topic)
        if channel is None:
            meta = topic_meta(topic, msgtype, Qos())
            schema = self._fg.Schema(name=msgtype, encoding=meta.schema_encoding,
                                     data=meta.schema)
            channel = self._fg.Channel(topic, schema=schema,
                                       message_encoding=meta.serialization_format,
                                       context=self._context)
            with self._lock:
                self._channels[topic] = channel
        return channel

    # -- traffic ------------------------------------------------------------------------------
    def __call__(self, env: Envelope) -> None:
        """As a plain bus tap (no recorder to share serialized bytes with)."""
        self.log(env, cdr_bytes(env))

    def log(self, env: Envelope, data: bytes) -> None:
        """Send one message's CDR bytes to the clients subscribed to its topic."""
        channel = self._channels.get(env.topic) or self._channel(env.topic, env.msgtype)
        try:
            latched = self._latched[env.topic]
        except KeyError:
            with self._lock:
                latched = self._latched[env.topic] = (
                    deque(maxlen=LATCHED_KEEP)
                    if self._qos_of(env.topic).durability == "transient_local" else None)
        if latched is not None:
            with self._lock:
                latched.append((env.stamp_ns, data))
        channel.log(data, log_time=env.stamp_ns)
        if env.stamp_ns > self._now_ns:
            self._now_ns = env.stamp_ns

    def _subscribed(self, topic: str) -> None:
        """A client subscribed to ``topic`` (SDK thread): send it what the topic latched. The
        SDK cannot address one client from Python, so clients already subscribed get the
        latched messages again; for static transforms that changes nothing."""
        with self._lock:
            channel = self._channels.get(topic)
            latched = list(self._latched.get(topic) or ())
        if channel is not None:
            for stamp_ns, data in latched:
                channel.log(data, log_time=stamp_ns)
        self._last_subscribe = time.monotonic()
        self._client.set()

    # -- time -----------------------------------------------------------------------------------
    def wait_for_client(self) -> bool:
        """With ``wait_s``, hold until a client subscribes to a topic (Foxglove does as soon as
        a panel shows one) or ``wait_s`` passes; True when one came. Starts the pacing clock."""
        came = self._client.is_set()
        if self.config.wait_s:  # (0: run at once, as without --foxglove-wait)
            came = True
            if not self._client.is_set():
                self._notice(f"waiting up to {self.config.wait_s:g} s for a Foxglove client "
                             f"on {self.url}")
                deadline = time.monotonic() + self.config.wait_s
                while not self._client.wait(timeout=max(0.0, min(0.1, deadline
                                                                  - time.monotonic()))):
                    if time.monotonic() >= deadline:
                        came = False
                        break
            # a client subscribes to its panels' topics one by one: start when that settled,
            # so none of them misses the first tick
            while came and time.monotonic() - self._last_subscribe < SETTLE_S:
                time.sleep(0.05)
            self._notice("a Foxglove client is connected; running" if came else
                         f"no Foxglove client subscribed to a topic within "
                         f"{self.config.wait_s:g} s; running anyway")
        self._pacer.start()
        return came

    def tick(self) -> None:
        """After each tick: broadcast the simulation time of the newest message, then sleep
        if the run is ahead of ``rate``."""
        self._server.broadcast_time(self._now_ns)
        self._pacer.pace(self._now_ns)

    @property
    def has_client(self) -> bool:
        """Whether a client has subscribed to a topic since the server started."""
        return self._client.is_set()
