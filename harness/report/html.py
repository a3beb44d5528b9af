"""``report.html``: one self-contained page per run for the reviewer.

Top of the page (what a 1280×900 window shows first): the verdict banner with its reasons,
the table of what regressed (or failed, or which health gate tripped) with the sim-time
windows that explain each value, and the time-series panels of the regressed metrics' group
with those windows outlined. Below: the top-down map with the numbered moments, camera
keyframes at those moments, the other time series, every metric, the health gates, the
action graphs, the topic table, versions and the command to reproduce the run, and the
resolved scenario.

Each camera's recording plays in the page (:mod:`harness.report.video`: WebM files in
``video/`` beside the page, linked relatively) under one time cursor shared with every time
series and the map (a small inline script, ``templates/cursor.js``); short clips around the
regressed or failing metrics' windows and the moments are listed right under the summary.
Otherwise the page loads nothing: plots are inline SVG, keyframes base64 PNG (kept for
printing and for runs without cameras), CSS inline.
"""

from __future__ import annotations

import json
import os
import shlex
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from markupsafe import Markup

from harness import __version__
from harness.atomic import write_text_atomic
from harness.errors import SrrError
from harness.frames import Frames
from harness.metrics.safety import NEAR_AT
from harness.regression.verdict import GOAL_REACHED, GOAL_REACHED_AT
from harness.report.data import RunData, load_run, metric_windows
from harness.report.graphs import GRAPHS_JSON, RunGraphs, graph_diagrams, read_graphs
from harness.report.images import IMAGE_TYPES, Keyframe, keyframes
from harness.report.plots import (
    Highlight,
    Panel,
    RunStyle,
    map_legend,
    map_svg,
    map_tracks,
    time_panels,
)
from harness.report.templates import template
from harness.report.video import (
    CLIP_PAD_S,
    MAX_CLIP_S,
    MAX_CLIPS,
    ClipSpec,
    VideoSet,
    remove_videos,
    write_videos,
)
from harness.scenario import Scenario
from harness.summary import recording_note, replay_note, versions_note

__all__ = ["GraphRebuild", "clip_specs", "cursor_context", "fmt_value", "fmt_windows",
           "render_report", "write_report"]

#: The action graphs of a run directory without ``graphs.json``, from its scenario, summary
#: and directory (``harness.api`` builds the scene again; the report itself never does).
GraphRebuild = Callable[[Scenario, Mapping[str, Any], Path], RunGraphs]

REPORT_NAME = "report.html"
MAX_REASONS = 3


def fmt_value(v: Any, unit: str = "", *, signed: bool = False) -> str:
    """A metric value for people: 4 significant digits, the unit, "—" when undefined."""
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if not isinstance(v, (int, float)):
        return str(v)
    if unit == "bool" and not signed:
        return "yes" if v >= 0.5 else "no"
    if signed and v == 0:
        return "0"
    text = f"{v:+.4g}" if signed else f"{v:.4g}"
    if unit == "count" and float(v).is_integer():
        text = f"{int(v):+d}" if signed else f"{int(v)}"
    suffix = {"": "", "ratio": "", "count": "", "bool": ""}.get(unit, f" {unit}")
    return text + suffix


def fmt_windows(ws: Sequence[tuple[float, float]], limit: int = 3) -> str:
    """``20.53–22.05, @7.42 +2 more`` (a point window is ``@t``)."""
    parts = []
    for a, b in list(ws)[:limit]:
        parts.append(f"@{a:.2f}" if abs(b - a) < 1e-9 else f"{a:.2f}–{b:.2f}")
    more = len(ws) - limit
    return ", ".join(parts) + (f" +{more} more" if more > 0 else "")


def window_links(ws: Sequence[tuple[float, float]], limit: int = 3) -> dict[str, Any] | None:
    """The windows of :func:`fmt_windows` as links the page's cursor seeks to (their start)."""
    if not ws:
        return None
    links = [{"text": f"@{a:.2f}" if abs(b - a) < 1e-9 else f"{a:.2f}–{b:.2f}", "t": a}
             for a, b in list(ws)[:limit]]
    return {"links": links, "more": max(0, len(ws) - limit)}


def _human_bytes(n: Any) -> str:
    if not isinstance(n, (int, float)):
        return str(n)
    for unit in ("B", "kB", "MB", "GB"):
        if abs(n) < 1000 or unit == "GB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1000.0
    return str(n)


def _group(name: str, data: RunData) -> str:
    m = data.metric(name)
    if m and m.get("group"):
        return str(m["group"])
    return name.split(".", 1)[0]


@dataclass
class _Headline:
    kind: str  # regressions | failures | health | mismatch | changes | none
    rows: list[Any] = field(default_factory=list)
    text: str = ""
    metrics: list[str] = field(default_factory=list)


def _comparison_row(e: dict[str, Any], data: RunData) -> dict[str, Any]:
    unit = str(e.get("unit", ""))
    m = data.metric(e["name"]) or {}
    direction = e.get("direction")
    return {
        "name": e["name"],
        "value": fmt_value(e.get("value"), unit),
        "baseline": fmt_value(e.get("baseline"), unit),
        "delta": fmt_value(e.get("delta"), unit if unit != "bool" else "", signed=True),
        "tolerance": "±" + f"{e.get('tolerance', 0):.3g}",
        "status": e.get("status", ""),
        "status_text": str(e.get("status", "")).replace("_", " "),
        "better": {"lower": "lower is better", "higher": "higher is better"}.get(
            str(direction), ""),
        "when": fmt_windows(metric_windows(e["name"], data)),
        "windows": window_links(metric_windows(e["name"], data)),
        "detail": m.get("detail", ""),
    }


def _failing(m: dict[str, Any]) -> bool:
    v = m.get("value")
    return (m.get("verdict") == "FAIL"
            or (m.get("name") == "safety.match_rate" and v is not None and v < NEAR_AT)
            or (GOAL_REACHED.match(str(m.get("name"))) is not None and v is not None
                and v < GOAL_REACHED_AT))


def _metric_row(m: dict[str, Any], data: RunData) -> dict[str, Any]:
    return {
        "name": m["name"],
        "value": fmt_value(m.get("value"), str(m.get("unit", ""))),
        "verdict": m.get("verdict") or "",
        "detail": m.get("detail", ""),
        "when": fmt_windows(metric_windows(m["name"], data)),
        "windows": window_links(metric_windows(m["name"], data)),
        "failing": _failing(m),
    }


def _headline(data: RunData) -> _Headline:
    s = data.summary
    verdict = s.get("verdict")
    comparison = s.get("comparison") or []
    if verdict == "INVALID":
        rows = [h for h in s.get("health", []) if not h.get("ok")]
        if rows:
            return _Headline("health", rows)
    if verdict == "MISMATCH":
        return _Headline("mismatch", list((s.get("baseline") or {}).get(
            "config_differences", [])))
    if verdict == "INTERRUPTED":  # a shorter run's scores say nothing against a whole one's
        return _Headline("none", text="The run was interrupted: the scores cover the recorded "
                                      "part only and are not judged against the baseline.")
    regressed = [e for e in comparison if e.get("status") in ("regressed", "missing")]
    if regressed:
        return _Headline("regressions", [_comparison_row(e, data) for e in regressed],
                         metrics=[e["name"] for e in regressed])
    failing = [m for m in s.get("metrics", []) if _failing(m)]
    if failing:
        return _Headline("failures", [_metric_row(m, data) for m in failing],
                         metrics=[m["name"] for m in failing])
    notable = [e for e in comparison if e.get("status") in ("improved", "changed", "new")]
    if notable:
        return _Headline("changes", [_comparison_row(e, data) for e in notable])
    n_gates = len(s.get("health", []))
    if comparison:
        text = (f"All {len(comparison)} metrics within tolerance of the baseline; "
                f"{n_gates} health gates ok.")
    elif s.get("metrics"):
        text = "No baseline to compare with: the metric values are listed below."
    elif verdict == "RECORDED":
        text = (f"Recorded on purpose (scoring.record_only): nothing is scored or compared; "
                f"{n_gates} health gates ok.")
    else:
        text = "This scenario scores no metrics; health gates below."
    return _Headline("none", text=text)


def _highlights(data: RunData, names: Sequence[str]) -> dict[str, Highlight]:
    out: dict[str, Highlight] = {}
    for name in names:
        group = _group(name, data)
        if group in out:
            continue
        ws = metric_windows(name, data)
        if ws:
            m = data.metric(name) or {}
            out[group] = Highlight(f"{name} = {fmt_value(m.get('value'), m.get('unit', ''))}",
                                   tuple(ws))
    return out


def _graphs(data: RunData, rebuild: GraphRebuild | None) -> tuple[list[Any], str, str | None]:
    """(diagrams, mermaid text, problem): the graphs the run wrote into its directory; for a
    run directory from before srr wrote them, ``rebuild``'s (the caller's, which may build
    the scene again), or none and a note saying so."""
    try:
        found = read_graphs(data.run_dir)
        if found is None:
            if data.scenario is None:
                return [], "", None
            if rebuild is None:
                return [], "", (f"action graphs: this run directory has no {GRAPHS_JSON} "
                                "(written by runs since srr recorded its graphs)")
            try:
                found = rebuild(data.scenario, data.summary, data.run_dir)
            except Exception as err:  # a plug-in that no longer imports must not hide the report
                return [], "", f"action graphs could not be rebuilt: {err}"
        stage = found.stage()
    except (OSError, ValueError) as err:  # a damaged graphs file costs the graphs, not the report
        return [], "", f"{data.run_dir / GRAPHS_JSON}: could not be read: {err}"
    return graph_diagrams(stage), found.mermaid, None


@dataclass
class _KfRow:
    moment: Any
    frames: list[Keyframe]


def _keyframes(data: RunData) -> tuple[list[_KfRow], str | None]:
    if not data.moments or data.frames is None:
        return [], None
    tp = data.frames.topics
    gaps = {str(r["name"]): int(r["max_gap_ns"]) for _, r in tp.iterrows()
            if r["type"] in IMAGE_TYPES}
    if not gaps:
        return [], None
    targets = [round(m.t_s * 1e9) for m in data.moments]
    try:
        found = keyframes(data.run_dir / "bag", targets, max_gap_ns=gaps)
    except Exception as err:  # a damaged chunk costs the images, not the report
        return [], f"camera keyframes could not be read: {err}"
    rows = [_KfRow(m, found.get(t, [])) for m, t in zip(data.moments, targets, strict=True)]
    if not any(r.frames for r in rows):
        return [], None
    return rows, None


def _panel_ctx(p: Panel, hl: dict[str, Highlight]) -> dict[str, Any]:
    h = hl.get(p.group)
    return {"key": p.key, "group": p.group, "title": p.title, "svg": Markup(p.svg),
            "legend": p.legend, "note": p.note, "highlight": h.label if h else ""}


#: The two runs of the "against the baseline" section.
REFERENCE_STYLE = RunStyle("a", "baseline", "#2563eb", "#92400e")
THIS_RUN_STYLE = RunStyle("b", "this run", "#ea580c", "#be185d")


def _against(data: RunData) -> dict[str, Any] | None:
    """Both runs on one map and overlaid time series, the baseline drawn from its reference
    recording (None when there is none to compare with)."""
    ref = data.reference
    if ref is None or not ref.tracks or not data.tracks:
        return None
    pair = [(ref, REFERENCE_STYLE), (data, THIS_RUN_STYLE)]
    return {"map_svg": Markup(map_svg(pair)), "map_legend": map_legend(pair),
            "panels": [_panel_ctx(p, {}) for p in time_panels(pair)],
            "file": ref.run_dir.name}


def _exact_command(data: RunData) -> str:
    """Re-run from the resolved scenario of the run directory: includes, defaults and every
    ``--set`` override are already in it."""
    s = data.summary
    run_dir = data.run_dir
    parts = ["srr", "run", str(run_dir / "scenario.yaml"), "--seed", str(s.get("seed", 0)),
             "--out", f"{run_dir}-rerun"]
    base = s.get("baseline")
    if base and base.get("path"):
        parts += ["--baselines", str(Path(str(base["path"])).parent)]
    return " ".join(shlex.quote(p) for p in parts)


def clip_specs(data: RunData) -> list[ClipSpec]:
    """What the report's clips show, most important first: each window of the regressed
    (or failing) metrics, then each moment; :data:`CLIP_PAD_S` before and after, at most
    :data:`MAX_CLIP_S` long, at most :data:`MAX_CLIPS`, none twice."""
    end = data.end_s
    out: list[ClipSpec] = []
    seen: set[tuple[float, float]] = set()

    def add(label: str, at: float, a: float, b: float, kind: str) -> None:
        start = max(0.0, a - CLIP_PAD_S)
        stop = min(end, max(b, a) + CLIP_PAD_S, start + MAX_CLIP_S)
        key = (round(start, 2), round(stop, 2))
        if stop > start and key not in seen and len(out) < MAX_CLIPS:
            seen.add(key)
            out.append(ClipSpec(label, at, start, stop, kind))

    names: dict[tuple[float, float], list[str]] = {}  # window → the metrics it explains
    for name in _headline(data).metrics:
        for w in metric_windows(name, data)[:3]:
            names.setdefault(w, []).append(name)
    for (a, b), ms in names.items():
        when = f"@{a:.2f} s" if abs(b - a) < 1e-9 else f"{a:.2f}–{b:.2f} s"
        more = f" +{len(ms) - 1} more" if len(ms) > 1 else ""
        add(f"{ms[0]}{more} {when}", a, a, b, "metric")
    for m in data.moments:
        add(f"M{m.number} {m.t_s:.2f} s — {m.label}", m.t_s, m.t_s, m.t_s, "moment")
    return out


def _safe_json(value: Any) -> Markup:
    """JSON for an inline ``<script type="application/json">`` (``</`` cannot end it)."""
    return Markup(json.dumps(value, separators=(",", ":")).replace("</", "<\\/"))


def cursor_context(end_s: float, tracks: list[dict[str, object]],
                   videos: Sequence[tuple[str, str, VideoSet]], page_dir: Path
                   ) -> dict[str, Any]:
    """What the time cursor's bar and script need: the time axis's end, the map's tracks
    and each run's videos — ``(run key, label prefix, VideoSet of the run's folder)`` with
    the files linked relative to ``page_dir`` (``/``-separated, so ``file://`` finds them)."""
    items = []
    for run, prefix, vs in videos:
        for v in vs.videos:
            src = Path(os.path.relpath(vs.path(v), page_dir)).as_posix()
            items.append({"src": src, "t0_s": v.t0_s, "topic": v.topic, "run": run,
                          "width": v.width, "height": v.height,
                          "label": f"{prefix}{v.topic} · {v.frames} frames"})
    return {"end_s": end_s, "videos": items, "tracks_json": _safe_json(tracks)}


def _clips(videos: VideoSet | None) -> list[dict[str, Any]]:
    if videos is None:
        return []
    return [{"label": c.spec.label, "kind": c.spec.kind, "at": c.spec.at_s,
             "start": c.spec.start_s, "end": c.spec.end_s,
             "files": [{"href": f.file, "topic": f.topic, "bytes": _human_bytes(f.bytes)}
                       for f in c.files]} for c in videos.clips]


def render_report(run_dir: str | Path, *, summary: dict[str, Any] | None = None,
                  scenario: Scenario | None = None, frames: Frames | None = None,
                  rebuild_graphs: GraphRebuild | None = None,
                  videos: VideoSet | None = None) -> str:
    """The HTML text of a run directory's report.

    ``summary``, ``scenario`` and ``frames`` may be passed when the caller already has them
    (``run_scenario`` does); otherwise they are read from ``run_dir``. The action graphs are
    the run's ``graphs.json``; for a run directory without one, ``rebuild_graphs`` (given by
    :mod:`harness.api`, which can build the scene) supplies them, or the page says they are
    missing. ``videos``: the run's videos (:func:`write_report` writes them), played in the
    page; None: none. Raises :class:`SrrError` when ``run_dir`` is not a run directory."""
    # resolved: the page names the run directory the same however it was spelt (a
    # re-render from another directory writes the same bytes)
    data = load_run(Path(run_dir).resolve(), summary=summary, scenario=scenario, frames=frames)
    return _render(data, rebuild_graphs, videos, [])


def _render(data: RunData, rebuild_graphs: GraphRebuild | None, videos: VideoSet | None,
            video_problems: list[str]) -> str:
    s = data.summary
    verdict = str(s.get("verdict", "INVALID"))
    head = _headline(data)
    # the group with the most regressed (or failing) metrics first, then first come
    # the group with the most regressed (or failing) metrics first, then a group whose
    # metrics point at moments in time, then first come
    groups = [_group(name, data) for name in head.metrics]
    timed = {_group(n, data) for n in head.metrics if metric_windows(n, data)}
    focus_groups = sorted(dict.fromkeys(groups), key=lambda g: (
        -groups.count(g), g not in timed, groups.index(g)))
    hl = _highlights(data, head.metrics)
    panels = time_panels(data, hl)
    focus = [p for g in focus_groups for p in panels if p.group == g]
    others = [p for p in panels if p not in focus]
    graphs, mermaid, graph_problem = _graphs(data, rebuild_graphs)
    kf_rows, kf_problem = _keyframes(data)
    problems = list(data.problems) + [p for p in (graph_problem, kf_problem) if p] \
        + video_problems

    reasons = [str(r) for r in s.get("reasons", [])]
    baseline = s.get("baseline")
    meta = [f"seed {s.get('seed', '?')}", f"{float(s.get('simulated_s') or 0):.1f} s simulated"]
    replay = replay_note(s)
    if replay is not None:
        meta.insert(0, replay)
    if s.get("duration_s") and s.get("simulated_s") is not None and \
            abs(float(s["duration_s"]) - float(s["simulated_s"])) > 1e-6:
        meta[-1] += f" of {float(s['duration_s']):g} s"
    if baseline:
        meta.append(f"baseline {Path(str(baseline.get('path', ''))).stem}, blessed "
                    f"{str(baseline.get('blessed_at', ''))[:10]} by "
                    f"{baseline.get('blessed_by', '?')}")
        meta.append(recording_note(s) or "")
    no_baseline = ""
    if not baseline and s.get("metrics"):
        no_baseline = next((r for r in reasons if "baseline" in r), "")
        reasons = [r for r in reasons if r != no_baseline]
    toc = [("headline", "Summary")]
    clips = _clips(videos)
    if clips:
        toc.append(("clips", "Clips"))
    if videos is not None:
        toc.append(("video", "Video"))
    if focus:
        toc.append(("focus", "In time"))
    if data.scenario is not None and data.tracks:
        toc.append(("map", "Map"))
    against = _against(data)
    if against:
        toc.append(("against", "Against the baseline"))
    if kf_rows:
        toc.append(("cameras", "Cameras"))
    if others:
        toc.append(("timeseries", "Time series"))
    toc += [("metrics", "All metrics"), ("health", "Health"), ("graphs", "Action graphs"),
            ("topics", "Topics"), ("run", "Reproduce"), ("scenario", "Scenario")]
    topics = [{"name": name, "type": t.get("type", ""), "count": t.get("count", ""),
               "published": t.get("published", ""),
               "rate": f"{t['rate_hz']:.2f}" if isinstance(t.get("rate_hz"), (int, float))
               else "", "bytes": _human_bytes(t.get("bytes")),
               "durability": t.get("durability", ""), "sha256": str(t.get("sha256", ""))}
              for name, t in sorted((s.get("topics") or {}).items())]
    # each topic's bytes against the baseline's: "same" / "differs" (only when there is a
    # baseline with per-topic digests to say it from)
    differing = set((baseline or {}).get("topics_differing") or ())
    vs_baseline = baseline is not None and (bool(baseline.get("digest_matches"))
                                            or bool(differing))
    for row in topics:
        row["vs_baseline"] = "differs" if row["name"] in differing else "same"
    run_info = [("run directory", str(data.run_dir)),
                ("scenario file", s.get("scenario_file", "")),
                ("seed", s.get("seed", "")),
                ("simulated", f"{s.get('simulated_s', '')} s, {s.get('ticks', '')} ticks at "
                              f"{s.get('tick_hz', '')} Hz"),
                ("ground truth", "on (/gt/*)" if s.get("srr_gt") else "off"),
                ("systems under test", ", ".join(s.get("systems_under_test", [])) or "—"),
                ("recording digest", s.get("digest", ""))]
    if baseline:
        run_info += [("baseline", baseline.get("path", "")),
                     ("baseline blessed", f"{baseline.get('blessed_at', '')} by "
                                          f"{baseline.get('blessed_by', '')}: "
                                          f"{baseline.get('reason', '')}"),
                     ("baseline digest", f"{baseline.get('digest', '')} ("
                      + ("same" if baseline.get("digest_matches") else "differs") + ")")]
        if baseline.get("topics_differing"):
            run_info.append(("topics differing from the baseline's",
                             ", ".join(map(str, baseline["topics_differing"]))))
        differ = versions_note(baseline)
        if differ:
            run_info.append(("versions differing (baseline → run)", differ))
    ctx = {
        "verdict": verdict,
        "exit_code": s.get("exit_code", ""),
        "scenario_name": s.get("scenario", data.run_dir.name),
        "meta": meta,
        "reasons": reasons,
        "reasons_shown": reasons[:MAX_REASONS],
        "reasons_more": max(0, len(reasons) - MAX_REASONS),
        "no_baseline": no_baseline,
        "toc": toc,
        "problems": problems,
        "warnings": [str(w) for w in s.get("warnings", [])],
        "headline": head,
        "n_compared": len(s.get("comparison") or []),
        "focus_panels": [_panel_ctx(p, hl) for p in focus],
        "other_panels": [_panel_ctx(p, hl) for p in others],
        "against": against,
        "map_svg": Markup(map_svg(data)) if data.tracks else "",
        "map_legend": map_legend(data) if data.tracks else [],
        "moments": data.moments,
        "keyframes": kf_rows,
        "clips": clips,
        "cursor": cursor_context(
            data.end_s, map_tracks(data) if data.scenario is not None and data.tracks else [],
            [("", "", videos)] if videos is not None else [], data.run_dir),
        "comparison": [_comparison_row(e, data) for e in s.get("comparison") or []],
        "not_compared": all(isinstance(e, dict) and e.get("status") == "not_compared"
                            for e in s.get("comparison") or []),
        "metrics": [_metric_row(m, data) for m in s.get("metrics", [])],
        "health": s.get("health", []),
        "health_ok": sum(bool(h.get("ok")) for h in s.get("health", [])),
        "graphs": [{"path": g.path, "svg": Markup(g.svg)} for g in graphs],
        "graph_paths": s.get("graphs", []) if not graphs else [],
        "mermaid": mermaid,
        "topics": topics, "topics_vs_baseline": vs_baseline,
        "command": s.get("command", ""),
        "command_exact": _exact_command(data),
        "run_info": run_info,
        "versions": sorted((s.get("versions") or {}).items()),
        "scenario_text": data.scenario_text,
        "scenario_lines": data.scenario_text.count("\n"),
        "srr_version": __version__,
        "run_dir": str(data.run_dir),
    }
    return template("report.html").render(**ctx)


def write_report(run_dir: str | Path, *, summary: dict[str, Any] | None = None,
                 scenario: Scenario | None = None, frames: Frames | None = None,
                 rebuild_graphs: GraphRebuild | None = None, video: bool = True) -> Path:
    """Render and write ``<run_dir>/report.html`` (atomically), with the camera videos and
    clips in ``<run_dir>/video/`` (written first; ``video=False``, or a bag without camera
    images: none, and an old ``video/`` folder is removed). A bag whose images cannot be
    encoded costs the videos, not the report: the page says why. Returns the page's path."""
    run_dir = Path(run_dir)
    data = load_run(run_dir, summary=summary, scenario=scenario, frames=frames)
    videos: VideoSet | None = None
    problems: list[str] = []
    if video and (run_dir / "bag").is_dir():
        rates = {name: float(t["rate_hz"]) for name, t in
                 (data.summary.get("topics") or {}).items()
                 if isinstance(t, dict) and isinstance(t.get("rate_hz"), (int, float))}
        try:
            videos = write_videos(run_dir / "bag", run_dir, clip_specs(data), rates_hz=rates)
        except SrrError as err:
            problems.append(f"camera videos: {err}")
    else:
        remove_videos(run_dir)
    text = _render(data, rebuild_graphs, videos, problems)
    path = run_dir / REPORT_NAME
    write_text_atomic(path, text)
    return path
