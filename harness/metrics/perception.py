"""Perception metrics: tracked objects (MarkerArray) against ground truth (``/gt/*``).

The core, :func:`clear_mot`, scores frames that are already aligned: per frame, the
ground-truth objects and the tracks of one class, both as world-frame positions.

Matching, per frame (the CLEAR MOT procedure, as py-motmetrics implements it):

1. An object that was matched before keeps its last track if that track is present in this
   frame and within the gate (objects in id order; the first track carrying that id).
2. The remaining objects and tracks are paired by a minimum-cost assignment on Euclidean
   distance: as many pairs within the gate as possible, then the smallest total distance
   (SciPy's ``linear_sum_assignment``).
3. A pair formed in step 2 is an ID switch when the object's last track was another one.

Counts: TP = pairs, FN = objects - TP, FP = tracks - TP; precision = TP / tracks,
recall = TP / objects, F1 their harmonic mean; MOTA = 1 - (FN + FP + IDSW) / objects.
Position error = distance of each TP pair (mean, median, 95th percentile, linear
interpolation). Recall at r is the recall of the same procedure run with gate r.
IDF1 = 2 IDTP / (objects + tracks), where IDTP is the largest total number of frames in which
a ground-truth identity and a track identity are within the gate, over one-to-one pairings
of identities for the whole run (global assignment).

Alignment (:func:`perception_metrics`): the frames are the perception output messages (one
per MarkerArray, empty ones included). Each frame takes, per ground-truth object, the pose
with the nearest stamp within ``time_tolerance_ns`` (default: half the median ground-truth
period). A frame with no ground-truth stamp near it at all is not scored (its count is in the
detail); an object without a nearby pose is absent from that frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from harness.errors import SrrError
from harness.frames import Frames
from harness.metrics.types import MetricResult

__all__ = [
    "MotCounts",
    "align_frames",
    "assign",
    "clear_mot",
    "perception_metrics",
]


# --------------------------------------------------------------------------- assignment


def _lsa(cost: np.ndarray) -> list[tuple[int, int]]:
    """SciPy's minimum-cost assignment, imported at the first call: importing
    ``scipy.optimize`` takes about 0.5 s, which a run without tracks need not pay."""
    from scipy.optimize import linear_sum_assignment

    r, c = linear_sum_assignment(cost)
    return list(zip(r.tolist(), c.tolist(), strict=True))


def assign(cost: np.ndarray) -> list[tuple[int, int]]:
    """Pairs of a cost matrix whose NaN/inf entries are forbidden: the most pairs possible,
    then the least total cost. Forbidden entries are replaced by a constant large enough that
    using one always costs more than any set of allowed ones (then dropped)."""
    cost = np.asarray(cost, dtype=np.float64)
    valid = np.isfinite(cost)
    if not valid.any():
        return []
    c = float(np.abs(cost[valid]).max()) + 1.0
    big = 2.0 * min(cost.shape) * c + 1.0
    pairs = _lsa(np.where(valid, cost, big))
    return [(i, j) for i, j in pairs if valid[i, j]]


# --------------------------------------------------------------------------- CLEAR MOT core


@dataclass(frozen=True)
class MotCounts:
    """Totals of one tracking evaluation. ``errors``: distance of every TP pair (m)."""

    frames: int
    objects: int
    tracks: int
    tp: int
    id_switches: int
    idtp: int
    errors: np.ndarray = field(compare=False, repr=False)

    @property
    def fn(self) -> int:
        return self.objects - self.tp

    @property
    def fp(self) -> int:
        return self.tracks - self.tp

    @property
    def precision(self) -> float | None:
        return self.tp / self.tracks if self.tracks else None

    @property
    def recall(self) -> float | None:
        return self.tp / self.objects if self.objects else None

    @property
    def f1(self) -> float | None:
        denom = self.objects + self.tracks
        return 2.0 * self.tp / denom if denom else None

    @property
    def mota(self) -> float | None:
        if not self.objects:
            return None
        return 1.0 - (self.fn + self.fp + self.id_switches) / self.objects

    @property
    def idf1(self) -> float | None:
        denom = self.objects + self.tracks
        return 2.0 * self.idtp / denom if denom else None


def _sorted_cols(df: pd.DataFrame, id_col: str) -> tuple[np.ndarray, ...]:
    d = df.sort_values(["frame", id_col], kind="stable")
    return (d["frame"].to_numpy(np.int64), d[id_col].to_numpy(), d["x"].to_numpy(np.float64),
            d["y"].to_numpy(np.float64))


def _pairs(gf: np.ndarray, gx: np.ndarray, gy: np.ndarray, hf: np.ndarray, hx: np.ndarray,
           hy: np.ndarray, gate: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All (object row, track row, distance) of the same frame within the gate, ordered by
    frame, then object row, then track row."""
    frames = np.union1d(gf, hf)
    g_lo, g_hi = np.searchsorted(gf, frames), np.searchsorted(gf, frames, side="right")
    h_lo, h_hi = np.searchsorted(hf, frames), np.searchsorted(hf, frames, side="right")
    ng, nh = g_hi - g_lo, h_hi - h_lo
    per = ng * nh
    total = int(per.sum())
    if total == 0:
        e = np.zeros(0, dtype=np.int64)
        return e, e, np.zeros(0)
    f_of = np.repeat(np.arange(frames.size), per)
    k = np.arange(total) - np.repeat(np.cumsum(per) - per, per)
    nh_of = nh[f_of]
    gi = g_lo[f_of] + k // nh_of
    hj = h_lo[f_of] + k % nh_of
    d = np.hypot(gx[gi] - hx[hj], gy[gi] - hy[hj])
    ok = d <= gate
    return gi[ok], hj[ok], d[ok]


def _identity_tp(oid: np.ndarray, hid: np.ndarray) -> int:
    """Largest total co-occurrence over one-to-one pairings of identities."""
    if oid.size == 0:
        return 0
    ou, oi = np.unique(oid, return_inverse=True)
    hu, hi = np.unique(hid, return_inverse=True)
    counts = np.zeros((ou.size, hu.size))
    np.add.at(counts, (oi, hi), 1.0)
    return round(float(sum(counts[i, j] for i, j in _lsa(-counts))))


def clear_mot(gt: pd.DataFrame, tracks: pd.DataFrame, *, gate: float = 1.0) -> MotCounts:
    """Score aligned frames. ``gt``: ``frame, oid, x, y``; ``tracks``: ``frame, hid, x, y``
    (any hashable ids). Frames are processed in increasing ``frame`` order.

    A frame in which no object and no track has two candidates within the gate is matched
    the same way whatever happened before (every candidate pair is a match), so those frames
    are scored together with numpy; only contested frames replay the procedure one by one,
    with the history of matches as of that frame. ID switches are then counted over all
    matches: a match whose object's previous match had another track."""
    gf, go, gx, gy = _sorted_cols(gt, "oid")
    hf, ho, hx, hy = (_sorted_cols(tracks, "hid") if len(tracks)
                      else (np.zeros(0, np.int64), np.zeros(0), np.zeros(0), np.zeros(0)))
    pi, pj, pd_ = _pairs(gf, gx, gy, hf, hx, hy, gate)
    pf = gf[pi]
    contested = ((np.bincount(pi, minlength=gf.size)[pi] > 1)
                 | (np.bincount(pj, minlength=hf.size)[pj] > 1))
    hard = np.isin(pf, np.unique(pf[contested]))
    easy_idx = np.flatnonzero(~hard)
    matched = [easy_idx]
    hard_idx = np.flatnonzero(hard)
    if hard_idx.size:
        matched.append(_replay_contested(hard_idx, easy_idx, pi, pj, pd_, pf, go, ho, hf))
    m = np.sort(np.concatenate(matched))
    o_codes = pd.factorize(go[pi[m]])[0]
    h_codes = pd.factorize(ho[pj[m]])[0]
    order = np.lexsort((pf[m], o_codes))
    o_s, h_s = o_codes[order], h_codes[order]
    switches = int(((o_s[1:] == o_s[:-1]) & (h_s[1:] != h_s[:-1])).sum())
    return MotCounts(frames=int(np.union1d(gf, hf).size), objects=int(gf.size),
                     tracks=int(hf.size), tp=int(m.size), id_switches=switches,
                     idtp=_identity_tp(go[pi], ho[pj]), errors=pd_[m])


def _replay_contested(hard_idx: np.ndarray, easy_idx: np.ndarray, pi: np.ndarray,
                      pj: np.ndarray, pd_: np.ndarray, pf: np.ndarray, go: np.ndarray,
                      ho: np.ndarray, hf: np.ndarray) -> np.ndarray:
    """Pair indices matched in the contested frames (keep, then assign)."""
    g_ids, h_ids = go.tolist(), ho.tolist()
    easy_f = pf[easy_idx]
    easy_o = go[pi[easy_idx]].tolist()
    easy_h = ho[pj[easy_idx]].tolist()
    hf_ = pf[hard_idx]
    bounds = np.flatnonzero(np.diff(hf_)) + 1
    starts = np.concatenate(([0], bounds)).astype(np.int64)
    ends = np.concatenate((bounds, [hard_idx.size])).astype(np.int64)
    frames = hf_[starts]
    upto = np.searchsorted(easy_f, frames).tolist()
    h_los = np.searchsorted(hf, frames).tolist()
    h_his = np.searchsorted(hf, frames, side="right").tolist()
    pi_l, pj_l, pd_l = pi.tolist(), pj.tolist(), pd_.tolist()
    hard_l = hard_idx.tolist()
    last: dict[Any, Any] = {}
    cursor = 0
    out: list[int] = []
    for s, e, up, h_lo, h_hi in zip(starts.tolist(), ends.tolist(), upto, h_los, h_his,
                                    strict=True):
        last.update(zip(easy_o[cursor:up], easy_h[cursor:up], strict=True))
        cursor = up
        pair_of = {(pi_l[k], pj_l[k]): k for k in hard_l[s:e]}
        g_used: set[int] = set()
        h_used: set[int] = set()
        # 1. keep previous correspondences (objects in id order, first track with that id)
        for g in sorted({g for g, _ in pair_of}):
            prev = last.get(g_ids[g], _NONE)
            if prev is _NONE:
                continue
            j = next((j for j in range(h_lo, h_hi) if j not in h_used and h_ids[j] == prev),
                     None)
            if j is None or (g, j) not in pair_of:
                continue
            g_used.add(g)
            h_used.add(j)
            out.append(pair_of[(g, j)])
        # 2. assign the rest
        rest = [(g, j) for (g, j) in pair_of if g not in g_used and j not in h_used]
        if not rest:
            continue
        rg = sorted({g for g, _ in rest})
        rh = sorted({j for _, j in rest})
        mat = np.full((len(rg), len(rh)), np.nan)
        gi_of = {g: i for i, g in enumerate(rg)}
        hj_of = {j: i for i, j in enumerate(rh)}
        for g, j in rest:
            mat[gi_of[g], hj_of[j]] = pd_l[pair_of[(g, j)]]
        for a, b in assign(mat):
            g, j = rg[a], rh[b]
            last[g_ids[g]] = h_ids[j]
            out.append(pair_of[(g, j)])
    return np.asarray(out, dtype=np.int64)


class _NoneType:
    pass


_NONE = _NoneType()


# --------------------------------------------------------------------------- alignment


def align_frames(frame_t: np.ndarray, gt: pd.DataFrame, *, tolerance_ns: int,
                 objects: Sequence[str] | None = None) -> tuple[np.ndarray, pd.DataFrame]:
    """Per frame time, the pose of each ground-truth object at its nearest stamp within the
    tolerance.

    Returns (frame has any ground-truth stamp near it, rows ``frame, oid, name, x, y``) where
    ``frame`` is the position in ``frame_t``, ``oid`` the object's rank in sorted ``objects``
    (default: every name in ``gt``); only objects produce rows, every name aligns."""
    n = frame_t.size
    aligned = np.zeros(n, dtype=bool)
    names = sorted(str(v) for v in gt["name"].unique())
    wanted = names if objects is None else sorted(set(objects) & set(names))
    rank = {name: i for i, name in enumerate(wanted)}
    parts = []
    for name, g in gt.groupby("name", sort=True, observed=True):
        g = g.sort_values("t_ns", kind="stable")
        t = g["t_ns"].to_numpy(np.int64)
        if t.size == 0:
            continue
        i = np.clip(np.searchsorted(t, frame_t), 1, max(t.size - 1, 1))
        lo = np.clip(i - 1, 0, t.size - 1)
        hi = np.clip(i, 0, t.size - 1)
        k = np.where(np.abs(t[hi] - frame_t) < np.abs(frame_t - t[lo]), hi, lo)
        ok = np.abs(t[k] - frame_t) <= tolerance_ns
        aligned |= ok
        if str(name) in rank:
            m = int(ok.sum())
            parts.append(pd.DataFrame({
                "frame": np.flatnonzero(ok), "oid": np.full(m, rank[str(name)]),
                "name": np.full(m, str(name), dtype=object),
                "x": g["x"].to_numpy(np.float64)[k[ok]],
                "y": g["y"].to_numpy(np.float64)[k[ok]]}))
    rows = (pd.concat(parts, ignore_index=True) if parts
            else pd.DataFrame({"frame": np.zeros(0, np.int64), "oid": np.zeros(0, np.int64),
                               "name": np.zeros(0, object), "x": np.zeros(0),
                               "y": np.zeros(0)}))
    return aligned, rows


def _pm(prefix: str, name: str, value: float | None, unit: str, direction: Any,
        detail: str = "") -> MetricResult:
    v = None if value is None or not math.isfinite(value) else float(value)
    return MetricResult(f"{prefix}.{name}", v, unit, direction, "perception", detail)


def perception_metrics(frames: Frames, *, cls: str = "person",
                       gt_prefix: str = "character_", gate: float = 1.0,
                       time_tolerance_ns: int | None = None, topic: str | None = None,
                       recall_radii: Sequence[float] = (0.5, 1.0),
                       prefix: str = "perception") -> list[MetricResult]:
    """Every perception metric for tracks of class ``cls`` (marker ``ns``) against the
    ground-truth objects whose name starts with ``gt_prefix``.

    ``topic``: the MarkerArray topic to score; needed when the bag has several."""
    tf = frames.track_frames
    topics = sorted(set(tf["topic"]))
    if topic is None and len(topics) > 1:
        raise SrrError(f"perception: {len(topics)} MarkerArray topics ({', '.join(topics)}); "
                       "choose one with topic=")
    if topic is not None:
        tf = tf[tf["topic"] == topic]
    names = ["precision", "recall", "f1", "position_error.mean", "position_error.median",
             "position_error.p95", *[_recall_name(r) for r in recall_radii],
             "recall_at_gate", "id_switches", "mota", "idf1"]
    gt_all = frames.gt_poses
    why = ("no tracking output" if len(tf) == 0
           else "no ground truth" if len(gt_all) == 0 else "")
    if why:
        return [_pm(prefix, n, None, *_unit(n), why) for n in names]
    tf = tf.sort_values(["t_ns", "frame"], kind="stable")
    if time_tolerance_ns is None:
        stamps = np.unique(gt_all["t_ns"].to_numpy(np.int64))
        time_tolerance_ns = int(np.median(np.diff(stamps)) // 2) if stamps.size > 1 else 0
    objects = [n for n in frames.gt_names if n.startswith(gt_prefix)]
    aligned, objs = align_frames(tf["t_ns"].to_numpy(np.int64), gt_all,
                                 tolerance_ns=time_tolerance_ns, objects=objects)
    # scoring order = time order: frame k is the k-th aligned frame
    rank = np.full(len(tf), -1, dtype=np.int64)
    rank[aligned] = np.arange(int(aligned.sum()))
    gt = pd.DataFrame({"frame": rank[objs["frame"].to_numpy(np.int64)],
                       "oid": objs["oid"].to_numpy(np.int64),
                       "x": objs["x"].to_numpy(np.float64), "y": objs["y"].to_numpy(np.float64)})
    frame_ids = tf["frame"].to_numpy(np.int64)
    rank_of = pd.Series(rank, index=frame_ids)
    tr = frames.tracks
    tr = tr[(tr["cls"] == cls).to_numpy(bool) & tr["frame"].isin(frame_ids[aligned]).to_numpy()]
    hyp = pd.DataFrame({"frame": rank_of.reindex(tr["frame"].to_numpy()).to_numpy(np.int64),
                        "hid": tr["track_id"].to_numpy(np.int64),
                        "x": tr["x"].to_numpy(np.float64), "y": tr["y"].to_numpy(np.float64)})
    res = clear_mot(gt, hyp, gate=gate)
    detail = (f"{int(aligned.sum())} of {len(tf)} frames scored (time tolerance "
              f"{time_tolerance_ns / 1e6:.3f} ms), {res.objects} objects, {res.tracks} "
              f"tracks, TP {res.tp}, FP {res.fp}, FN {res.fn}, gate {gate} m")
    err = res.errors
    has_err = err.size > 0
    out = [
        _pm(prefix, "precision", res.precision, "ratio", "higher", detail),
        _pm(prefix, "recall", res.recall, "ratio", "higher", detail),
        _pm(prefix, "f1", res.f1, "ratio", "higher", detail),
        _pm(prefix, "position_error.mean", float(err.mean()) if has_err else None, "m",
            "lower", "" if has_err else "no matches"),
        _pm(prefix, "position_error.median", float(np.median(err)) if has_err else None, "m",
            "lower", "" if has_err else "no matches"),
        _pm(prefix, "position_error.p95", float(np.percentile(err, 95)) if has_err else None,
            "m", "lower", "" if has_err else "no matches"),
    ]
    for r in recall_radii:
        at = res if r == gate else clear_mot(gt, hyp, gate=r)
        out.append(_pm(prefix, _recall_name(r), at.recall, "ratio", "higher",
                       f"recall with a {r} m gate"))
    out += [
        _pm(prefix, "recall_at_gate", res.recall, "ratio", "higher", f"gate {gate} m"),
        _pm(prefix, "id_switches", float(res.id_switches), "count", "lower", detail),
        _pm(prefix, "mota", res.mota, "ratio", "higher", detail),
        _pm(prefix, "idf1", res.idf1, "ratio", "higher", f"IDTP {res.idtp}; {detail}"),
    ]
    return out


def _recall_name(r: float) -> str:
    return "recall_at_" + f"{r:.1f}".replace(".", "_") + "m"


def _unit(name: str) -> tuple[str, str]:
    if name.startswith("position_error"):
        return "m", "lower"
    if name == "id_switches":
        return "count", "lower"
    return "ratio", "higher"
