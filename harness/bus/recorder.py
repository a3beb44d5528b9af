"""Record every message on the bus to a rosbag2 directory (MCAP storage, CDR).

The recorder is a bus tap: it sees each message at publish time, serializes it with the
rosbags typestore and writes it with the simulation time as log time. It keeps, per topic, the
count, byte total and a SHA-256 digest over ``(log time, payload)`` so two runs can be compared
without reading the bags back.
"""

from __future__ import annotations

import hashlib
import queue
import struct
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rosbags.interfaces import (
    Qos as BagQos,
)
from rosbags.interfaces import (
    QosDurability,
    QosHistory,
    QosLiveliness,
    QosReliability,
    QosTime,
)
from rosbags.rosbag2 import StoragePlugin, Writer

from harness.bus.bus import Envelope, Qos
from harness.bus.messages import TYPESTORE, serialize
from harness.errors import BagError

__all__ = ["Recorder", "TopicStats"]


@dataclass(frozen=True)
class TopicStats:
    """What the recorder wrote for one topic."""

    topic: str
    msgtype: str
    count: int
    bytes: int
    sha256: str
    first_ns: int | None
    last_ns: int | None
    durability: str


class _TopicState:
    __slots__ = ("bytes", "conn", "count", "digest", "first_ns", "last_ns", "msgtype", "qos",
                 "topic")

    def __init__(self, conn: Any, msgtype: str, qos: Qos) -> None:
        self.topic = ""
        self.conn = conn
        self.msgtype = msgtype
        self.qos = qos
        self.count = 0
        self.bytes = 0
        self.digest = hashlib.sha256()
        self.first_ns: int | None = None
        self.last_ns: int | None = None


def _bag_qos(qos: Qos) -> BagQos:
    inf = QosTime(sec=2147483647, nsec=4294967295)
    return BagQos(
        history=QosHistory.KEEP_LAST,
        depth=qos.depth,
        reliability=(QosReliability.RELIABLE if qos.reliability == "reliable"
                     else QosReliability.BEST_EFFORT),
        durability=(QosDurability.TRANSIENT_LOCAL if qos.durability == "transient_local"
                    else QosDurability.VOLATILE),
        deadline=inf,
        lifespan=inf,
        liveliness=QosLiveliness.AUTOMATIC,
        liveliness_lease_duration=inf,
        avoid_ros_namespace_conventions=False,
    )


class Recorder:
    """Writes a rosbag2 (version 9, MCAP) directory at ``bag_dir``.

    Call :meth:`open` with the bus's QoS look-up (so transient-local topics are marked so in
    ``metadata.yaml``), feed it envelopes, then :meth:`close`.

    Messages are serialized on the caller's thread (the message objects are not shared
    further); writing to MCAP and hashing run on one background thread, in publication order,
    so they overlap with rendering and physics (both release the GIL). The queue is bounded
    and ``put`` blocks: the recorder slows the loop down rather than dropping anything. An
    error on the writer thread is raised again by the next :meth:`write` or by :meth:`close`.
    """

    def __init__(self, bag_dir: Path, *, queue_size: int = 64) -> None:
        self.bag_dir = Path(bag_dir)
        self._qos_of: Callable[[str], Qos] = lambda topic: Qos()
        self._writer: Writer | None = None
        self._state: dict[str, _TopicState] = {}
        self._queue: queue.Queue[tuple[_TopicState, int, bytes] | None] = queue.Queue(
            maxsize=queue_size)
        self._thread: threading.Thread | None = None
        self._error: BagError | None = None

    def open(self, qos_of: Callable[[str], Qos] | None = None) -> None:
        """Open the bag; ``qos_of`` gives a topic's QoS when its first message arrives."""
        if qos_of is not None:
            self._qos_of = qos_of
        self._writer = Writer(self.bag_dir, version=9, storage_plugin=StoragePlugin.MCAP)
        self._writer.open()
        self._thread = threading.Thread(target=self._drain, name="srr-recorder", daemon=True)
        self._thread.start()

    def __call__(self, env: Envelope) -> None:
        self.write(env)

    def write(self, env: Envelope) -> None:
        if self._writer is None:
            raise RuntimeError("recorder is not open")
        if self._error is not None:
            raise self._error
        st = self._state.get(env.topic)
        if st is None:
            st = _TopicState(None, env.msgtype, self._qos_of(env.topic))
            st.topic = env.topic
            self._state[env.topic] = st
        data = env.raw if env.raw is not None else serialize(env.msg, env.msgtype)
        self._queue.put((st, env.stamp_ns, data))

    def _drain(self) -> None:
        writer = self._writer
        assert writer is not None
        while (item := self._queue.get()) is not None:
            if self._error is not None:
                continue  # keep draining so producers never block on a dead writer
            st, stamp, data = item
            try:
                if st.conn is None:
                    st.conn = writer.add_connection(
                        st.topic, st.msgtype, typestore=TYPESTORE,
                        offered_qos_profiles=[_bag_qos(st.qos)])
                writer.write(st.conn, stamp, data)
            except Exception as err:  # handed to the caller's thread as one clear error
                reason = err.strerror if isinstance(err, OSError) and err.strerror else err
                self._error = BagError(f"{self.bag_dir}: cannot record {st.topic}: {reason}")
                self._error.__cause__ = err
                continue
            st.count += 1
            st.bytes += len(data)
            st.digest.update(struct.pack("<qI", stamp, len(data)))
            st.digest.update(data)
            if st.first_ns is None:
                st.first_ns = stamp
            st.last_ns = stamp

    def close(self) -> dict[str, TopicStats]:
        """Flush the queue, close the bag, return per-topic statistics."""
        if self._thread is not None:
            self._queue.put(None)
            self._thread.join()
            self._thread = None
        if self._writer is not None:
            self._writer.close()
            self._writer = None
        if self._error is not None:
            raise self._error
        return self.stats()

    def stats(self) -> dict[str, TopicStats]:
        return {
            topic: TopicStats(topic, st.msgtype, st.count, st.bytes, st.digest.hexdigest(),
                              st.first_ns, st.last_ns, st.qos.durability)
            for topic, st in sorted(self._state.items())
        }
