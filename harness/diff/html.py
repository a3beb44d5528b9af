"""``srr diff --html FILE``: baseline (A) and candidate (B) on one self-contained page.

What the page shows, top to bottom: the verdict with the first divergence, both runs, the
topic table (first divergence and largest difference per topic), both runs' metrics side by
side, one map with both runs' trajectories, camera keyframes of A and B side by side (with
the pixels that differ) at the numbered moments — the first divergence, each camera's most
differing frame, the largest gap between the runs' robots and workers — the time series of
both runs overlaid, and every numeric field that differs.

Both runs' camera videos play side by side under one time cursor shared with the map and
the time series (the report's cursor, ``templates/cursor.js``): the videos each run's report
wrote (``<run>/video/``), linked relatively; for a run without them (rendered with
``--no-video``, or from before srr wrote videos) they are encoded beside the page, into
``<page>.video/a`` or ``b`` — a run directory is only read. Otherwise the page loads nothing:
inline SVG (drawn by :mod:`harness.report.plots`), base64 PNG, inline CSS. The runs are read
with :func:`harness.report.data.load_run`, so what is plotted is what the report plots.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from markupsafe import Markup

from harness import __version__
from harness.atomic import write_text_atomic
from harness.diff.result import DiffResult, TopicDiff
from harness.errors import SrrError
from harness.report.data import Moment, RunData, load_run
from harness.report.html import cursor_context, fmt_value
from harness.report.images import (
    IMAGE_TYPE,
    IMAGE_TYPES,
    Keyframe,
    data_uri,
    encode_png,
    nearest_images,
)
from harness.report.plots import (
    BASELINE,
    CANDIDATE,
    map_legend,
    map_svg,
    map_tracks,
    time_panels,
)
from harness.report.templates import template
from harness.report.video import VideoSet, read_videos, write_videos

__all__ = ["diff_moments", "render_diff", "write_diff"]

MAX_MOMENTS = 6
MAX_FIELDS = 300
MIN_GAP_M = 1e-3  # a smaller gap between the runs' trajectories is not a moment


@dataclass(frozen=True)
class Pair:
    """One camera at one moment: A's and B's nearest images and where they differ."""

    topic: str
    a: Keyframe | None
    b: Keyframe | None
    diff_uri: str | None
    differ: int
    total: int


@dataclass(frozen=True)
class PairRow:
    moment: Moment
    pairs: tuple[Pair, ...]


def _gap(a: RunData, b: RunData, kind: str) -> tuple[float, float, str] | None:
    """(time, distance, name) of the largest distance between the runs' same-named tracks of
    ``kind`` (B interpolated at A's times)."""
    best: tuple[float, float, str] | None = None
    others = {t.name: t for t in b.tracks if t.kind == kind}
    for ta in (t for t in a.tracks if t.kind == kind):
        tb = others.get(ta.name)
        if tb is None or ta.t.size == 0 or tb.t.size < 2:
            continue
        inside = (ta.t >= tb.t[0]) & (ta.t <= tb.t[-1])
        if not inside.any():
            continue
        t = ta.t[inside]
        d = np.hypot(ta.x[inside] - np.interp(t, tb.t, tb.x),
                     ta.y[inside] - np.interp(t, tb.t, tb.y))
        i = int(np.nanargmax(d)) if np.isfinite(d).any() else -1
        if i >= 0 and d[i] >= MIN_GAP_M and (best is None or d[i] > best[1]):
            best = (float(t[i]), float(d[i]), ta.name)
    return best


def diff_moments(result: DiffResult, a: RunData | None = None, b: RunData | None = None
                 ) -> list[Moment]:
    """Numbered moments worth a look, in time order: the first divergence, the most
    differing frame of each camera, the largest gap between the runs' robots and between
    their workers (at most :data:`MAX_MOMENTS`, none closer than 0.25 s to another)."""
    cands: list[tuple[float, str, str]] = []
    first = result.first_divergence or next(
        (t.first for t in sorted(result.topics, key=lambda t: t.first.t_ns if t.first else 0)
         if t.first is not None), None)
    if first is not None:
        cands.append((first.t_ns / 1e9, f"first divergence: {first.topic} #{first.index} "
                      f"{first.path}", "divergence"))
    images = sorted((t for t in result.topics if t.msgtype == IMAGE_TYPE and t.worst
                     and t.worst.values > 0), key=lambda t: -(t.worst.values if t.worst else 0))
    for img in images:
        assert img.worst is not None
        cands.append((img.worst.t_ns / 1e9, f"most differing {img.name} frame "
                      f"(#{img.worst.index}, {img.worst.values} values differ)", "camera"))
    if a is not None and b is not None:
        for kind, what in (("robot", "robot"), ("worker", "worker")):
            gap = _gap(a, b, kind)
            if gap is not None:
                cands.append((gap[0], f"largest gap between the runs' {what} {gap[2]}: "
                              f"{gap[1]:.3f} m", "separation"))
    chosen: list[tuple[float, str, str]] = []
    for t, label, kind in cands:
        if len(chosen) < MAX_MOMENTS and math.isfinite(t) and \
                all(abs(t - u) > 0.25 for u, _, _ in chosen):
            chosen.append((t, label, kind))
    chosen.sort(key=lambda m: m[0])
    return [Moment(i + 1, t, label, kind) for i, (t, label, kind) in enumerate(chosen)]


def _difference(pa: np.ndarray, pb: np.ndarray) -> tuple[bytes, int, int] | None:
    """PNG of A dimmed with the pixels that differ in red (brighter: larger difference),
    the number of differing pixels and of all pixels; None when the shapes differ."""
    if pa.shape != pb.shape:
        return None
    d = np.abs(pa.astype(np.int16) - pb.astype(np.int16))
    mag = d.max(axis=2) if d.ndim == 3 else d
    grey = pa.mean(axis=2) if pa.ndim == 3 else pa.astype(np.float64)
    base = (grey * 0.45).astype(np.uint8)
    out = np.stack([base, base, base], axis=-1)
    mask = mag > 0
    out[mask] = np.stack([np.minimum(255, 110 + mag[mask]), np.zeros(int(mask.sum())),
                          np.zeros(int(mask.sum()))], axis=-1).astype(np.uint8)
    return encode_png(out), int(mask.sum()), int(mask.size)


def _gaps(data: RunData) -> dict[str, int]:
    if data.frames is None:
        return {}
    tp = data.frames.topics
    return {str(r["name"]): int(r["max_gap_ns"]) for _, r in tp.iterrows()
            if r["type"] in IMAGE_TYPES}


def _keyframes(a: RunData, b: RunData, moments: Sequence[Moment]
               ) -> tuple[list[PairRow], str | None]:
    gaps_a, gaps_b = _gaps(a), _gaps(b)
    topics = sorted(set(gaps_a) | set(gaps_b))
    if not moments or not topics:
        return [], None
    targets = [round(m.t_s * 1e9) for m in moments]
    try:
        fa = nearest_images(a.run_dir / "bag", targets, max_gap_ns=gaps_a) if gaps_a else {}
        fb = nearest_images(b.run_dir / "bag", targets, max_gap_ns=gaps_b) if gaps_b else {}
    except Exception as err:  # a damaged chunk costs the images, not the page
        return [], f"camera keyframes could not be read: {err}"
    rows = []
    for m, target in zip(moments, targets, strict=True):
        side_a = {topic: (ts, px) for topic, ts, px in fa.get(target, [])}
        side_b = {topic: (ts, px) for topic, ts, px in fb.get(target, [])}
        pairs = []
        for topic in sorted(set(side_a) | set(side_b)):
            ka = kb = None
            if topic in side_a:
                ts, px = side_a[topic]
                ka = Keyframe(topic, ts, target, px.shape[1], px.shape[0], encode_png(px))
            if topic in side_b:
                ts, px = side_b[topic]
                kb = Keyframe(topic, ts, target, px.shape[1], px.shape[0], encode_png(px))
            diff = (_difference(side_a[topic][1], side_b[topic][1])
                    if ka is not None and kb is not None else None)
            pairs.append(Pair(topic, ka, kb, data_uri(diff[0]) if diff else None,
                              diff[1] if diff else 0, diff[2] if diff else 0))
        if pairs:
            rows.append(PairRow(m, tuple(pairs)))
    return rows, None


_STATUS_TEXT = {"identical": "identical", "within_tolerance": "within tolerance",
                "differs": "differs", "only_in_a": "only in A", "only_in_b": "only in B"}
_ORDER = {"differs": 0, "only_in_a": 1, "only_in_b": 1, "within_tolerance": 2, "identical": 3}


def _topic_row(t: TopicDiff) -> dict[str, Any]:
    d = t.first_beyond or t.first
    first = "" if d is None else (f"#{d.index} at {d.t_ns / 1e9:.3f} s: {d.path}: {d.detail}")
    worst = max(t.fields, key=lambda f: (not f.within, f.max_abs), default=None)
    largest = "" if worst is None else f"{worst.path}: {worst.max_abs:.4g} (RMS {worst.rms:.3g})"
    return {"name": t.name, "type": t.msgtype, "count_a": t.count_a, "count_b": t.count_b,
            "status": t.status, "status_text": _STATUS_TEXT[t.status],
            "differ": "—" if t.messages_differ is None else t.messages_differ,
            "first": first, "largest": largest}


def _run_info(r: Any, data: RunData | None) -> list[tuple[str, str]]:
    sim = f"{r.simulated_s:.1f} s" if r.simulated_s is not None else "?"
    out = [("run directory", str(r.path)), ("scenario", r.scenario), ("seed", str(r.seed)),
           ("verdict", r.verdict), ("simulated", sim), ("digest", r.digest[:16])]
    if r.replay is not None:
        out.insert(1, ("replay", r.replay))
    if data is not None and data.summary.get("systems_under_test"):
        out.append(("systems under test", ", ".join(data.summary["systems_under_test"])))
    return out


def _run_videos(data: RunData, key: str, page: Path) -> tuple[VideoSet | None, str | None]:
    """The run's report videos, or (none there) its bag's encoded beside the page."""
    found = read_videos(data.run_dir)
    if found is not None or not (data.run_dir / "bag").is_dir():
        return found, None
    try:
        return write_videos(data.run_dir / "bag", page.parent / f"{page.name}.video" / key), \
            None
    except SrrError as err:
        return None, f"camera videos: {err}"


def render_diff(result: DiffResult, *, data_a: RunData | None = None,
                data_b: RunData | None = None, page: Path | None = None,
                videos: tuple[VideoSet | None, VideoSet | None] = (None, None)) -> str:
    """The HTML text of the comparison page. ``data_a`` / ``data_b`` (what
    :func:`load_run` gives) are read from the run directories when not passed. ``videos``:
    A's and B's camera videos, linked relative to ``page`` (the page's path)."""
    a = data_a if data_a is not None else load_run(result.a.path)
    b = data_b if data_b is not None else load_run(result.b.path)
    moments = diff_moments(result, a, b)
    runs = [(a, BASELINE), (b, CANDIDATE)]
    panels = [p for p in time_panels(runs, moments=moments)]
    has_map = a.scenario is not None and bool(a.tracks or b.tracks)
    kf_rows, kf_problem = _keyframes(a, b, moments)
    problems = [f"A: {p}" for p in a.problems] + [f"B: {p}" for p in b.problems]
    if kf_problem:
        problems.append(kf_problem)
    notes = list(result.notes)
    topics = sorted(result.topics, key=lambda t: (_ORDER[t.status], t.name))
    fields = [{"topic": t.name, "path": f.path, "n_values": f.values, "differ": f.differ,
               "beyond": f.beyond, "max_abs": f"{f.max_abs:.4g}", "rms": f"{f.rms:.4g}",
               "at": f"#{f.at_index} at {f.at_ns / 1e9:.3f} s",
               "tolerance": f.tolerance.describe() if f.tolerance else "none",
               "within": f.within}
              for t in topics for f in t.fields]
    metrics = [{"name": m.name, "a": fmt_value(m.value_a, m.unit),
                "b": fmt_value(m.value_b, m.unit),
                "delta": fmt_value(m.delta, m.unit if m.unit != "bool" else "", signed=True),
                "tolerance": f"±{m.tolerance:.3g}", "status": m.status,
                "direction": {"lower": "lower is better", "higher": "higher is better"}.get(
                    m.direction, ""),
                "better": {"A": "A (baseline)", "B": "B (candidate)"}.get(m.better, "—")}
               for m in result.metrics]
    counts = [f"{n} {text}" for s, text in _STATUS_TEXT.items()
              if (n := sum(t.status == s for t in result.topics))]
    counts = [c.replace(" differs", " different") for c in counts]
    moved = sum(m.status != "ok" for m in result.metrics)
    if result.metrics:
        counts.append(f"{moved} of {len(result.metrics)} metrics moved beyond tolerance")
    sets = [(k, f"{k.upper()}: ", vs) for k, vs in zip("ab", videos, strict=True)
            if vs is not None]
    cursor = cursor_context(max(a.end_s, b.end_s), map_tracks(runs) if has_map else [], sets,
                            (page or Path("diff.html")).absolute().parent)
    cursor["videos"].sort(key=lambda v: (v["topic"], v["run"]))  # each camera: A beside B
    toc = [("runs", "Runs")]
    if cursor["videos"]:
        toc.append(("video", "Video"))
    toc += [("topics", "Topics"), ("metrics", "Metrics")]
    if has_map:
        toc.append(("map", "Map"))
    if kf_rows:
        toc.append(("cameras", "Cameras"))
    if panels:
        toc.append(("timeseries", "Time series"))
    toc.append(("fields", "Numeric differences"))
    ctx = {
        "verdict": result.verdict,
        "verdict_text": result.verdict.replace("_", " "),
        "exit_code": result.exit_code,
        "a": result.a,
        "b": result.b,
        "counts": counts,
        "first": result.first_divergence,
        "toc": toc,
        "problems": problems,
        "notes": notes,
        "replay_notes": list(result.replay_notes),
        "changes": list(result.changes),
        "runs": [{"key": st.key, "label": st.label, "color": st.color,
                  "info": _run_info(r, d)}
                 for r, d, st in ((result.a, a, BASELINE), (result.b, b, CANDIDATE))],
        "tolerances": [t.spec for t in result.tolerances],
        "topics": [_topic_row(t) for t in topics],
        "metrics": [m for m in metrics if m["status"] != "ok"],
        "metrics_ok": [m for m in metrics if m["status"] == "ok"],
        "n_metrics": len(metrics),
        "map_svg": Markup(map_svg(runs, moments=moments)) if has_map else "",
        "map_legend": map_legend(runs) if has_map else [],
        "moments": moments,
        "keyframes": kf_rows,
        "panels": [{"key": p.key, "group": p.group, "title": p.title, "svg": Markup(p.svg),
                    "legend": p.legend, "note": p.note, "highlight": ""} for p in panels],
        "cursor": cursor,
        "fields": fields[:MAX_FIELDS],
        "fields_more": max(0, len(fields) - MAX_FIELDS),
        "srr_version": __version__,
    }
    return template("diff.html").render(**ctx)


def write_diff(result: DiffResult, path: str | Path, *, video: bool = True) -> Path:
    """Render the page and write it to ``path`` atomically, with both runs' camera videos
    (``video=False``: none); returns the path."""
    path = Path(path)
    a, b = load_run(result.a.path), load_run(result.b.path)
    videos: tuple[VideoSet | None, VideoSet | None] = (None, None)
    if video:
        (va, pa), (vb, pb) = _run_videos(a, "a", path), _run_videos(b, "b", path)
        videos = (va, vb)
        a.problems.extend([pa] if pa else [])
        b.problems.extend([pb] if pb else [])
    write_text_atomic(path, render_diff(result, data_a=a, data_b=b, page=path,
                                        videos=videos))
    return path
