"""Record every message on the bus to a rosbag2 directory (MCAP storage, CDR).

The recorder is a bus tap: it sees each message at publish time, serializes it with the
rosbags typestore and writes it with the simulation time as log time, through
:class:`~harness.recording.bagfile.McapBagWriter` (bounded chunks: a crash loses at most the chunk
being filled). It keeps, per topic, the count, byte total and a SHA-256 digest over
``(log time, payload)`` so two runs can be compared without reading the bags back. Topics
named ``unrecorded`` (raw camera images a camera records only compressed) are counted, not
written.

Threads: the caller's (the tick loop) serializes ordinary messages; a :class:`Deferred`
message (a camera image still rendering) is built and serialized by a small pool instead; one
writer thread writes to MCAP in publication order, taking messages in batches (a deferred
message's place in a batch holds its pending result); topics with large payloads are digested
by a few hash threads (each topic on one of them, in order), the rest on the writer thread.
Every step's output is the same bytes in the same order as doing it all on the caller's
thread; the threads only overlap the work (CDR, SHA-256, file writes and NumPy release the
GIL).
"""

from __future__ import annotations

import hashlib
import os
import queue
import struct
import threading
from collections.abc import Callable, Collection
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
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
from rosbags.rosbag2.metadata import dump_qos_v9

from harness.bus.bus import Deferred, Envelope, Qos, resolved
from harness.recording.bagfile import (
    ChunkPolicy,
    McapBagWriter,
    TopicMeta,
    bag_metadata,
    dump_metadata,
    write_metadata,
)
from harness.recording.errors import BagError
from harness.recording.mcap_writer import Payload, payload_size
from harness.serde.messages import TYPESTORE, serialize, serialize_pieces

__all__ = ["HASH_LANE_MIN_BYTES", "Recorder", "TopicState", "TopicStats", "cdr_bytes",
           "digest_update", "topic_meta"]

#: A topic whose first payload is at least this large is digested on a hash thread.
HASH_LANE_MIN_BYTES = 64 * 1024
# Threads that build and serialize deferred messages, and hash threads, at most. Two of each
# keep up with four 640x480 cameras at 130 sets/s; more only add contention for the GIL (on
# the H100's 16-core host, 4 of each gave 100-105 sets/s against 111-126 with 2).
_POOL_THREADS = 2
_HASH_LANES = max(1, min(2, os.cpu_count() or 1))
# A digested message's head: log time, payload length.
_DIGEST_HEAD = struct.Struct("<qI")
# Payloads smaller than this are digested joined to their head (copying them is cheaper than
# a second ``update`` call).
_JOIN_BELOW = 4096


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


def digest_update(h: Any, stamp_ns: int, data: Payload) -> None:
    """Feed one message into a topic's digest: ``(log time, length, payload)`` (a payload in
    pieces digests as the pieces joined). A small payload goes in one ``update`` with its
    head (the digest of the bytes fed is the same however they are split)."""
    if isinstance(data, tuple):
        h.update(_DIGEST_HEAD.pack(stamp_ns, payload_size(data)))
        for piece in data:
            h.update(piece)
        return
    size = len(data)
    if size < _JOIN_BELOW:
        h.update(_DIGEST_HEAD.pack(stamp_ns, size) + data)
        return
    h.update(_DIGEST_HEAD.pack(stamp_ns, size))
    h.update(data)


class TopicState:
    """What the recorder keeps of one topic while it writes (its channel, counts, running
    digest); a subclass's :meth:`Recorder._first_of` sees it, as the ROS 1 writer's does."""

    __slots__ = ("bytes", "channel", "count", "digest", "first_ns", "lane", "last_ns", "msgtype",
                 "qos", "topic")

    def __init__(self, topic: str, msgtype: str, qos: Qos) -> None:
        self.topic = topic
        self.channel: int | None = None
        self.msgtype = msgtype
        self.qos = qos
        self.count = 0
        self.bytes = 0
        self.digest = hashlib.sha256()
        self.first_ns: int | None = None
        self.last_ns: int | None = None
        self.lane: _HashLane | None = None  # None: digested on the writer thread


class _HashLane:
    """A thread that digests the payloads of the topics given to it, in the order queued."""

    def __init__(self, name: str) -> None:
        self._queue: queue.Queue[tuple[Any, int, Payload] | None] = queue.Queue(
            maxsize=256)
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def put(self, digest: Any, stamp_ns: int, data: Payload) -> None:
        self._queue.put((digest, stamp_ns, data))

    def _run(self) -> None:
        while (item := self._queue.get()) is not None:
            digest_update(*item)

    def close(self) -> None:
        self._queue.put(None)
        self._thread.join()


def cdr_bytes(env: Envelope) -> bytes:
    """A message's CDR bytes: ``env.raw`` when it is CDR (packed by its publisher, or a
    replayed ROS 2 recording), else the message serialized (a deferred one computed first)."""
    if env.raw is not None and env.encoding == "cdr":
        return env.raw
    return serialize(resolved(env.msg), env.msgtype)


def _serialize_deferred(msg: Deferred, msgtype: str) -> Payload:
    """CDR of a deferred message (an image) in pieces: the pixels stay the message's own
    array, never copied (megabytes a frame; a copy would hold the GIL). The writer and the
    digest take the pieces as they are."""
    return serialize_pieces(msg.resolve(), msgtype)


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


def topic_meta(topic: str, msgtype: str, qos: Qos) -> TopicMeta:
    """A topic's rosbag2 description from the typestore (message definition, RIHS01 hash) and
    its offered QoS (one profile, as ``ros2 bag record`` stores it)."""
    schema, type_hash = type_description(msgtype)
    return TopicMeta(topic, msgtype, schema, qos_profiles(qos), type_hash)


def type_description(msgtype: str) -> tuple[bytes, str]:
    """``msgtype``'s message definition (``ros2msg`` text) and RIHS01 hash."""
    msgdef, _ = TYPESTORE.generate_msgdef(msgtype, ros_version=2)
    return msgdef.encode(), TYPESTORE.hash_rihs01(msgtype)


def qos_profiles(qos: Qos) -> str:
    """``offered_qos_profiles`` of a topic offered with ``qos``, as rosbag2 stores it."""
    return str(yaml.safe_dump(dump_qos_v9([_bag_qos(qos)]), default_flow_style=False,
                              sort_keys=True)).strip()


class Recorder:
    """Writes a rosbag2 (version 9, MCAP) directory at ``bag_dir``.

    Call :meth:`open` with the bus's QoS look-up (so transient-local topics are marked so in
    ``metadata.yaml``), feed it envelopes, then :meth:`close`. ``chunks`` bounds what a crash
    can lose (see :class:`~harness.recording.bagfile.ChunkPolicy`).

    Messages are serialized on the caller's thread (the message objects are not shared
    further), :class:`~harness.bus.bus.Deferred` ones on a pool (ROS 2 only: another format
    builds them on the caller's thread); writing to MCAP and hashing run on background
    threads, in publication order, so they overlap with rendering and physics (see the module
    doc). Messages are handed to the writer thread in batches of up to ``batch`` messages
    (fewer when they reach ``batch_bytes``, or ``deferred_batch`` messages once a deferred
    one is among them: a deferred message counts no bytes, its size not yet known, so this
    bounds the images in flight), so small messages cost the two threads one hand-off per
    batch rather than one each. The queue holds at most ``queue_size // batch`` batches (at
    least one) and ``put`` blocks: the recorder slows the loop down rather than dropping
    anything. An error on a background thread is raised again by the next
    :meth:`write` or by :meth:`close`.
    """

    #: The bus hands :class:`~harness.bus.bus.Deferred` messages over as they are.
    takes_deferred = True
    #: Deferred messages are built and serialized on the pool (the typestore's CDR of the bus
    #: type); False in a format that converts messages (ROS 1), which builds them inline.
    _defer_ok = True
    #: A message that comes with bytes in this encoding (``Envelope.encoding``) is recorded as
    #: those bytes; any other is serialized (:meth:`_serialize`).
    _recorded_encoding = "cdr"

    def __init__(self, bag_dir: Path, *, queue_size: int = 256,
                 chunks: ChunkPolicy | None = None,
                 unrecorded: Collection[str] = (), batch: int = 64,
                 batch_bytes: int = 1 << 20, deferred_batch: int = 16) -> None:
        self.bag_dir = Path(bag_dir)
        # Topics published but not written (a camera's raw images when it records them
        # compressed): counted, and still handed to the serialized taps.
        self.unrecorded = frozenset(unrecorded)
        self._skipped: dict[str, tuple[str, int]] = {}
        self.chunks = chunks or ChunkPolicy()
        self._inline_bytes = 0  # serialized on the caller's thread
        self._deferred_bytes = 0  # serialized on the pool (counted by the writer thread)
        self._qos_of: Callable[[str], Qos] = lambda topic: Qos()
        self._writer: Any = None
        self._state: dict[str, TopicState] = {}
        self._batch_limit = max(1, batch)
        self._deferred_limit = max(1, min(batch, deferred_batch))
        self._batch_bytes_limit = batch_bytes
        self._batch: list[tuple[TopicState, int, bytes | Future[Payload]]] = []
        self._batch_bytes = 0
        self._queue: queue.Queue[
            list[tuple[TopicState, int, bytes | Future[Payload]]] | None] = \
            queue.Queue(maxsize=max(1, queue_size // self._batch_limit))
        self._thread: threading.Thread | None = None
        self._pool: ThreadPoolExecutor | None = None
        self._lanes: list[_HashLane] = []
        self._next_lane = 0
        self._error: BagError | None = None
        self._forward: list[Callable[[Envelope, bytes], None]] = []
        # topic_meta's parts by message type and by QoS (see _add_topic; writer thread)
        self._described: dict[str, tuple[bytes, str]] = {}
        self._profiles: dict[Qos, str] = {}

    @property
    def bytes_serialized(self) -> int:
        """Serialized bytes handed to the writer so far (read on the caller's thread, e.g. by
        a disk-space guard; deferred messages count once the writer has them)."""
        return self._inline_bytes + self._deferred_bytes

    def add_serialized_tap(self, tap: Callable[[Envelope, bytes], None]) -> None:
        """Also hand each envelope with its serialized bytes to ``tap`` (on the caller's
        thread, before the bytes are queued for writing), so a second consumer (the live view)
        does not serialize the message again. Deferred messages are then built on the
        caller's thread too."""
        self._forward.append(tap)

    @property
    def mcap_path(self) -> Path:
        return self.bag_dir / f"{self.bag_dir.name}.mcap"

    def open(self, qos_of: Callable[[str], Qos] | None = None) -> None:
        """Open the bag; ``qos_of`` gives a topic's QoS when its first message arrives."""
        if qos_of is not None:
            self._qos_of = qos_of
        try:
            self.bag_dir.mkdir(parents=True)
            self._writer = self._open_writer()
        except OSError as err:
            raise BagError(f"{self.bag_dir}: cannot record: {err.strerror or err}") from err
        self._thread = threading.Thread(target=self._drain, name="srr-recorder", daemon=True)
        self._thread.start()

    def write(self, env: Envelope) -> None:
        """Record one message (the bus calls the recorder with each, as a tap).

        The usual message comes with bytes in the recorded encoding (packed by its
        publisher): its topic's state is looked up and the bytes appended to the batch being
        filled, nothing else. Everything else (a new topic, an unrecorded one, a message to
        serialize or to build on the pool) takes the longer path."""
        if self._writer is None:
            raise RuntimeError("recorder is not open")
        if self._error is not None:
            raise self._error
        st = self._state.get(env.topic)
        if st is None:
            st = self._first_of(env)
            if st is None:
                return
        raw = env.raw
        if raw is not None and env.encoding == self._recorded_encoding:
            data = raw
        else:
            # env.msg only when no bytes came with it: reading it builds a packed message
            msg = env.msg if raw is None else None
            if type(msg) is Deferred and self._defer_ok and not self._forward:
                self._defer(st, env, msg)
                return
            data = self._serialize(env)
        self._inline_bytes += len(data)
        for tap in self._forward:
            tap(env, data)
        batch = self._batch
        batch.append((st, env.stamp_ns, data))
        self._batch_bytes += len(data)
        if len(batch) >= self._batch_limit or self._batch_bytes >= self._batch_bytes_limit:
            self._hand_over()

    #: The recorder is the bus's tap: calling it is :meth:`write` itself (no second call per
    #: message). A subclass that overrides ``write`` sets ``__call__ = write`` again.
    __call__ = write

    def _first_of(self, env: Envelope) -> TopicState | None:
        """The state of ``env``'s topic, made on its first message; None for a topic that is
        not recorded (the message is counted, and handed to the serialized taps)."""
        if env.topic in self.unrecorded:
            _, n = self._skipped.get(env.topic, (env.msgtype, 0))
            self._skipped[env.topic] = (env.msgtype, n + 1)
            if self._forward:
                data = cdr_bytes(env)
                for tap in self._forward:
                    tap(env, data)
            return None
        st = self._state[env.topic] = TopicState(env.topic, self._recorded_type(env.msgtype),
                                                  self._qos_of(env.topic))
        return st

    def _defer(self, st: TopicState, env: Envelope, msg: Deferred) -> None:
        """Queue a deferred message, built and serialized on the pool (see the class doc)."""
        if self._pool is None:
            self._pool = ThreadPoolExecutor(_POOL_THREADS, thread_name_prefix="srr-cdr")
        self._batch.append((st, env.stamp_ns,
                            self._pool.submit(_serialize_deferred, msg, env.msgtype)))
        if len(self._batch) >= self._deferred_limit:
            self._hand_over()

    def _hand_over(self) -> None:
        """Queue the batch being filled for the writer thread (blocks while the queue is
        full)."""
        if self._batch:
            self._queue.put(self._batch)
            self._batch, self._batch_bytes = [], 0

    def _fail(self, what: str, err: Exception) -> None:
        reason = err.strerror if isinstance(err, OSError) and err.strerror else err
        self._error = BagError(f"{self.bag_dir}: cannot record {what}: {reason}")
        self._error.__cause__ = err

    def _lane(self, size: int) -> _HashLane | None:
        """The hash thread for a new topic whose first payload has ``size`` bytes (None: the
        writer thread digests it)."""
        if size < HASH_LANE_MIN_BYTES:
            return None
        if len(self._lanes) < _HASH_LANES:
            self._lanes.append(_HashLane(f"srr-digest-{len(self._lanes)}"))
        lane = self._lanes[self._next_lane % len(self._lanes)]
        self._next_lane += 1
        return lane

    def _drain(self) -> None:
        writer = self._writer
        assert writer is not None
        write = writer.write
        while (batch := self._queue.get()) is not None:
            for st, stamp, payload in batch:
                if self._error is not None:
                    break  # keep draining so producers never block on a dead writer
                try:
                    data: Payload
                    if isinstance(payload, Future):
                        data = payload.result()
                        size = payload_size(data)
                        self._deferred_bytes += size
                    else:
                        data = payload
                        size = len(data)
                    if st.channel is None:
                        st.channel = self._add_topic(writer, st.topic, st.msgtype, st.qos)
                        st.lane = self._lane(size)
                    write(st.channel, stamp, data)
                except Exception as err:  # handed to the caller's thread as one clear error
                    self._fail(st.topic, err)
                    break
                st.count += 1
                st.bytes += size
                if st.lane is None:
                    digest_update(st.digest, stamp, data)
                else:
                    st.lane.put(st.digest, stamp, data)
                if st.first_ns is None:
                    st.first_ns = stamp
                st.last_ns = stamp

    def close(self) -> dict[str, TopicStats]:
        """Flush the queue, close the bag (summary, footer, ``metadata.yaml``), return
        per-topic statistics."""
        if self._thread is not None:
            self._hand_over()
            self._queue.put(None)
            self._thread.join()
            self._thread = None
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None
        for lane in self._lanes:
            lane.close()
        self._lanes.clear()
        writer, self._writer = self._writer, None
        if writer is not None:
            if self._error is not None:
                writer.abort()
            else:
                try:
                    self._finish(writer)
                except Exception as err:
                    writer.abort()
                    self._fail("the bag's index", err)
        if self._error is not None:
            raise self._error
        return self.stats()

    def skipped(self) -> dict[str, tuple[str, int]]:
        """Topic → (type, messages) of what was published on :attr:`unrecorded` topics."""
        return dict(sorted(self._skipped.items()))

    # -- the format: a rosbag2 directory with one MCAP file of CDR messages (ROS 2). A
    # subclass records another (harness.recording.ros1bag: ROS 1) by overriding these.
    def _open_writer(self) -> Any:
        """The file writer, opened (called once, on the caller's thread)."""
        return McapBagWriter(self.mcap_path, self.chunks)

    def _recorded_type(self, msgtype: str) -> str:
        """The type name a bus type is recorded (and reported) as."""
        return msgtype

    def _serialize(self, env: Envelope) -> bytes:
        """The bytes recorded for one message (on the caller's thread, in publication order):
        its CDR bytes (:func:`cdr_bytes`)."""
        return cdr_bytes(env)

    def _add_topic(self, writer: Any, topic: str, msgtype: str, qos: Qos) -> int:
        """Register a topic with the writer (on the writer thread); returns its channel.
        :func:`topic_meta`'s parts are made once per message type and once per QoS of the
        recording (a QoS profile's YAML takes about a third of a millisecond, a type's
        definition and hash a sixth: a run's six topics of three types, five of them with
        one QoS, took 3 ms of the writer thread's time in the first ticks)."""
        described = self._described.get(msgtype)
        if described is None:
            described = self._described[msgtype] = type_description(msgtype)
        profiles = self._profiles.get(qos)
        if profiles is None:
            profiles = self._profiles[qos] = qos_profiles(qos)
        schema, type_hash = described
        return int(writer.add_topic(TopicMeta(topic, msgtype, schema, profiles, type_hash)))

    def _finish(self, writer: Any) -> None:
        """Close the file (summary, index) and write what goes beside it."""
        info = bag_metadata(writer.path.name, list(zip(writer.topics, writer.counts,
                                                       strict=True)),
                            writer.start_ns, writer.end_ns)
        writer.finish(dump_metadata(info))
        write_metadata(self.bag_dir, info)

    def stats(self) -> dict[str, TopicStats]:
        return {
            topic: TopicStats(topic, st.msgtype, st.count, st.bytes, st.digest.hexdigest(),
                              st.first_ns, st.last_ns, st.qos.durability)
            for topic, st in sorted(self._state.items())
        }
