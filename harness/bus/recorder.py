"""Record every message on the bus to a rosbag2 directory (MCAP storage, CDR).

The recorder is a bus tap: it sees each message at publish time, serializes it with the
rosbags typestore and writes it with the simulation time as log time. It keeps, per topic, the
count, byte total and a SHA-256 digest over ``(log time, payload)`` so two runs can be compared
without reading the bags back.
"""

from __future__ import annotations

import hashlib
import struct
from dataclasses import dataclass
from collections.abc import Callable
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
    __slots__ = ("bytes", "conn", "count", "digest", "first_ns", "last_ns", "msgtype", "qos")

    def __init__(self, conn: Any, msgtype: str, qos: Qos) -> None:
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
    """

    def __init__(self, bag_dir: Path) -> None:
        self.bag_dir = Path(bag_dir)
        self._qos_of: Callable[[str], Qos] = lambda topic: Qos()
        self._writer: Writer | None = None
        self._state: dict[str, _TopicState] = {}

    def open(self, qos_of: Callable[[str], Qos] | None = None) -> None:
        """Open the bag; ``qos_of`` gives a topic's QoS when its first message arrives."""
        if qos_of is not None:
            self._qos_of = qos_of
        self._writer = Writer(self.bag_dir, version=9, storage_plugin=StoragePlugin.MCAP)
        self._writer.open()

    def __call__(self, env: Envelope) -> None:
        self.write(env)

    def write(self, env: Envelope) -> None:
        if self._writer is None:
            raise RuntimeError("recorder is not open")
        st = self._state.get(env.topic)
        if st is None:
            qos = self._qos_of(env.topic)
            conn = self._writer.add_connection(
                env.topic, env.msgtype, typestore=TYPESTORE,
                offered_qos_profiles=[_bag_qos(qos)])
            st = _TopicState(conn, env.msgtype, qos)
            self._state[env.topic] = st
        data = serialize(env.msg, env.msgtype)
        self._writer.write(st.conn, env.stamp_ns, data)
        st.count += 1
        st.bytes += len(data)
        st.digest.update(struct.pack("<qI", env.stamp_ns, len(data)))
        st.digest.update(data)
        if st.first_ns is None:
            st.first_ns = env.stamp_ns
        st.last_ns = env.stamp_ns

    def close(self) -> dict[str, TopicStats]:
        if self._writer is not None:
            self._writer.close()
            self._writer = None
        return self.stats()

    def stats(self) -> dict[str, TopicStats]:
        return {
            topic: TopicStats(topic, st.msgtype, st.count, st.bytes, st.digest.hexdigest(),
                              st.first_ns, st.last_ns, st.qos.durability)
            for topic, st in sorted(self._state.items())
        }
