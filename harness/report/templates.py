"""Jinja2 templates and the stylesheet of the HTML report and the suite page.

They live in a Python module (not loose files) so that they ship with the package whatever
installs it. Autoescaping is on: every value is text unless wrapped in ``Markup`` (the SVGs
the report builds itself).
"""

from __future__ import annotations

__all__ = ["CSS", "MACROS", "REPORT", "SUITE", "VERDICT_COLORS"]

VERDICT_COLORS = {
    "PASS": "#15803d",
    "RECORDED": "#0f766e",
    "FAIL": "#b91c1c",
    "REGRESSED": "#c2410c",
    "INVALID": "#6d28d9",
    "INTERRUPTED": "#475569",
    "UNSCORED": "#a16207",
    "MISMATCH": "#0e7490",
    "FLAKY": "#be185d",
}

CSS = """
:root { --fg:#111827; --muted:#6b7280; --line:#e5e7eb; --bg:#ffffff; --soft:#f8fafc;
  --PASS:#15803d; --FAIL:#b91c1c; --REGRESSED:#c2410c; --INVALID:#6d28d9;
  --INTERRUPTED:#475569; --UNSCORED:#a16207;
  --MISMATCH:#0e7490; --FLAKY:#be185d; --RECORDED:#0f766e; }
* { box-sizing: border-box; }
html, body { margin:0; padding:0; background:var(--bg); color:var(--fg);
  font: 14px/1.4 system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", Arial, sans-serif; }
code, pre, .mono { font-family: ui-monospace, "DejaVu Sans Mono", Menlo, Consolas, monospace;
  font-size: 12.5px; }
.wrap { max-width: 1248px; margin: 0 auto; padding: 0 16px; }
.banner { color:#fff; }
.banner .wrap { display:flex; gap:20px; align-items:flex-start; padding-top:12px;
  padding-bottom:12px; }
.banner.v-PASS { background:var(--PASS); } .banner.v-FAIL { background:var(--FAIL); }
.banner.v-REGRESSED { background:var(--REGRESSED); } .banner.v-INVALID { background:var(--INVALID); }
.banner.v-INTERRUPTED { background:var(--INTERRUPTED); }
.banner.v-UNSCORED { background:var(--UNSCORED); } .banner.v-MISMATCH { background:var(--MISMATCH); }
.banner.v-FLAKY { background:var(--FLAKY); } .banner.v-RECORDED { background:var(--RECORDED); }
.verdict-word { font-size:30px; font-weight:800; letter-spacing:.04em; min-width:210px;
  line-height:1.1; }
.verdict-word small { display:block; font-size:12px; font-weight:500; letter-spacing:0;
  opacity:.9; margin-top:4px; }
.banner h1 { font-size:19px; margin:0 0 2px 0; font-weight:700; }
.banner .meta { margin:0; opacity:.93; font-size:13px; }
.banner ul.reasons { margin:6px 0 0 0; padding-left:18px; font-size:13px; }
.banner ul.reasons li { margin:1px 0; }
.banner .nobaseline { margin-top:6px; background:rgba(255,255,255,.16); padding:4px 8px;
  border-radius:4px; font-size:13px; display:inline-block; }
nav.toc { border-bottom:1px solid var(--line); background:var(--soft); font-size:13px; }
nav.toc .wrap { padding-top:5px; padding-bottom:5px; }
nav.toc a { color:#1d4ed8; text-decoration:none; margin-right:14px; }
section { margin: 14px 0 22px 0; }
h2 { font-size:15px; margin:0 0 6px 0; padding-bottom:3px; border-bottom:2px solid var(--line); }
h2 .count { color:var(--muted); font-weight:500; }
h3 { font-size:13.5px; margin:10px 0 4px 0; }
p.note, .note { color:var(--muted); font-size:12.5px; margin:3px 0; }
table { border-collapse:collapse; width:100%; font-size:13px; }
th, td { text-align:left; padding:3px 8px; border-bottom:1px solid var(--line);
  vertical-align:top; }
th { background:var(--soft); font-weight:600; white-space:nowrap; }
td.num, th.num { text-align:right; font-variant-numeric: tabular-nums; white-space:nowrap; }
td.when { white-space:nowrap; font-variant-numeric: tabular-nums; }
td.name { font-family: ui-monospace, "DejaVu Sans Mono", Menlo, Consolas, monospace;
  font-size:12.5px; white-space:nowrap; }
tr.st-regressed td, tr.st-missing td { background:#fef2f2; }
tr.st-improved td { background:#f0fdf4; }
.badge { display:inline-block; padding:0 7px; border-radius:9px; font-size:12px;
  font-weight:600; line-height:18px; white-space:nowrap; }
.b-regressed, .b-missing, .b-FAIL, .b-tripped { background:#dc2626; color:#fff; }
.b-improved, .b-PASS, .b-okgate { background:#dcfce7; color:#166534; }
.b-ok { background:#f1f5f9; color:#475569; }
.b-changed { background:#dbeafe; color:#1e40af; }
.b-new { background:#fef9c3; color:#854d0e; }
.b-NEAR { background:#fef3c7; color:#92400e; }
.b-v-PASS { background:var(--PASS); color:#fff; } .b-v-FAIL { background:var(--FAIL); color:#fff; }
.b-v-REGRESSED { background:var(--REGRESSED); color:#fff; }
.b-v-INVALID { background:var(--INVALID); color:#fff; }
.b-v-INTERRUPTED { background:var(--INTERRUPTED); color:#fff; }
.b-v-UNSCORED { background:var(--UNSCORED); color:#fff; }
.b-v-MISMATCH { background:var(--MISMATCH); color:#fff; }
.b-v-FLAKY { background:var(--FLAKY); color:#fff; }
.b-v-RECORDED { background:var(--RECORDED); color:#fff; }
.b-not_compared { background:#f1f5f9; color:#64748b; font-style:italic; }
.headline table { font-size:13.5px; }
.headline td, .headline th { padding:2px 8px; }
figure.panel { margin:6px 0 10px 0; }
figure.panel figcaption { font-weight:600; font-size:13.5px; margin:0 0 1px 0; }
figure.panel figcaption .hl-name { font-weight:500; color:#111827; background:#fde68a;
  padding:0 5px; border-radius:3px; margin-left:8px; font-size:12.5px; }
.legend { font-size:12px; color:#374151; margin:0 0 2px 0; }
.legend span.key { margin-right:12px; white-space:nowrap; }
.legend i { display:inline-block; width:14px; height:10px; margin-right:4px;
  vertical-align:-1px; border-radius:2px; }
.legend i.line { height:3px; vertical-align:3px; }
.legend i.dashed { height:0; border-top:2px dashed; vertical-align:3px; background:none !important; }
.legend i.dot { width:8px; height:8px; border-radius:50%; }
.legend i.tri { width:0; height:0; border-left:5px solid transparent; border-right:5px solid
  transparent; border-bottom:9px solid #111827; background:none !important; border-radius:0; }
.legend i.x { width:10px; height:10px; background:none !important; border-radius:0;
  background-image:none; position:relative; }
.legend i.x::before, .legend i.x::after { content:""; position:absolute; left:4px; top:-1px;
  width:2.5px; height:12px; background:#111827; transform:rotate(45deg); }
.legend i.x::after { transform:rotate(-45deg); }
svg.plot, svg.graph-svg { display:block; max-width:100%; height:auto; }
svg text { font-family: system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", Arial, sans-serif; }
svg .grid { stroke:#eef0f3; stroke-width:1; }
svg .axis { stroke:#9ca3af; stroke-width:1; }
svg .tick { font-size:11px; fill:#6b7280; }
svg .axis-label { font-size:11px; fill:#6b7280; }
svg .lane-label { font-size:12px; fill:#111827; font-weight:600; }
svg .lane-sub { font-size:10.5px; fill:#6b7280; }
svg .lane-base { stroke:#d1d5db; stroke-width:1; }
svg .moment-line { stroke:#9ca3af; stroke-width:1; stroke-dasharray:2 3; }
svg .moment-label { font-size:10.5px; fill:#374151; font-weight:700; }
svg .edge-line { stroke:#111827; stroke-width:1; stroke-dasharray:3 2; }
svg .lag-arrow { stroke:#111827; stroke-width:1.6; fill:#111827; }
svg .lag-arrow.never { stroke:#dc2626; fill:#dc2626; }
svg .lag-arrow.head { stroke:none; }
svg .lag-label { font-size:11.5px; fill:#111827; font-weight:600; }
svg .hl-box { fill:none; stroke:#111827; stroke-width:1.5; stroke-dasharray:5 3; }
svg .hl-bracket { fill:none; stroke:#111827; stroke-width:2.5; }
svg .series { fill:none; }
svg .series.dashed { stroke-dasharray:5 3; }
svg .point-label { font-size:11.5px; fill:#111827; font-weight:600; }
svg .point-label, svg .lag-label, svg .moment-label { paint-order:stroke; stroke:#fff;
  stroke-width:3px; stroke-linejoin:round; }
svg.map .map-bg { fill:#fafafa; }
svg.map .floor { fill:#ffffff; stroke:#374151; stroke-width:3; }
svg.map .shelf { fill:#d6d3d1; stroke:#a8a29e; }
svg.map .static { fill:#d6d3d1; stroke:#78716c; stroke-width:1; }
svg.map .trailer { fill:#f5f5f4; stroke:#57534e; stroke-width:2; }
svg.map .roi { fill:#7c3aed; fill-opacity:.12; stroke:#7c3aed; stroke-width:1.5; }
svg.map .area { fill:none; stroke:#0f766e; stroke-width:1.2; stroke-dasharray:6 4; }
svg.map .tripwire { stroke:#dc2626; stroke-width:3; stroke-dasharray:6 3; }
svg.map .tripwire-dir { stroke:#dc2626; stroke-width:1.5; }
svg.map .route { stroke:#cbd5e1; stroke-width:9; stroke-linecap:round; stroke-linejoin:round; }
svg.map .waypoint { fill:#94a3b8; }
svg.map .camera { fill:#111827; }
svg.map .map-label { font-size:11.5px; fill:#374151; }
svg.map .roi-label { fill:#6d28d9; font-weight:600; }
svg.map .trip-label { fill:#b91c1c; font-weight:600; }
svg.map .cam-label { font-size:10.5px; fill:#6b7280; }
svg.map .robot-path { fill:none; stroke-width:2.2; }
svg.map .odom-path { fill:none; stroke-width:1.5; stroke-dasharray:5 4; }
svg.map .worker-path { fill:none; stroke-width:2; }
svg.map .worker-plan { stroke:#92400e; stroke-width:1.2; stroke-dasharray:2 4; }
svg.map .mismatch-path { fill:none; stroke-width:8; stroke-opacity:.55; stroke-linecap:round; }
svg.map .collision { stroke:#111827; stroke-width:3; }
svg.map .moment-leader { stroke:#111827; stroke-width:1; }
svg.map .moment-dot { fill:#111827; stroke:#fff; stroke-width:1.5; }
svg.map .moment-num { font-size:11px; fill:#fff; font-weight:700; }
svg.map .worker-at { fill:#92400e; stroke:#fff; }
svg.map .moment-map { font-size:11px; font-weight:700; fill:#92400e; }
.two-col { display:grid; grid-template-columns: 1fr; gap:8px; }
ol.moments { margin:4px 0; padding-left:0; list-style:none; columns:2; font-size:13px; }
ol.moments li { margin:1px 0; break-inside:avoid; }
ol.moments b { display:inline-block; min-width:30px; }
.kf-grid { display:grid; grid-template-columns: repeat(3, minmax(0, 1fr)); gap:10px; }
.kf-card { border:1px solid var(--line); border-radius:6px; padding:6px 8px; }
.kf-head { font-size:12.5px; margin-bottom:4px; min-height:2.6em; }
.kf-head b { font-size:13.5px; }
.kf-imgs { display:grid; grid-template-columns: repeat(auto-fit, minmax(140px, 1fr)); gap:6px; }
figure.kf { margin:0; }
figure.kf img { display:block; width:100%; height:auto; border:1px solid #d1d5db;
  background:#000; }
figure.kf figcaption { font-size:11px; color:#4b5563; }
.graphs { display:flex; flex-wrap:wrap; gap:10px; }
.graph-card { border:1px solid var(--line); border-radius:6px; padding:6px 8px; background:#fff; }
.graph-card h3 { margin:0 0 4px 0; font-family: ui-monospace, "DejaVu Sans Mono", monospace;
  font-size:12.5px; }
svg .g-node rect { stroke:#64748b; stroke-width:1.2; fill:#f8fafc; }
svg .g-node-event rect { fill:#dcfce7; stroke:#16a34a; }
svg .g-node-data rect { fill:#e0f2fe; stroke:#0284c7; stroke-dasharray:4 2; }
svg .g-name { font-size:12px; font-weight:600; fill:#111827; }
svg .g-type { font-size:10.5px; fill:#6b7280; }
svg .g-edge { fill:none; stroke-width:1.5; }
svg .g-exec { stroke:#111827; fill:#111827; }
svg .g-edge.g-exec { fill:none; }
svg .g-data { stroke:#0284c7; fill:#0284c7; }
svg .g-edge.g-data { stroke-dasharray:4 3; fill:none; }
svg .g-head { stroke:none; }
details { margin:6px 0; }
details > summary { cursor:pointer; color:#1d4ed8; font-size:13px; }
pre { background:var(--soft); border:1px solid var(--line); padding:8px 10px; overflow:auto;
  max-height:560px; margin:4px 0; white-space:pre; }
pre.cmd { max-height:none; white-space:pre-wrap; word-break:break-all; }
dl.kv { display:grid; grid-template-columns: 160px 1fr; gap:2px 12px; margin:4px 0; font-size:13px; }
dl.kv dt { color:var(--muted); } dl.kv dd { margin:0; word-break:break-all; }
.warning { border-left:4px solid #d97706; background:#fffbeb; padding:6px 10px; margin:8px 0;
  font-size:13px; }
.problem { border-left:4px solid #dc2626; background:#fef2f2; padding:6px 10px; margin:8px 0;
  font-size:13px; }
.allgood { background:#f0fdf4; border-left:4px solid #16a34a; padding:6px 10px; font-size:13.5px; }
table.groups-table td.gid, table.groups-table td.params { font-family: ui-monospace,
  "DejaVu Sans Mono", Menlo, Consolas, monospace; font-size:12px; word-break:break-all; }
table.groups-table td.gid { width:22%; } table.groups-table td.params { width:16%; }
table.groups-table td.key { min-width:320px; }
ul.key { margin:0; padding-left:16px; }
ul.runs { margin:0; padding:0; list-style:none; white-space:nowrap; }
ul.runs li { margin:1px 0; }
ul.runs .problem-text { white-space:normal; color:#991b1b; font-size:12.5px; }
.flaky { border-left:4px solid var(--FLAKY); background:#fdf2f8; padding:4px 8px; margin:4px 0;
  font-size:12.5px; }
.flaky table { font-size:12px; width:auto; }
details > summary .badge { margin-right:6px; }
.sweep-grid { display:grid; grid-template-columns: repeat(2, minmax(0, 1fr)); gap:10px 14px; }
figure.sweep-fig { margin:0; border:1px solid var(--line); border-radius:6px; padding:6px 8px; }
figure.sweep-fig figcaption { font-weight:600; font-size:13px; }
figure.sweep-fig figcaption .unit { color:var(--muted); font-weight:500; }
ul.boundaries { margin:2px 0 8px 0; padding-left:18px; font-size:13px; }
svg .dot { stroke-width:1.2; }
svg .mean-line { fill:none; stroke-width:1.8; }
svg .mean { stroke:#111827; stroke-width:2; }
svg .band-PASS { fill:#16a34a; fill-opacity:.10; } svg .band-NEAR { fill:#f59e0b; fill-opacity:.16; }
svg .band-FAIL { fill:#dc2626; fill-opacity:.10; }
svg .band-label { font-size:10.5px; font-weight:600; fill:#6b7280; }
svg .threshold { stroke:#6b7280; stroke-width:1; stroke-dasharray:4 3; }
svg .tol-band { fill:#64748b; fill-opacity:.16; stroke:none; }
svg .baseline-line { fill:none; stroke:#64748b; stroke-width:1.2; stroke-dasharray:5 3; }
svg .boundary { stroke:#111827; stroke-width:1.5; stroke-dasharray:3 3; }
svg .boundary-label { font-size:10.5px; font-weight:700; fill:#111827; paint-order:stroke;
  stroke:#fff; stroke-width:3px; }
table.history td { vertical-align:middle; }
table.history td:first-child { width:300px; } table.history td:nth-child(2) { width:300px; }
table.history td:nth-child(3) { width:200px; }
svg.spark .spark-line { fill:none; stroke:#475569; stroke-width:1.4; }
svg.spark .night { fill:#475569; }
svg.spark .night.missing { fill:#fff; stroke:#9ca3af; stroke-width:1; }
svg.spark .night.tonight { stroke:#111827; stroke-width:1.5; }
svg.spark .strip-cell { stroke:#fff; stroke-width:1; }
svg.spark .strip-cell.tonight { stroke:#111827; stroke-width:1.5; }
.hist-note { color:#92400e; font-size:12.5px; }
footer { color:var(--muted); font-size:12px; padding:16px 0 28px 0; }
"""

REPORT = """<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{{ verdict }} · {{ scenario_name }} · srr report</title>
<style>{{ css }}</style>
</head>
<body>
<header class="banner v-{{ verdict }}" id="verdict" data-verdict="{{ verdict }}">
 <div class="wrap">
  <div class="verdict-word">{{ verdict }}<small>exit code {{ exit_code }}</small></div>
  <div class="banner-main">
   <h1>{{ scenario_name }}</h1>
   <p class="meta">{{ meta | join(" · ") }}</p>
   {% if reasons %}<ul class="reasons">
    {% for r in reasons_shown %}<li>{{ r }}</li>{% endfor %}
    {% if reasons_more %}<li>… and {{ reasons_more }} more (table below)</li>{% endif %}
   </ul>{% endif %}
   {% if no_baseline %}<div class="nobaseline">No baseline: metric values only, nothing
    compared — {{ no_baseline }}</div>{% endif %}
  </div>
 </div>
</header>
<nav class="toc"><div class="wrap">
 {% for id, label in toc %}<a href="#{{ id }}">{{ label }}</a>{% endfor %}
</div></nav>
<main class="wrap">
{% for p in problems %}<div class="problem report-problem">{{ p }}</div>{% endfor %}
{% for w in warnings %}<div class="warning wiring-warning">wiring: {{ w }}</div>{% endfor %}

<section id="headline" class="headline">
{% if headline.kind == "regressions" %}
 <h2>Regressed metrics <span class="count">({{ headline.rows | length }} of {{ n_compared }}
  compared with the baseline)</span></h2>
 {{ comparison_table(headline.rows, "headline-table") }}
{% elif headline.kind == "failures" %}
 <h2>Failing criteria <span class="count">({{ headline.rows | length }})</span></h2>
 {{ metric_table(headline.rows, "headline-table") }}
{% elif headline.kind == "health" %}
 <h2>Tripped health gates <span class="count">({{ headline.rows | length }}): the scores of
  this run cannot be trusted</span></h2>
 <table class="headline-table"><thead><tr><th>gate</th><th>detail</th></tr></thead><tbody>
 {% for h in headline.rows %}<tr class="st-regressed"><td class="name">{{ h.name }}</td>
  <td>{{ h.detail }}</td></tr>{% endfor %}
 </tbody></table>
{% elif headline.kind == "mismatch" %}
 <h2>Not compared: the baseline was recorded with another configuration <span class="count">
  ({{ headline.rows | length }} differing field(s); the metrics below are this run's alone)</span></h2>
 <ul class="mismatch">{% for d in headline.rows %}<li><code>{{ d }}</code></li>{% endfor %}</ul>
 <p>Bless a baseline for this configuration (<code>--update-baseline</code>) if the change is intended.</p>
{% elif headline.kind == "changes" %}
 <h2>Changes against the baseline <span class="count">(none regressed; {{ n_compared }}
  compared)</span></h2>
 {{ comparison_table(headline.rows, "headline-table") }}
{% else %}
 <div class="allgood">{{ headline.text }}</div>
{% endif %}
</section>

{% if focus_panels %}
<section id="focus">
 {% for p in focus_panels %}{{ panel(p) }}{% endfor %}
</section>
{% endif %}

{% if map_svg %}
<section id="map">
 <h2>Top-down map <span class="count">(world frame, metres)</span></h2>
 <div class="legend">{{ legend_keys(map_legend, ".35") }}</div>
 {{ map_svg }}
 {% if moments %}<ol class="moments">
  {% for m in moments %}<li><b>M{{ m.number }}</b> {{ "%.2f" | format(m.t_s) }} s — {{ m.label }}</li>{% endfor %}
 </ol>{% endif %}
</section>
{% endif %}

{% if against %}
<section id="against">
 <h2>Against the baseline <span class="count">(the baseline drawn from its reference recording
  {{ against.file }}; same scenario, same time axis)</span></h2>
 <div class="legend">{{ legend_keys(against.map_legend, ".35") }}</div>
 {{ against.map_svg }}
 {% for p in against.panels %}{{ panel(p) }}{% endfor %}
</section>
{% endif %}

{% if keyframes %}
<section id="cameras">
 <h2>Camera keyframes <span class="count">(nearest recorded image to each moment)</span></h2>
 <div class="kf-grid">
 {% for row in keyframes %}
  <div class="kf-card" id="kf-m{{ row.moment.number }}"><div class="kf-head"><b>M{{ row.moment.number }}</b>
   · {{ "%.2f" | format(row.moment.t_s) }} s — {{ row.moment.label }}</div>
   <div class="kf-imgs">
   {% for k in row.frames %}<figure class="kf"><img src="{{ k.uri }}" width="{{ k.width }}"
     height="{{ k.height }}" alt="{{ k.topic }} at {{ '%.2f' | format(k.t_ns / 1e9) }} s">
     <figcaption>{{ k.topic }} · {{ "%.2f" | format(k.t_ns / 1e9) }} s</figcaption></figure>
   {% else %}<span class="note">no colour image near this moment</span>{% endfor %}
   </div></div>
 {% endfor %}
 </div>
</section>
{% endif %}

{% if other_panels %}
<section id="timeseries">
 <h2>Time series <span class="count">(shared time axis, seconds of simulation time{% if focus_panels %}; the panels that explain the summary are at the top{% endif %})</span></h2>
 {% for p in other_panels %}{{ panel(p) }}{% endfor %}
</section>
{% endif %}

<section id="metrics">
{% if comparison and not_compared %}
 <h2>All metrics beside a baseline of another configuration, not compared <span class="count">({{ comparison | length }})</span></h2>
 {{ comparison_table(comparison, "metrics-table") }}
{% elif comparison %}
 <h2>All metrics against the baseline <span class="count">({{ comparison | length }})</span></h2>
 {{ comparison_table(comparison, "metrics-table") }}
{% elif not metrics %}
 <h2>All metrics <span class="count">(0)</span></h2>
 <p class="note">This scenario has no <code>scoring:</code> block that produces metrics.</p>
{% else %}
 <h2>All metrics <span class="count">({{ metrics | length }}{% if no_baseline %}; no baseline:
  values only{% endif %})</span></h2>
 {{ metric_table(metrics, "metrics-table") }}
{% endif %}
</section>

<section id="health">
 <h2>Health gates <span class="count">({{ health_ok }}/{{ health | length }} ok)</span></h2>
 <table><thead><tr><th>gate</th><th>status</th><th>detail</th></tr></thead><tbody>
 {% for h in health %}<tr{% if not h.ok %} class="st-regressed"{% endif %}><td class="name">{{ h.name }}</td>
  <td>{% if h.ok %}<span class="badge b-okgate">ok</span>{% else %}<span class="badge b-tripped">tripped</span>{% endif %}</td>
  <td>{{ h.detail }}</td></tr>{% endfor %}
 </tbody></table>
</section>

<section id="graphs">
 <h2>Action graphs <span class="count">({{ graphs | length }})</span></h2>
 {% if graphs %}
 <p class="note">Columns follow execution and data depth. Solid: execution; dashed blue:
  data; rounded green: event nodes; dashed boxes: data nodes. Hover for attributes.</p>
 <div class="graphs">
 {% for g in graphs %}<div class="graph-card"><h3>{{ g.path }}</h3>{{ g.svg }}</div>{% endfor %}
 </div>
 {% endif %}
 {% if graph_paths %}<p class="note">Graph paths in the summary: {{ graph_paths | join(", ") }}</p>{% endif %}
 {% if mermaid %}<details><summary>Mermaid text of the graphs</summary><pre class="mermaid-text">{{ mermaid }}</pre></details>{% endif %}
</section>

<section id="topics">
 <h2>Topics <span class="count">({{ topics | length }})</span></h2>
 <table><thead><tr><th>topic</th><th>type</th><th class="num">count</th>
  <th class="num">published</th><th class="num">rate (Hz)</th><th class="num">bytes</th>
  <th>durability</th><th>sha256</th></tr></thead><tbody>
 {% for t in topics %}<tr><td class="name">{{ t.name }}</td><td class="mono">{{ t.type }}</td>
  <td class="num">{{ t.count }}</td><td class="num">{{ t.published }}</td>
  <td class="num">{{ t.rate }}</td><td class="num">{{ t.bytes }}</td><td>{{ t.durability }}</td>
  <td class="mono" title="{{ t.sha256 }}">{{ t.sha256[:16] }}</td></tr>{% endfor %}
 </tbody></table>
</section>

<section id="run">
 <h2>Reproduce</h2>
 <pre class="cmd" id="command">{{ command }}</pre>
 <p class="note">The same run from its resolved scenario (includes, defaults and <code>--set</code>
  overrides applied):</p>
 <pre class="cmd" id="command-exact">{{ command_exact }}</pre>
 <dl class="kv">
  {% for k, v in run_info %}<dt>{{ k }}</dt><dd class="mono">{{ v }}</dd>{% endfor %}
 </dl>
 <h3>Versions</h3>
 <dl class="kv">
  {% for k, v in versions %}<dt>{{ k }}</dt><dd class="mono">{{ v }}</dd>{% endfor %}
 </dl>
</section>

<section id="scenario">
 <h2>Resolved scenario <span class="count">(scenario.yaml, {{ scenario_lines }} lines)</span></h2>
 <details><summary>show scenario.yaml</summary><pre class="scenario-yaml">{{ scenario_text }}</pre></details>
</section>
<footer>srr {{ srr_version }} · report generated from {{ run_dir }} · self-contained: no
 scripts, no network requests.</footer>
</main>
</body>
</html>
"""

MACROS = """
{% macro comparison_table(rows, cls) -%}
<table class="{{ cls }}"><thead><tr><th>metric</th><th class="num">value</th>
 <th class="num">baseline</th><th class="num">delta</th><th class="num">tolerance</th>
 <th>status</th><th>when (sim s)</th></tr></thead><tbody>
{% for e in rows %}<tr class="st-{{ e.status }}" data-metric="{{ e.name }}">
 <td class="name" title="{{ e.detail }}">{{ e.name }}</td><td class="num">{{ e.value }}</td>
 <td class="num">{{ e.baseline }}</td><td class="num">{{ e.delta }}</td>
 <td class="num">{{ e.tolerance }}</td>
 <td><span class="badge b-{{ e.status }}">{{ e.status_text }}</span> <span class="note">{{ e.better }}</span></td>
 <td class="when">{{ e.when }}</td></tr>
{% endfor %}</tbody></table>
{%- endmacro %}

{% macro metric_table(rows, cls) -%}
<table class="{{ cls }}"><thead><tr><th>metric</th><th class="num">value</th><th>band</th>
 <th>detail</th><th>when (sim s)</th></tr></thead><tbody>
{% for m in rows %}<tr data-metric="{{ m.name }}"{% if m.failing %} class="st-regressed"{% endif %}>
 <td class="name">{{ m.name }}</td><td class="num">{{ m.value }}</td>
 <td>{% if m.verdict %}<span class="badge b-{{ m.verdict }}">{{ m.verdict }}</span>{% endif %}</td>
 <td>{{ m.detail }}</td><td class="when">{{ m.when }}</td></tr>
{% endfor %}</tbody></table>
{%- endmacro %}

{% macro legend_keys(items, fill_opacity) -%}
{% for label, color, style in items %}<span class="key"><i class="{{ style }}"
 style="{% if style == 'dashed' %}border-color{% else %}background{% endif %}:{{ color }}{% if style == 'fill' %};opacity:{{ fill_opacity }}{% endif %}"></i>{{ label }}</span>{% endfor %}
{%- endmacro %}

{% macro panel(p) -%}
<figure class="panel" id="panel-{{ p.key }}" data-group="{{ p.group }}">
 <figcaption>{{ p.title }}{% if p.highlight %}<span class="hl-name">dashed outline:
  {{ p.highlight }}</span>{% endif %}</figcaption>
 <div class="legend">{{ legend_keys(p.legend, ".6") }}
  {% if p.note %}<span class="note">{{ p.note }}</span>{% endif %}</div>
 {{ p.svg }}
</figure>
{%- endmacro %}
"""

SUITE = """<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{{ b.verdict }} · {{ b.name }} · srr suite</title>
<style>{{ css }}</style>
</head>
<body>
<header class="banner v-{{ b.verdict }}" id="verdict" data-verdict="{{ b.verdict }}"><div class="wrap">
 <div class="verdict-word">{{ b.verdict }}<small>exit code {{ b.exit_code }}</small></div>
 <div class="banner-main"><h1>{{ b.name }}</h1>
  <p class="meta" id="counts">{% for v, n in b.counts %}<span data-count="{{ v }}">{{ n }} {{ v }}</span>{% if not loop.last %} · {% endif %}{% endfor %}</p>
  <p class="meta">{{ b.meta | join(" · ") }}</p>
  {% if b.interrupted %}<div class="nobaseline" id="interrupted">Interrupted: the suite was
   stopped before every run finished; runs that did not start are INTERRUPTED.</div>{% endif %}
 </div></div>
</header>
<nav class="toc"><div class="wrap">
 <a href="#groups">Groups</a><a href="#stats">Metric statistics</a>
 {% if sweeps %}<a href="#sweeps">Sweeps</a>{% endif %}
 {% if history %}<a href="#history">History</a>{% endif %}
</div></nav>
<main class="wrap">
<section id="groups">
 <h2>Groups <span class="count">({{ groups | length }} groups, {{ b.n_runs }} runs; worst first)</span></h2>
 <table class="groups-table"><thead><tr><th>verdict</th><th>group</th><th>params</th>
  <th class="num">repeats</th><th>key regressions / reasons</th><th>runs</th></tr></thead><tbody>
 {% for g in groups %}<tr data-group="{{ g.id }}" data-verdict="{{ g.verdict }}">
  <td><span class="badge b-v-{{ g.verdict }}">{{ g.verdict }}</span></td>
  <td class="gid"><a href="#{{ g.anchor }}">{{ g.id }}</a></td>
  <td class="params">{% for p in g.params %}{{ p }}{% if not loop.last %}<br>{% endif %}{% endfor %}</td>
  <td class="num">{{ g.repeats }}</td>
  <td class="key">{% if g.key %}<ul class="key">{% for k in g.key %}<li>{{ k }}</li>{% endfor %}</ul>{% endif %}
   {% if g.more %}<span class="note">+{{ g.more }} more</span>{% endif %}
   {% if g.flaky %}<div class="flaky">
    <b>flaky:</b> {% if g.flaky.topics %}digests differ on
     <span class="flaky-topics">{% for t in g.flaky.topics %}<code>{{ t }}</code>{% if not loop.last %}, {% endif %}{% endfor %}</span>{% else %}verdicts differ, digests agree{% endif %}
    {% if g.flaky.compared %} <span class="note">({{ g.flaky.compared | join(" vs ") }})</span>{% endif %}
    {% if g.flaky.first_divergence %}<br>first divergence: <code class="first-divergence">{{ g.flaky.first_divergence }}</code>{% endif %}
    <table class="flaky-repeats"><tr><th>repeat</th><th>verdict</th><th>digest</th></tr>
    {% for r in g.flaky.repeats %}<tr><td>{{ r.label }}</td><td><span class="badge b-v-{{ r.verdict }}">{{ r.verdict }}</span></td>
     <td class="mono" title="{{ r.digest }}">{{ r.digest[:16] }}</td></tr>{% endfor %}
    </table></div>{% endif %}</td>
  <td><ul class="runs">{% for r in g.runs %}<li data-run="{{ r.id }}">
   {% if r.report %}<a href="{{ r.report }}">#{{ r.repeat }} report</a>{% else %}#{{ r.repeat }}{% endif %}
   <span class="badge b-v-{{ r.verdict }}">{{ r.verdict }}</span>
   {% if r.log %}<a href="{{ r.log }}">log</a>{% endif %}
   {% if r.problem %}<div class="problem-text">{{ r.problem }}</div>{% endif %}
  </li>{% endfor %}</ul></td>
 </tr>{% endfor %}
 </tbody></table>
</section>

<section id="stats">
 <h2>Metric statistics per group <span class="count">(over the repeats that produced a value)</span></h2>
 {% for g in groups %}<details class="group-stats" id="{{ g.anchor }}" data-group="{{ g.id }}">
  <summary><span class="badge b-v-{{ g.verdict }}">{{ g.verdict }}</span>{{ g.id }}
   <span class="note">({{ g.stats | length }} metrics)</span></summary>
  {% if g.stats %}<table class="stats-table"><thead><tr><th>metric</th><th class="num">mean ± std</th>
   <th class="num">95 % CI</th><th class="num">min / max</th><th class="num">n</th>
   <th class="num">baseline ± tolerance</th><th>status</th></tr></thead><tbody>
  {% for m in g.stats %}<tr class="st-{{ m.status }}" data-metric="{{ m.name }}">
   <td class="name">{{ m.name }}</td><td class="num">{{ m.mean }}</td><td class="num">{{ m.ci }}</td>
   <td class="num">{{ m.range }}</td><td class="num">{{ m.n }}</td><td class="num">{{ m.baseline }}</td>
   <td>{% if m.status %}<span class="badge b-{{ m.status }}">{{ m.status }}</span>{% endif %}
    {% if m.band %}<span class="badge b-{{ m.band }}">{{ m.band }}</span>{% endif %}
    <span class="note">{{ m.better }}</span></td></tr>
  {% endfor %}</tbody></table>
  {% else %}<p class="note">No metric values: no repeat of this group produced scores.</p>{% endif %}
 </details>{% endfor %}
</section>

{% if sweeps %}
<section id="sweeps">
 <h2>Sweeps <span class="count">(each metric against the swept parameter; points coloured by
  their group's verdict)</span></h2>
 {% for s in sweeps %}<div class="sweep" data-sweep="{{ s.name }}">
  <h3>{{ s.name }} <span class="note">scenario {{ s.scenario }} · x: <code>{{ s.x_param }}</code>
   {% if s.series_param %}· one line per <code>{{ s.series_param }}</code>{% endif %}
   · {{ s.n_points }} points</span></h3>
  {% if s.boundaries %}<ul class="boundaries">{% for t in s.boundaries %}<li>{{ t }}</li>{% endfor %}</ul>
  {% else %}<p class="note">The verdict does not change along the sweep.</p>{% endif %}
  {% for n in s.notes %}<p class="note">{{ n }}</p>{% endfor %}
  <div class="sweep-grid">
  {% for f in s.figures %}<figure class="sweep-fig" data-metric="{{ f.metric }}">
   <figcaption>{{ f.metric }}{% if f.unit %} <span class="unit">({{ f.unit }})</span>{% endif %}</figcaption>
   <div class="legend">{{ legend_keys(f.legend, ".5") }}</div>
   {{ f.svg }}
   {% if f.note %}<p class="note">{{ f.note }}</p>{% endif %}
  </figure>{% endfor %}
  </div></div>
 {% endfor %}
</section>
{% endif %}

{% if history %}
<section id="history">
 <h2>History <span class="count">({{ history.n_nights }} nights, oldest → tonight; the last,
  outlined point is tonight)</span></h2>
 <p class="note">{{ history.span }}</p>
 {% for w in history.warnings %}<div class="warning history-warning">{{ w }}</div>{% endfor %}
 {% for h in history.groups %}<details class="group-history" data-group="{{ h.id }}"{% if h.open %} open{% endif %}>
  <summary><span class="badge b-v-{{ h.verdict }}">{{ h.verdict }}</span>{{ h.id }}
   {% if h.note %}<span class="hist-note">{{ h.note }}</span>{% endif %}</summary>
  <table class="history"><tbody>
   <tr><td class="note">{{ h.strip_label }}</td><td>{{ h.strip }}</td><td></td><td></td></tr>
  {% for m in h.metrics %}<tr data-metric="{{ m.name }}"><td class="name">{{ m.name }}</td>
   <td>{{ m.svg }}</td><td class="num">{{ m.tonight }}{% if m.earlier %}<br><span class="note">earlier
    {{ m.earlier }}</span>{% endif %}</td>
   <td>{% if m.note %}<span class="hist-note">{{ m.note }}</span>{% endif %}</td></tr>
  {% endfor %}</tbody></table>
 </details>{% endfor %}
</section>
{% endif %}
<footer>srr {{ srr_version }} · suite page of {{ b.name }} · links are relative to this file, so
 the folder works as one downloaded artifact · self-contained: no scripts, no network requests.</footer>
</main>
</body>
</html>
"""
