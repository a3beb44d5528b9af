"""In-process publish/subscribe bus ordered by simulation time.

Publishing never calls subscribers directly: messages queue in publication order and
:meth:`Bus.spin` delivers them, so the tick loop decides when callbacks run and the order is
the same on every run. Taps (the recorder) see every message at publish time. Topics are
typed: advertising or subscribing with a different type than the topic already has is an
error, as in ROS 2. Transient-local topics keep their last ``depth`` messages for late
subscribers (``/tf_static``).
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

from harness.errors import SrrError

__all__ = ["Bus", "BusError", "Deferred", "Envelope", "Publisher", "Qos", "TopicInfo", "resolved"]


class BusError(SrrError):
    """A topic was used with two different message types."""


@dataclass(frozen=True)
class Qos:
    durability: Literal["volatile", "transient_local"] = "volatile"
    reliability: Literal["reliable", "best_effort"] = "reliable"
    depth: int = 10


TRANSIENT_LOCAL = Qos(durability="transient_local", depth=1)


_UNSET = object()


class Deferred:
    """A message computed when first needed: ``resolve()`` calls ``build()`` once (on
    whichever thread asks first; thread-safe) and returns its message from then on."""

    __slots__ = ("_build", "_lock", "_msg")

    def __init__(self, build: Callable[[], Any]) -> None:
        self._build: Callable[[], Any] | None = build
        self._lock = threading.Lock()
        self._msg: Any = _UNSET

    def resolve(self) -> Any:
        msg = self._msg
        if msg is _UNSET:
            with self._lock:
                if self._msg is _UNSET:
                    build, self._build = self._build, None
                    assert build is not None
                    self._msg = build()
                msg = self._msg
        return msg


def resolved(msg: Any) -> Any:
    """``msg``, computed if it is a :class:`Deferred`."""
    return msg.resolve() if type(msg) is Deferred else msg


class Envelope:
    """One published message: where, what, when (simulation ns) and its sequence number.

    ``raw`` holds the CDR bytes when the message was published already serialized: by a
    publisher that lays out its own bytes (:meth:`Bus.publish_serialized`), whose message
    object is then built on the first read of :attr:`msg` (a subscriber or a tap that looks
    at it), or a replayed recording, whose ``msg`` is the decoded message, or None when nobody
    subscribes. ``encoding`` says what ``raw`` is: ``cdr`` (ROS 2), or ``ros1`` for a replayed
    ROS 1 recording. The fields are read-only by convention.
    """

    __slots__ = ("_build", "_msg", "encoding", "msgtype", "raw", "seq", "stamp_ns", "topic")

    def __init__(self, topic: str, msgtype: str, stamp_ns: int, seq: int, msg: Any,
                 raw: bytes | None = None, build: Callable[[], Any] | None = None,
                 encoding: str = "cdr") -> None:
        self.topic = topic
        self.msgtype = msgtype
        self.stamp_ns = stamp_ns
        self.seq = seq
        self.raw = raw
        self.encoding = encoding
        self._msg = msg
        self._build = build

    def __repr__(self) -> str:
        return (f"Envelope(topic={self.topic!r}, msgtype={self.msgtype!r}, "
                f"stamp_ns={self.stamp_ns}, seq={self.seq})")

    @property
    def msg(self) -> Any:
        """The message object (built now, once, when it was published as bytes)."""
        if self._build is not None:
            self._msg = self._build()
            self._build = None
        return self._msg


@dataclass
class TopicInfo:
    msgtype: str
    qos: Qos
    published: int = 0
    latched: deque[Envelope] = field(default_factory=deque)


Callback = Callable[[Any], None]
Tap = Callable[[Envelope], None]


class Publisher:
    """A handle bound to one topic and type; ``publish(msg)`` stamps it with bus time."""

    __slots__ = ("_bus", "_info", "msgtype", "topic")

    def __init__(self, bus: Bus, topic: str, msgtype: str) -> None:
        self._bus = bus
        self.topic = topic
        self.msgtype = msgtype
        self._info = bus._declare(topic, msgtype, None)  # one per topic, kept by the bus

    def publish(self, msg: Any) -> None:
        self._bus.publish(self.topic, self.msgtype, msg)

    def publish_serialized(self, raw: bytes, build: Callable[[], Any]) -> None:
        """Publish a message given as its CDR bytes and a function making its object (see
        :meth:`Bus.publish_serialized`; the topic was declared when advertised)."""
        bus = self._bus
        bus._send(self._info, Envelope(self.topic, self.msgtype, bus._now_ns(), bus._seq, None,
                                       raw, build), True)


class Bus:
    """Typed topics, FIFO delivery on :meth:`spin`, taps for recording."""

    def __init__(self, now_ns: Callable[[], int]) -> None:
        self._now_ns = now_ns
        self._topics: dict[str, TopicInfo] = {}
        self._subs: dict[str, list[Callback | _EnvelopeCallback]] = {}
        self._queue: deque[Envelope | _Redelivery] = deque()
        self._taps: list[Tap] = []
        self._taps_defer = True  # every tap takes Deferred messages as they are
        self._seq = 0

    # -- topology -----------------------------------------------------------------------------
    def _declare(self, topic: str, msgtype: str, qos: Qos | None) -> TopicInfo:
        info = self._topics.get(topic)
        if info is None:
            info = TopicInfo(msgtype=msgtype, qos=qos or Qos())
            self._topics[topic] = info
        elif info.msgtype != msgtype:
            raise BusError(f"topic {topic} carries {info.msgtype}, not {msgtype}")
        elif qos is not None and qos != info.qos and info.published == 0:
            info.qos = qos
        return info

    def advertise(self, topic: str, msgtype: str, qos: Qos | None = None) -> Publisher:
        self._declare(topic, msgtype, qos)
        return Publisher(self, topic, msgtype)

    def subscribe(self, topic: str, msgtype: str, callback: Callback) -> None:
        self._subscribe(topic, msgtype, callback)

    def subscribe_envelopes(self, topic: str, msgtype: str,
                            callback: Callable[[Envelope], None]) -> None:
        """Like :meth:`subscribe`, but ``callback`` gets each message's :class:`Envelope`,
        in the same order among the topic's subscribers: a subscriber that keeps only the
        latest message reads ``resolved(env.msg)`` when it needs it, so a message published
        as bytes is built only if read (and only once, whoever reads it)."""
        self._subscribe(topic, msgtype, _EnvelopeCallback(callback))

    def _subscribe(self, topic: str, msgtype: str,
                   callback: Callback | _EnvelopeCallback) -> None:
        info = self._declare(topic, msgtype, None)
        self._subs.setdefault(topic, []).append(callback)
        if info.qos.durability == "transient_local":
            for env in info.latched:
                self._queue.append(_Redelivery(env, callback))

    def add_tap(self, tap: Tap) -> None:
        self._taps.append(tap)
        self._taps_defer = all(getattr(t, "takes_deferred", False) for t in self._taps)

    # -- traffic ------------------------------------------------------------------------------
    def publish(self, topic: str, msgtype: str, msg: Any) -> None:
        if not self._taps_defer and type(msg) is Deferred:
            msg = msg.resolve()
        self._send(self._declare(topic, msgtype, None),
                   Envelope(topic, msgtype, self._now_ns(), self._seq, msg), True)

    def publish_serialized(self, topic: str, msgtype: str, raw: bytes,
                           build: Callable[[], Any]) -> None:
        """Publish a message as its CDR bytes ``raw`` (what taps such as the recorder take)
        and ``build``, which makes the same message as an object: it runs when something
        reads the message (a subscriber, a tap reading ``msg``), at most once, so a topic
        nobody reads costs no object. Delivery is as for :meth:`publish`."""
        self._send(self._declare(topic, msgtype, None),
                   Envelope(topic, msgtype, self._now_ns(), self._seq, None, raw, build), True)

    def publish_raw(self, topic: str, msgtype: str, raw: bytes,
                    decode: Callable[[bytes, str], Any], qos: Qos | None = None,
                    encoding: str = "cdr") -> None:
        """Publish an already serialized message (a replayed recording; ``encoding``:
        ``cdr``, or ``ros1`` for a ROS 1 recording's bytes). Taps get the bytes as they are;
        ``decode(raw, msgtype)`` runs only when something will read the message (a
        subscriber, or a transient-local topic that may be read later)."""
        info = self._declare(topic, msgtype, qos)
        wanted = bool(self._subs.get(topic)) or info.qos.durability == "transient_local"
        msg = decode(raw, msgtype) if wanted else None
        self._send(info, Envelope(topic, msgtype, self._now_ns(), self._seq, msg, raw,
                                  encoding=encoding),
                   msg is not None or not raw)

    def _send(self, info: TopicInfo, env: Envelope, deliver: bool) -> None:
        self._seq += 1
        info.published += 1
        if info.qos.durability == "transient_local":
            info.latched.append(env)
            while len(info.latched) > max(info.qos.depth, 1):
                info.latched.popleft()
        for tap in self._taps:
            tap(env)
        if deliver:
            self._queue.append(env)

    def spin(self) -> int:
        """Deliver queued messages in publication order (including ones published meanwhile)."""
        delivered = 0
        while self._queue:
            env = self._queue.popleft()
            if isinstance(env, _Redelivery):
                if isinstance(env.callback, _EnvelopeCallback):
                    env.callback.callback(env.env)
                else:
                    env.callback(resolved(env.env.msg))
                delivered += 1
                continue
            subs = self._subs.get(env.topic)
            if subs:
                msg = _UNSET  # built on the first subscriber that takes the message
                for cb in subs:
                    if isinstance(cb, _EnvelopeCallback):
                        cb.callback(env)
                    else:
                        if msg is _UNSET:
                            msg = resolved(env.msg)
                        cb(msg)
                    delivered += 1
        return delivered

    # -- introspection ------------------------------------------------------------------------
    def topics(self) -> dict[str, TopicInfo]:
        return dict(self._topics)

    def qos(self, topic: str) -> Qos:
        info = self._topics.get(topic)
        return info.qos if info is not None else Qos()

    def published_counts(self) -> dict[str, int]:
        return {t: i.published for t, i in self._topics.items()}

    def subscribed(self) -> dict[str, str]:
        """Topic → message type of every topic something subscribes to."""
        return {t: self._topics[t].msgtype for t, cbs in self._subs.items() if cbs}


@dataclass(frozen=True)
class _Redelivery:
    env: Envelope
    callback: Callback | _EnvelopeCallback


class _EnvelopeCallback:
    """A subscriber that takes envelopes (see :meth:`Bus.subscribe_envelopes`)."""

    __slots__ = ("callback",)

    def __init__(self, callback: Callable[[Envelope], None]) -> None:
        self.callback = callback
