"""Health gates: checks that decide whether a run's scores can be trusted at all.

A tripped gate makes the run INVALID (exit 3), not FAIL. Every gate is a pure function from
plain inputs to :class:`HealthResult` rows; :func:`health_gates` wires them to
:class:`~harness.frames.Frames`. Names: ``topic_rate:<topic>``,
``recorded_equals_published``, ``clock_monotonic``, ``gt_not_frozen:<name>``,
``sut_output_alive:<topic>``.

* Topic rate: ``count / duration`` >= ``min_fraction`` (0.9) x the expected rate.
* Recorded = published: per topic, the recorder's count equals the bus's.
* Clock: ``/clock`` values strictly increasing, at least one message.
* Ground truth not frozen: for each expected ground-truth object, at least one message; an
  object whose poses are all identical trips the gate when it should move: a robot whose
  odometry travelled more than ``min_motion_m``, or a name listed in ``moving``.
* SUT output alive: per output topic, at least ``min_count`` messages, the first within
  ``first_within_s`` of the start, and no silence longer than ``max_silence_s`` between two
  messages or between the last one and the end of the run.
* TF tree (``tf_tree``, or ``tf_tree:<ns>`` for a namespaced ``<ns>/tf``): the recorded
  transforms form one valid tree as tf2 needs it — every frame one parent, no frame both
  static and dynamic, no cycle, frame ids tf2 accepts (:mod:`harness.tf_tree`), no frame
  published twice with the same stamp (two sources; tf2 drops the second as repeated data)
  and no static frame given two different transforms.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import pandas as pd

from harness.frames import Frames
from harness.metrics.types import HealthResult
from harness.tf_tree import Edge, roots, tree_problems

__all__ = [
    "OutputSpec",
    "clock_monotonic",
    "gt_not_frozen",
    "health_gates",
    "recorded_equals_published",
    "sut_outputs_alive",
    "tf_tree_gate",
    "topic_rates",
]


@dataclass(frozen=True)
class OutputSpec:
    """What "alive" means for one output topic of a system under test."""

    min_count: int = 1
    first_within_s: float | None = None
    max_silence_s: float | None = None


def _abs(topic: str) -> str:
    return topic if topic.startswith("/") else f"/{topic}"


def topic_rates(topics: pd.DataFrame, expected_hz: Mapping[str, float], *, duration_s: float,
                min_fraction: float = 0.9) -> list[HealthResult]:
    """``topics``: ``name, count`` (the frames' topic table)."""
    counts = dict(zip(topics["name"], topics["count"], strict=True))
    out = []
    for topic, hz in sorted(expected_hz.items()):
        name = _abs(topic)
        n = int(counts.get(name, 0))
        rate = n / duration_s if duration_s > 0 else 0.0
        need = min_fraction * hz
        ok = rate >= need - 1e-9
        out.append(HealthResult(
            f"topic_rate:{name}", ok,
            f"{rate:.3f} Hz ({n} messages in {duration_s:.3f} s); expected {hz:g} Hz, "
            f"needs >= {need:.3f} Hz"))
    return out


def recorded_equals_published(recorded: Mapping[str, int], published: Mapping[str, int]
                              ) -> list[HealthResult]:
    rec = {_abs(k): int(v) for k, v in recorded.items()}
    pub = {_abs(k): int(v) for k, v in published.items()}
    bad = {t: (pub.get(t, 0), rec.get(t, 0)) for t in sorted(set(rec) | set(pub))
           if pub.get(t, 0) != rec.get(t, 0)}
    if bad:
        detail = "; ".join(f"{t}: published {p}, recorded {r}" for t, (p, r) in bad.items())
    else:
        detail = (f"every published message was recorded ({sum(pub.values())} messages on "
                  f"{len(pub)} topics)")
    return [HealthResult("recorded_equals_published", not bad, detail)]


def clock_monotonic(clock: pd.DataFrame) -> list[HealthResult]:
    """``clock``: ``t_ns`` in recorded order."""
    t = clock["t_ns"].to_numpy(np.int64)
    if t.size == 0:
        return [HealthResult("clock_monotonic", False, "no /clock messages")]
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        i = int(bad[0])
        return [HealthResult("clock_monotonic", False,
                             f"{bad.size} non-increasing steps; first at message {i + 1}: "
                             f"{int(t[i])} ns -> {int(t[i + 1])} ns")]
    return [HealthResult("clock_monotonic", True,
                         f"{t.size} messages, strictly increasing")]


def gt_not_frozen(gt_poses: pd.DataFrame, *, expected: Sequence[str],
                  odom_motion_m: Mapping[str, float] | None = None,
                  moving: Sequence[str] = (), min_motion_m: float = 0.05
                  ) -> list[HealthResult]:
    """``gt_poses``: ``name, x, y, z, yaw``. ``odom_motion_m``: robot name → distance its
    odometry travelled (m)."""
    odom_motion_m = odom_motion_m or {}
    out = []
    for name in sorted(set(expected) | set(moving) | set(odom_motion_m)):
        g = gt_poses[gt_poses["name"] == name]
        if len(g) == 0:
            out.append(HealthResult(f"gt_not_frozen:{name}", False,
                                    f"/gt/{name}/tf has no messages"))
            continue
        vals = g[["x", "y", "z", "yaw"]].to_numpy(np.float64)
        frozen = bool((vals == vals[0]).all())
        odo = odom_motion_m.get(name)
        if frozen and odo is not None and odo > min_motion_m:
            out.append(HealthResult(f"gt_not_frozen:{name}", False,
                                    f"{len(g)} identical poses while odometry travelled "
                                    f"{odo:.3f} m"))
        elif frozen and name in moving:
            out.append(HealthResult(f"gt_not_frozen:{name}", False,
                                    f"{len(g)} identical poses for an object that moves"))
        else:
            span = float(np.hypot(*(vals[:, :2] - vals[0, :2]).T).max())
            out.append(HealthResult(f"gt_not_frozen:{name}", True,
                                    f"{len(g)} poses, up to {span:.3f} m from the first"))
    return out


def sut_outputs_alive(topics: pd.DataFrame, outputs: Mapping[str, OutputSpec], *,
                      start_ns: int, end_ns: int) -> list[HealthResult]:
    """``topics``: ``name, count, first_ns, last_ns, max_gap_ns`` (the frames' topic table);
    ``end_ns``: the end of the run (its last tick)."""
    rows = {r.name: r for r in topics.itertuples(index=False)}
    out = []
    for topic, spec in sorted(outputs.items()):
        name = _abs(topic)
        r = rows.get(name)
        count = int(r.count) if r is not None else 0
        problems = []
        if count < spec.min_count:
            problems.append(f"{count} messages, needs >= {spec.min_count}")
        if r is not None and count:
            first_s = (int(r.first_ns) - start_ns) / 1e9
            if spec.first_within_s is not None and first_s > spec.first_within_s:
                problems.append(f"first message at {first_s:.3f} s, needs <= "
                                f"{spec.first_within_s:g} s")
            if spec.max_silence_s is not None:
                gap_s = int(r.max_gap_ns) / 1e9
                tail_s = (end_ns - int(r.last_ns)) / 1e9
                if gap_s > spec.max_silence_s:
                    problems.append(f"silent for {gap_s:.3f} s between messages, allowed "
                                    f"{spec.max_silence_s:g} s")
                if tail_s > spec.max_silence_s:
                    problems.append(f"silent for the last {tail_s:.3f} s, allowed "
                                    f"{spec.max_silence_s:g} s")
        elif spec.first_within_s is not None and spec.min_count > 0:
            problems.append("never published")
        detail = "; ".join(problems) if problems else f"{count} messages"
        out.append(HealthResult(f"sut_output_alive:{name}", not problems, detail))
    return out


_POSE = ["x", "y", "z", "qx", "qy", "qz", "qw"]


def tf_tree_gate(tf: pd.DataFrame) -> list[HealthResult]:
    """``tf``: the frames' TF table (``topic, tree, static, parent, child, t_ns`` and the
    pose). One gate per tree namespace; none when nothing was published on a TF topic.

    Works on the categorical columns' codes, so that its memory stays a few integer arrays
    of the table's length (a long run's ``/tf`` has hundreds of thousands of rows; grouping
    and de-duplicating them in pandas took more than twice the table's size again)."""
    out = []
    cols = {c: _codes(tf[c]) for c in ("tree", "parent", "child", "topic")}
    static = tf["static"].to_numpy(bool)
    t_ns = tf["t_ns"].to_numpy(np.int64)
    for k in np.unique(cols["tree"][0]):
        rows = np.flatnonzero(cols["tree"][0] == k)
        tree = str(cols["tree"][1][k])
        edges = _tf_edges(cols, static, rows)
        problems = [p.detail for p in tree_problems(sorted(edges, key=_edge_key))]
        problems += _repeated_stamps(cols["child"], t_ns, rows[~static[rows]])
        st = tf.iloc[rows[static[rows]]]
        for child, c in st.groupby("child", observed=True):
            # different beyond float noise (1 µm, 1e-6 of a unit quaternion)
            distinct = len(c[_POSE].round(6).drop_duplicates())
            if distinct > 1 and c["parent"].nunique() == 1:
                problems.append(f"static frame '{child}' was given {distinct} different "
                                "transforms (two sources?)")
        name = "tf_tree" if tree == "/" else f"tf_tree:{tree}"
        if problems:
            out.append(HealthResult(name, False, "; ".join(problems)))
        else:
            frames = {e.child for e in edges} | {e.parent for e in edges}
            rts = roots(edges)
            out.append(HealthResult(name, True, f"{len(frames)} frames, one parent each; "
                                    f"root{'s' if len(rts) > 1 else ''}: {', '.join(rts)}"))
    return out


Codes = npt.NDArray[np.signedinteger[Any]]


def _codes(column: pd.Series) -> tuple[Codes, npt.NDArray[np.object_]]:
    """A column as integer codes into its sorted distinct values (a categorical's own
    categories and order, in its own code type: one byte a row for a few hundred frames,
    or the values' sorted order)."""
    if isinstance(column.dtype, pd.CategoricalDtype):
        return (column.cat.codes.to_numpy(),
                np.asarray(column.cat.categories, dtype=object))
    values, codes = np.unique(column.to_numpy(object).astype(str), return_inverse=True)
    return codes.astype(np.int64), values.astype(object)


def _tf_edges(cols: Mapping[str, tuple[Codes, npt.NDArray[np.object_]]],
              static: npt.NDArray[np.bool_], rows: npt.NDArray[np.intp]) -> set[Edge]:
    """The distinct (parent, child, static, topic) of ``rows``, as edges."""
    key = np.zeros(len(rows), dtype=np.int64)
    for name in ("parent", "child", "topic"):
        codes, values = cols[name]
        key = key * len(values) + codes[rows]
    key = key * 2 + static[rows]
    edges = set()
    for k in np.unique(key).tolist():
        k, st = divmod(k, 2)
        k, topic = divmod(k, len(cols["topic"][1]))
        parent, child = divmod(k, len(cols["child"][1]))
        edges.add(Edge(str(cols["parent"][1][parent]), str(cols["child"][1][child]),
                       bool(st), str(cols["topic"][1][topic])))
    return edges


def _repeated_stamps(child: tuple[Codes, npt.NDArray[np.object_]],
                     t_ns: npt.NDArray[np.int64], rows: npt.NDArray[np.intp]) -> list[str]:
    """Per child frame (in category order) published more than once with one stamp in
    ``rows``: how often at its first such stamp, at how many stamps, and the first."""
    codes, values = child
    c, t = codes[rows], t_ns[rows]
    order = np.lexsort((t, c))
    c, t = c[order], t[order]
    if len(c) < 2:
        return []
    same = (c[1:] == c[:-1]) & (t[1:] == t[:-1])
    if not same.any():
        return []
    starts = np.flatnonzero(np.r_[True, ~same])  # the first row of each (child, stamp)
    sizes = np.diff(np.r_[starts, len(c)])
    dup = starts[sizes > 1]
    dup_sizes = sizes[sizes > 1]
    problems = []
    for code in np.unique(c[dup]).tolist():
        mine = np.flatnonzero(c[dup] == code)
        first = int(dup[mine[0]])
        problems.append(f"frame '{values[code]}' published {int(dup_sizes[mine[0]])} times "
                        f"with the same stamp at {len(mine)} time(s), first at "
                        f"{int(t[first]) / 1e9:.3f} s: two sources (tf2 ignores the "
                        "repeats)")
    return problems


def _edge_key(e: Edge) -> tuple[str, str, bool, str]:
    return (e.child, e.parent, e.static, e.source)


def _odom_travel(frames: Frames, odom_topics: Mapping[str, str]) -> dict[str, float]:
    """Robot name → distance its odometry (``odom_topics[robot]``) travelled."""
    out = {}
    for robot, topic in odom_topics.items():
        o = frames.odom[frames.odom["topic"] == topic]
        x, y = o["x"].to_numpy(), o["y"].to_numpy()
        out[robot] = float(np.hypot(np.diff(x), np.diff(y)).sum()) if x.size > 1 else 0.0
    return out


def health_gates(frames: Frames, *, expected_hz: Mapping[str, float] | None = None,
                 recorded: Mapping[str, int] | None = None,
                 published: Mapping[str, int] | None = None,
                 gt_expected: Sequence[str] | None = None, gt_moving: Sequence[str] = (),
                 robots: Mapping[str, str] | None = None,
                 outputs: Mapping[str, OutputSpec] | None = None,
                 duration_s: float | None = None, min_fraction: float = 0.9
                 ) -> list[HealthResult]:
    """Every gate that its inputs allow. ``gt_expected`` None: no ground truth expected, no
    gate; ``recorded`` defaults to the bag's counts; ``duration_s`` to the span of the bag plus
    one clock period. ``robots``: robot name → its odometry topic, which tells whether it
    moved."""
    if duration_s is None:
        ct = frames.clock["t_ns"].to_numpy(np.int64)
        tick = int(np.median(np.diff(ct))) if ct.size > 1 else 0
        duration_s = (frames.end_ns - frames.start_ns + tick) / 1e9
    out: list[HealthResult] = []
    if expected_hz:
        out += topic_rates(frames.topics, expected_hz, duration_s=duration_s,
                           min_fraction=min_fraction)
    if published is not None:
        rec = recorded if recorded is not None else dict(
            zip(frames.topics["name"], frames.topics["count"], strict=True))
        out += recorded_equals_published(rec, published)
    out += clock_monotonic(frames.clock)
    out += tf_tree_gate(frames.tf)
    if gt_expected is not None:
        out += gt_not_frozen(frames.gt_poses, expected=gt_expected,
                             odom_motion_m=_odom_travel(frames, robots or {}),
                             moving=gt_moving)
    if outputs:
        ct = frames.clock["t_ns"].to_numpy(np.int64)
        start = int(ct[0]) if ct.size else frames.start_ns
        end = int(ct[-1]) if ct.size else frames.end_ns
        out += sut_outputs_alive(frames.topics, outputs, start_ns=start, end_ns=end)
    return out
