"""Compare the bags of two runs topic by topic, reading each bag once.

Both bags are read in one merged pass ordered by log time. Each topic's messages are paired
by index (the ``i``-th message of a topic in A with the ``i``-th in B); a pair whose log time
and payload bytes are equal costs a byte comparison. Other pairs are decoded with the
``rosbags`` typestore and walked field by field (:mod:`harness.diff.fields`) to find the first
differing field and to accumulate per-field ``|B − A|`` (max, RMS) against the tolerances.

Only the messages of a topic that one run has reached and the other not yet are held in
memory (runs of one scenario stay within a tick of each other); nothing else is kept, so
camera images are never all loaded at once. Each topic's SHA-256 over (log time, payload)
is recomputed as the recorder computes it.

ROS 1 recordings (:mod:`harness.recording.bagread`) are compared the same way; their topics carry
their ROS 1 type names (``sensor_msgs/Image``), so a ROS 1 run and a ROS 2 run differ in type
on every topic, and a differing ROS 1 payload is decoded into the ROS 2 message to walk it.
"""

from __future__ import annotations

import hashlib
import math
import struct
from collections import deque
from collections.abc import Collection, Generator, Sequence
from contextlib import closing
from pathlib import Path
from typing import Any

import numpy as np

from harness.diff.fields import as_float, walk
from harness.diff.result import Divergence, FieldDiff, TopicDiff, TopicStatus, Worst
from harness.diff.tolerance import Tolerance, glob_match, tolerance_for
from harness.errors import reason
from harness.recording.bagread import DECODE_ERRORS, deserialize, open_indexed, open_recording
from harness.recording.errors import BagError

__all__ = ["diff_bags", "message_stream"]


def _decode(raw: bytes, msgtype: str) -> Any:
    """The ROS 2 message of a payload of ``msgtype`` as recorded: ``pkg/msg/Name`` is CDR,
    ``pkg/Name`` (a ROS 1 recording) ROS 1."""
    return deserialize(raw, msgtype, "cdr" if "/msg/" in msgtype else "ros1")


def _num(v: float) -> str:
    """A value as a divergence shows it: a boolean as ``false``/``true``, a number to 6
    significant digits."""
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    return f"{v:.6g}"


class _Field:
    __slots__ = ("at_index", "at_ns", "beyond", "differ", "max_abs", "path", "sum_sq", "tol",
                 "values")

    def __init__(self, path: str, tol: Tolerance | None) -> None:
        self.path = path
        self.tol = tol
        self.values = 0
        self.differ = 0
        self.beyond = 0
        self.sum_sq = 0.0
        self.max_abs = 0.0
        self.at_index = -1
        self.at_ns = 0

    def freeze(self) -> FieldDiff:
        rms = math.sqrt(self.sum_sq / self.values) if self.values else 0.0
        return FieldDiff(self.path, self.values, self.differ, self.beyond, self.max_abs, rms,
                         self.at_index, self.at_ns, self.tol)


# one side's message not yet paired: (index, log time, payload or None when not kept)
_Pending = tuple[int, int, bytes | None]


class _Topic:
    """Per-topic state; also the :class:`~harness.diff.fields.Visitor` of its messages."""

    def __init__(self, name: str, tolerances: Sequence[Tolerance]) -> None:
        self.name = name
        self.tolerances = tuple(t for t in tolerances if glob_match(name, t.topic))
        self.types: list[str | None] = [None, None]
        self.counts = [0, 0]
        self.sha = [hashlib.sha256(), hashlib.sha256()]
        self.pending: tuple[deque[_Pending], deque[_Pending]] = (deque(), deque())
        self.fields: dict[str, _Field] = {}
        self.mism: dict[str, int] = {}
        self.first: Divergence | None = None
        self.first_beyond: Divergence | None = None
        self.msgs_differ = 0
        self.time_shifts = 0
        self.worst: Worst | None = None
        # the pair being walked
        self._i = 0
        self._ns = (0, 0)
        self._noted = False
        self._values = 0

    # ------------------------------------------------------------------ visitor

    def _field(self, path: str) -> _Field:
        f = self.fields.get(path)
        if f is None:
            f = self.fields[path] = _Field(path, tolerance_for(self.name, path,
                                                                self.tolerances))
        return f

    def _note(self, path: str, detail: str, beyond: bool) -> None:
        self._noted = True
        if self.first is None or (beyond and self.first_beyond is None):
            d = Divergence(self.name, self._i, self._ns[0], self._ns[1], path, detail)
            if self.first is None:
                self.first = d
            if beyond and self.first_beyond is None:
                self.first_beyond = d

    def _hit(self, f: _Field, d: float) -> None:
        if d > f.max_abs or f.at_index < 0:
            f.max_abs, f.at_index, f.at_ns = d, self._i, self._ns[0]

    def scalar(self, path: str, a: float, b: float) -> None:
        f = self._field(path)
        f.values += 1
        if a == b or (math.isnan(a) and math.isnan(b)):
            return
        d = abs(b - a)
        if math.isnan(d):
            d = math.inf
        f.differ += 1
        f.sum_sq += d * d
        self._hit(f, d)
        tol = f.tol
        ok = tol is not None and d <= max(tol.abs, tol.rel * abs(a) if math.isfinite(a)
                                          else 0.0) + 1e-12
        if not ok:
            f.beyond += 1
        self._values += 1
        self._note(path, f"{_num(a)} vs {_num(b)}", not ok)

    def array(self, path: str, a: np.ndarray, b: np.ndarray) -> None:
        f = self._field(path + "[*]")
        a, b = a.reshape(-1), b.reshape(-1)
        n = int(a.size)
        f.values += n
        # only the elements that differ are looked at (an image pair differs in a few %)
        if a.dtype.kind in "biu" and b.dtype.kind in "biu":  # pixels, counts: exact
            size = max(a.dtype.itemsize, b.dtype.itemsize)
            wide = np.int16 if size == 1 else np.int32 if size == 2 else np.int64
            di = np.subtract(b, a, dtype=wide)
            nz = np.flatnonzero(di)
            if nz.size == 0:
                return
            dv = np.abs(di[nz].astype(np.float64))
        else:
            a64, b64 = as_float(a), as_float(b)
            nz = np.flatnonzero(a64 != b64)
            nz = nz[~(np.isnan(a64[nz]) & np.isnan(b64[nz]))]
            if nz.size == 0:
                return
            with np.errstate(invalid="ignore", over="ignore"):
                dv = np.abs(b64[nz] - a64[nz])
            dv[np.isnan(dv)] = math.inf
        nd = int(nz.size)
        with np.errstate(over="ignore"):
            f.sum_sq += float(np.dot(dv, dv))
        f.differ += nd
        k = int(np.argmax(dv))
        self._hit(f, float(dv[k]))
        tol = f.tol
        if tol is None:
            beyond = np.ones(nd, dtype=bool)
        else:
            allowed = np.full(nd, tol.abs)
            if tol.rel:
                av = as_float(a[nz])
                fin = np.isfinite(av)
                allowed[fin] = np.maximum(tol.abs, tol.rel * np.abs(av[fin]))
            beyond = ~(dv <= allowed + 1e-12)
        nb = int(np.count_nonzero(beyond))
        f.beyond += nb
        self._values += nd
        summary = f"{nd} of {n} values differ, max |Δ| {_num(float(dv[k]))}"

        def pair(i: int) -> str:  # a bool[] field's items as false/true
            x, y = (bool(a[i]), bool(b[i])) if a.dtype.kind == "b" == b.dtype.kind \
                else (float(a[i]), float(b[i]))
            return f"{_num(x)} vs {_num(y)} ({summary})"

        first = int(nz[0])
        self._note(f"{path}[{first}]", pair(first), False)
        if nb:
            j = int(nz[int(np.argmax(beyond))])
            self._note(f"{path}[{j}]", pair(j), True)

    def mismatch(self, path: str, detail: str) -> None:
        self.mism[path] = self.mism.get(path, 0) + 1
        self._values += 1
        self._note(path, detail, True)

    # ------------------------------------------------------------------ pairs

    def compare(self, i: int, a: tuple[int, bytes], b: tuple[int, bytes], bags: tuple[Path, Path]
                ) -> None:
        (ns_a, raw_a), (ns_b, raw_b) = a, b
        if ns_a == ns_b and raw_a == raw_b:
            return
        self.msgs_differ += 1
        self._i, self._ns, self._noted, self._values = i, (ns_a, ns_b), False, 0
        if ns_a != ns_b:
            self.time_shifts += 1
            self._values += 1
            self._note("(log time)", f"{ns_a / 1e9:.6f} s vs {ns_b / 1e9:.6f} s", True)
        if raw_a != raw_b:
            msgtype = self.types[0] or ""
            msgs = []
            for bag, raw in zip(bags, (raw_a, raw_b), strict=True):
                try:
                    msgs.append(_decode(raw, msgtype))
                except DECODE_ERRORS as err:
                    raise BagError(f"{bag}: {self.name} message #{i} ({msgtype}) does not "
                                   f"decode: {reason(err)}") from err
            noted = self._noted
            self._noted = False
            walk(msgs[0], msgs[1], self)
            if not self._noted:
                self._values += 1
                self._note("(payload bytes)", f"{len(raw_a)} vs {len(raw_b)} bytes, every "
                           "field equal", True)
            self._noted = self._noted or noted
        if self.worst is None or self._values > self.worst.values:
            self.worst = Worst(i, ns_a, self._values)

    def push(self, side: int, ns: int, raw: bytes, other_done: bool,
             bags: tuple[Path, Path]) -> None:
        i = self.counts[side]
        self.counts[side] += 1
        h = self.sha[side]
        h.update(struct.pack("<qI", ns, len(raw)))
        h.update(raw)
        mine, other = self.pending[side], self.pending[1 - side]
        if self.types[0] != self.types[1] or (other_done and not other):
            if not mine:  # nothing to pair with: remember where this side's extra ones start
                mine.append((i, ns, None))
            return
        if other:
            j, ns_o, raw_o = other.popleft()
            assert j == i and raw_o is not None
            pair = ((ns, raw), (ns_o, raw_o))
            self.compare(i, pair[side], pair[1 - side], bags)
            return
        mine.append((i, ns, raw))

    # ------------------------------------------------------------------ result

    def freeze(self) -> TopicDiff:
        ta, tb = self.types
        ca, cb = self.counts
        sha_a = self.sha[0].hexdigest() if ta is not None else None
        sha_b = self.sha[1].hexdigest() if tb is not None else None
        first, beyond = self.first, self.first_beyond
        status: TopicStatus
        if tb is None or ta is None:
            status = "only_in_a" if tb is None else "only_in_b"
            side = 0 if tb is None else 1
            stamp = self.pending[side][0][1] if self.pending[side] else None
            beyond = first = Divergence(self.name, 0, stamp if side == 0 else None,
                                        stamp if side == 1 else None, "(topic)",
                                        f"recorded only in {'AB'[side]} ({max(ca, cb)} "
                                        "messages)")
        elif ta != tb:
            status = "differs"
            beyond = first = Divergence(self.name, 0, None, None, "(type)", f"{ta} vs {tb}")
        else:
            if ca != cb:
                side = 0 if ca > cb else 1
                i, ns, _ = self.pending[side][0]
                more = Divergence(self.name, i, ns if side == 0 else None,
                                  ns if side == 1 else None, "(message)",
                                  f"only in {'AB'[side]}: {ca} vs {cb} messages")
                first = first or more
                beyond = beyond or more
            if beyond is not None:
                status = "differs"
            elif first is not None or sha_a != sha_b:
                status = "within_tolerance"
            else:
                status = "identical"
        # beyond tolerance first, then in field order
        fields = tuple(sorted((f.freeze() for f in self.fields.values() if f.differ),
                              key=lambda f: f.within))
        return TopicDiff(self.name, ta, tb, ca, cb, sha_a, sha_b, status, self.msgs_differ,
                         first, beyond, fields, tuple(sorted(self.mism.items())),
                         self.time_shifts, self.worst, self.tolerances)


def message_stream(bag: Path, skip: Collection[str] = ()
                   ) -> tuple[dict[str, str], Generator[tuple[str, str, int, bytes], None, None]]:
    """The topics of a rosbag2 directory or a ROS 1 run's ``bag/`` (name → type as
    recorded) and an iterator of ``(topic, type, log time, payload)`` over every message, in
    the reader's order, which closes the bag when exhausted. Read errors (when opening or
    later) are :class:`~harness.recording.errors.BagReadError` naming the bag.

    ``skip``: topics left out, listed and read neither; the bag is then read through its
    MCAP index (:func:`~harness.recording.bagread.open_indexed`), which leaves their payloads
    (camera images) on disk."""
    reader = open_indexed(bag, shown=bag) if skip else open_recording(bag, shown=bag)
    kept = [c for c in reader.connections if c.topic not in skip]
    types = {c.topic: c.recorded_type for c in kept}

    def messages() -> Generator[tuple[str, str, int, bytes], None, None]:
        try:
            if kept or not skip:  # (no connection given: every topic)
                for conn, ns, raw in reader.messages(kept if skip else ()):
                    yield conn.topic, conn.recorded_type, int(ns), bytes(raw)
        finally:
            reader.close()

    return types, messages()


def diff_bags(bag_a: Path, bag_b: Path, tolerances: Sequence[Tolerance] = (), *,
              skip: Collection[str] = ()) -> tuple[TopicDiff, ...]:
    """Every topic of either bag compared (sorted by name), but those in ``skip`` (which
    are not read: the caller knows them to be identical)."""
    bags = (Path(bag_a), Path(bag_b))
    (types_a, stream_a) = message_stream(bags[0], skip)
    try:
        (types_b, stream_b) = message_stream(bags[1], skip)
    except BagError:
        stream_a.close()
        raise
    with closing(stream_a), closing(stream_b):
        return _diff_streams(bags, (types_a, types_b), (stream_a, stream_b), tolerances)


def _diff_streams(bags: tuple[Path, Path], types: tuple[dict[str, str], dict[str, str]],
                  streams: tuple[Generator[tuple[str, str, int, bytes], None, None],
                                 Generator[tuple[str, str, int, bytes], None, None]],
                  tolerances: Sequence[Tolerance]) -> tuple[TopicDiff, ...]:
    topics: dict[str, _Topic] = {}
    for side in (0, 1):
        for name, msgtype in types[side].items():
            t = topics.setdefault(name, _Topic(name, tolerances))
            t.types[side] = msgtype
    heads: list[Any] = [next(streams[0], None), next(streams[1], None)]
    while heads[0] is not None or heads[1] is not None:
        side = 0 if heads[1] is None or (heads[0] is not None
                                         and heads[0][2] <= heads[1][2]) else 1
        name, _, ns, raw = heads[side]
        if name not in topics:  # a connection the reader did not list up front
            topics[name] = _Topic(name, tolerances)
            topics[name].types[side] = heads[side][1]
        topics[name].push(side, ns, raw, heads[1 - side] is None, bags)
        heads[side] = next(streams[side], None)
    return tuple(topics[n].freeze() for n in sorted(topics))
