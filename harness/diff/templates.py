"""The Jinja2 template and extra styles of the ``srr diff --html`` page. The report's
stylesheet and panel macro are reused (:mod:`harness.report.templates`), so a panel looks the
same in a run's report and in a comparison."""

from __future__ import annotations

__all__ = ["DELTA_MACRO", "DIFF", "DIFF_CSS"]

DIFF_CSS = """
.banner.v-IDENTICAL, .banner.v-EQUAL_WITHIN_TOLERANCE { background:var(--PASS); }
.banner.v-DIFFERENT { background:var(--REGRESSED); }
.banner .first { margin:6px 0 0 0; font-size:13px; background:rgba(255,255,255,.16);
  padding:4px 8px; border-radius:4px; display:inline-block; }
.runs { display:grid; grid-template-columns: 1fr 1fr; gap:10px; }
.run-card { border:1px solid var(--line); border-left-width:6px; border-radius:6px;
  padding:6px 10px; font-size:13px; }
.run-card h3 { margin:0 0 4px 0; }
.run-card dl.kv { grid-template-columns: 110px 1fr; }
.run-chip { display:inline-block; width:12px; height:12px; border-radius:3px; margin-right:5px;
  vertical-align:-1px; }
tr.st-differs td, tr.st-only_in_a td, tr.st-only_in_b td { background:#fef2f2; }
tr.st-within_tolerance td { background:#fffbeb; }
.b-identical { background:#f1f5f9; color:#475569; }
.b-within_tolerance { background:#fef3c7; color:#92400e; }
.b-differs, .b-only_in_a, .b-only_in_b, .b-beyond { background:#dc2626; color:#fff; }
.b-within { background:#fef3c7; color:#92400e; }
td.path { font-family: ui-monospace, "DejaVu Sans Mono", Menlo, Consolas, monospace;
  font-size:12px; word-break:break-all; min-width:16em; }
.metrics-ok { margin-top:4px; }
.pair-row { border:1px solid var(--line); border-radius:6px; padding:6px 8px; margin:0 0 10px 0; }
.pair-head { font-size:13px; margin-bottom:4px; }
.pair-head b { font-size:13.5px; }
.pair-grid { display:grid; grid-template-columns: repeat(auto-fit, minmax(330px, 1fr)); gap:10px; }
.pair { display:grid; grid-template-columns: 1fr 1fr 1fr; gap:4px; }
.pair figure { margin:0; }
.pair img { display:block; width:100%; height:auto; border:1px solid #d1d5db; background:#000; }
.pair figcaption { font-size:11px; color:#4b5563; }
.pair figure.side-a img { border-color:#2563eb; border-width:2px; }
.pair figure.side-b img { border-color:#ea580c; border-width:2px; }
.pair-topic { font-size:12px; font-family: ui-monospace, "DejaVu Sans Mono", monospace;
  margin:2px 0; grid-column: 1 / -1; }
"""

DELTA_MACRO = """
{% macro delta_table(rows, cls) -%}
<table class="{{ cls }}"><thead><tr><th>metric</th><th class="num">A</th>
 <th class="num">B</th><th class="num">delta (B − A)</th><th class="num">tolerance</th>
 <th>status</th><th>better</th></tr></thead><tbody>
{% for m in rows %}<tr class="st-{{ m.status }}" data-metric="{{ m.name }}" data-status="{{ m.status }}">
 <td class="name">{{ m.name }}</td><td class="num">{{ m.a }}</td><td class="num">{{ m.b }}</td>
 <td class="num">{{ m.delta }}</td><td class="num">{{ m.tolerance }}</td>
 <td><span class="badge b-{{ m.status }}">{{ m.status }}</span> <span class="note">{{ m.direction }}</span></td>
 <td>{{ m.better }}</td></tr>{% endfor %}
</tbody></table>
{%- endmacro %}
"""

DIFF = """<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{{ verdict_text }} · {{ a.scenario }} vs {{ b.scenario }} · srr diff</title>
<style>{{ css }}</style>
</head>
<body>
<header class="banner v-{{ verdict }}" id="verdict" data-verdict="{{ verdict }}">
 <div class="wrap">
  <div class="verdict-word">{{ verdict_text }}<small>exit code {{ exit_code }}</small></div>
  <div class="banner-main">
   <h1>{{ a.scenario }} (A, seed {{ a.seed }}) vs {{ b.scenario }} (B, seed {{ b.seed }})</h1>
   <p class="meta">{{ counts | join(" · ") }}</p>
   {% for n in replay_notes %}<p class="meta replay-note">{{ n }}</p>{% endfor %}
   {% if first %}<div class="first" id="first-divergence" data-topic="{{ first.topic }}"
    data-index="{{ first.index }}" data-path="{{ first.path }}">first divergence:
    {{ first.describe() }}</div>{% endif %}
  </div>
 </div>
</header>
<nav class="toc"><div class="wrap">
 {% for id, label in toc %}<a href="#{{ id }}">{{ label }}</a>{% endfor %}
</div></nav>
<main class="wrap">
{% for p in problems %}<div class="problem report-problem">{{ p }}</div>{% endfor %}
{% for n in notes %}<div class="warning diff-note">{{ n }}</div>{% endfor %}

<section id="runs">
 <div class="runs">
 {% for r in runs %}<div class="run-card run-{{ r.key }}" style="border-left-color:{{ r.color }}">
  <h3><span class="run-chip" style="background:{{ r.color }}"></span>{{ r.label }}</h3>
  <dl class="kv">{% for k, v in r.info %}<dt>{{ k }}</dt><dd class="mono">{{ v }}</dd>{% endfor %}</dl>
 </div>{% endfor %}
 </div>
 <p class="note">The exit code depends on the recorded data only (same topics, types and
  counts; every message identical or within the tolerances); metrics are shown side by side,
  A as the baseline.{% if tolerances %} Tolerances: {% for t in tolerances %}<code>{{ t }}</code>{% if not loop.last %}, {% endif %}{% endfor %}.{% endif %}</p>
</section>

<section id="topics">
 <h2>Recorded topics <span class="count">({{ topics | length }}; messages paired by index;
  differing first)</span></h2>
 <table class="topic-table"><thead><tr><th>topic</th><th>type</th><th class="num">A</th>
  <th class="num">B</th><th>status</th><th class="num">differ</th><th>first divergence</th>
  <th>largest difference</th></tr></thead><tbody>
 {% for t in topics %}<tr class="st-{{ t.status }}" data-topic="{{ t.name }}" data-status="{{ t.status }}">
  <td class="name">{{ t.name }}</td><td class="mono">{{ t.type }}</td>
  <td class="num">{{ t.count_a }}</td><td class="num">{{ t.count_b }}</td>
  <td><span class="badge b-{{ t.status }}">{{ t.status_text }}</span></td>
  <td class="num">{{ t.differ }}</td>
  <td class="path">{{ t.first }}</td><td class="path">{{ t.largest }}</td></tr>{% endfor %}
 </tbody></table>
</section>

<section id="metrics">
 <h2>Metrics side by side <span class="count">({{ n_metrics }}; A = baseline; {{ metrics | length }}
  moved beyond tolerance)</span></h2>
 {% if metrics %}{{ delta_table(metrics, "metric-delta-table") }}{% endif %}
 {% if metrics_ok %}<details{% if not metrics %} open{% endif %}><summary>{{ metrics_ok | length }} metric(s) within tolerance</summary>
 {{ delta_table(metrics_ok, "metric-delta-table metrics-ok") }}</details>{% endif %}
 {% if not n_metrics %}<p class="note">Neither run scored any metric.</p>{% endif %}
</section>

{% if map_svg %}
<section id="map">
 <h2>Top-down map <span class="count">(world frame, metres; the scene of A)</span></h2>
 <div class="legend map-legend">{{ legend_keys(map_legend, ".35") }}</div>
 {{ map_svg }}
 {% if moments %}<ol class="moments">
  {% for m in moments %}<li><b>M{{ m.number }}</b> {{ "%.2f" | format(m.t_s) }} s — {{ m.label }}</li>{% endfor %}
 </ol>{% endif %}
</section>
{% endif %}

{% if keyframes %}
<section id="cameras">
 <h2>Camera keyframes <span class="count">(A | B | where they differ, nearest recorded image to
  each moment)</span></h2>
 {% for row in keyframes %}
 <div class="pair-row" id="kf-m{{ row.moment.number }}"><div class="pair-head"><b>M{{ row.moment.number }}</b>
  · {{ "%.2f" | format(row.moment.t_s) }} s — {{ row.moment.label }}</div>
  <div class="pair-grid">
  {% for p in row.pairs %}<div class="pair" data-topic="{{ p.topic }}">
   <div class="pair-topic">{{ p.topic }}{% if p.total %} · {{ p.differ }} of {{ p.total }} pixels differ{% endif %}</div>
   {% for side, k in (("a", p.a), ("b", p.b)) %}<figure class="side-{{ side }}">{% if k %}<img
     src="{{ k.uri }}" width="{{ k.width }}" height="{{ k.height }}"
     alt="{{ k.topic }} of {{ side | upper }} at {{ '%.2f' | format(k.t_ns / 1e9) }} s">
     <figcaption>{{ side | upper }} · {{ "%.2f" | format(k.t_ns / 1e9) }} s</figcaption>{% else %}<figcaption>no image in {{ side | upper }}</figcaption>{% endif %}</figure>
   {% endfor %}
   <figure class="side-diff">{% if p.diff_uri %}<img src="{{ p.diff_uri }}" width="{{ p.a.width }}"
     height="{{ p.a.height }}" alt="pixels that differ between A and B">
     <figcaption>|A − B| in red over A</figcaption>{% else %}<figcaption>not comparable</figcaption>{% endif %}</figure>
  </div>{% endfor %}
  </div></div>
 {% endfor %}
</section>
{% endif %}

{% if panels %}
<section id="timeseries">
 <h2>Time series <span class="count">(both runs overlaid on one time axis, seconds of simulation
  time)</span></h2>
 {% for p in panels %}{{ panel(p) }}{% endfor %}
</section>
{% endif %}

<section id="fields">
 <h2>Numeric differences <span class="count">({{ fields | length }} fields; |B − A| over the
  messages whose payloads differ)</span></h2>
 {% if fields %}
 <table class="field-table"><thead><tr><th>topic</th><th>field</th><th class="num">values</th>
  <th class="num">differ</th><th class="num">beyond</th><th class="num">max |Δ|</th>
  <th class="num">RMS</th><th>max at</th><th>tolerance</th></tr></thead><tbody>
 {% for f in fields %}<tr data-topic="{{ f.topic }}" data-field="{{ f.path }}"{% if not f.within %} class="st-differs"{% endif %}>
  <td class="name">{{ f.topic }}</td><td class="path">{{ f.path }}</td>
  <td class="num">{{ f.n_values }}</td><td class="num">{{ f.differ }}</td>
  <td class="num">{{ f.beyond }}</td><td class="num">{{ f.max_abs }}</td>
  <td class="num">{{ f.rms }}</td><td class="when">{{ f.at }}</td>
  <td>{% if f.within %}<span class="badge b-within">{{ f.tolerance }}</span>{% else %}<span class="badge b-beyond">{{ f.tolerance }}</span>{% endif %}</td></tr>{% endfor %}
 </tbody></table>
 {% if fields_more %}<p class="note">… and {{ fields_more }} more (in <code>--json</code>).</p>{% endif %}
 {% else %}<p class="note">No numeric field differs.</p>{% endif %}
</section>
<footer>srr {{ srr_version }} · srr diff {{ a.path }} {{ b.path }} · self-contained: no scripts,
 no network requests.</footer>
</main>
</body>
</html>
"""
