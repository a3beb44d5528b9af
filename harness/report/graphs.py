"""The run's action graphs drawn as SVG, one diagram per graph, without any script.

A run writes its graphs into the run directory as it starts (:data:`GRAPHS_JSON`, the JSON of
``srr graph --format json``, and :data:`GRAPHS_MERMAID`, the Mermaid text of ``srr graph``):
the report reads them there (:func:`read_graphs`) and never builds a simulation.

Layout: a node's column is its depth, the longest chain of connections (execution and data)
leading to it; nodes keep their creation order inside a column. Execution edges are solid,
data edges dashed; hovering an edge or a node shows its attributes.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness.atomic import write_text_atomic
from harness.report.svg import Svg

__all__ = ["GRAPHS_JSON", "GRAPHS_MERMAID", "GraphDiagram", "RunGraphs", "graph_diagrams",
           "layout_depths", "read_graphs", "write_graphs"]

#: The run's action graphs as JSON (``srr graph --format json``), in the run directory.
GRAPHS_JSON = "graphs.json"
#: The same graphs as a Mermaid flowchart (``srr graph``).
GRAPHS_MERMAID = "graphs.mmd"

NODE_W = 150.0  # narrowest node; wider when a name needs it
NODE_H = 40.0
COL_GAP = 54.0
ROW_GAP = 14.0
PAD = 12.0
_MAX_CHARS = 34
_CHAR_W = 7.2  # bold 12 px


@dataclass(frozen=True)
class RunGraphs:
    """A run's action graphs as ``srr graph`` prints them: ``json_text`` (the stage dump)
    and ``mermaid`` (the flowchart)."""

    json_text: str
    mermaid: str

    def stage(self) -> dict[str, Any]:
        """The stage dump as a dict (:func:`graph_diagrams` draws it); raises ValueError
        when the JSON text is not an object."""
        data = json.loads(self.json_text)
        if not isinstance(data, dict):
            raise ValueError("expected a JSON object")
        return data


def write_graphs(run_dir: Path, graphs: RunGraphs) -> None:
    """Write :data:`GRAPHS_JSON` and :data:`GRAPHS_MERMAID` into ``run_dir`` (atomically)."""
    write_text_atomic(run_dir / GRAPHS_JSON, graphs.json_text)
    write_text_atomic(run_dir / GRAPHS_MERMAID, graphs.mermaid)


def read_graphs(run_dir: Path) -> RunGraphs | None:
    """The graphs a run wrote into ``run_dir``; None for a run directory without
    :data:`GRAPHS_JSON` (one written before srr recorded its graphs). Raises OSError or
    UnicodeDecodeError when a file is there but cannot be read."""
    path = run_dir / GRAPHS_JSON
    if not path.is_file():
        return None
    mermaid = run_dir / GRAPHS_MERMAID
    return RunGraphs(path.read_text(encoding="utf-8"),
                     mermaid.read_text(encoding="utf-8") if mermaid.is_file() else "")


@dataclass(frozen=True)
class GraphDiagram:
    path: str
    nodes: int
    connections: int
    svg: str


def _node_of(endpoint: str) -> str:
    return endpoint.split(".", 1)[0]


def layout_depths(nodes: list[str], edges: list[tuple[str, str]]) -> dict[str, int]:
    """Longest-path depth of each node over ``edges`` (src, dst); cycles are cut by capping
    the depth at the number of nodes."""
    depth = dict.fromkeys(nodes, 0)
    limit = len(nodes)
    for _ in range(limit):
        changed = False
        for a, b in edges:
            if a in depth and b in depth and a != b and depth[b] < depth[a] + 1 <= limit:
                depth[b] = depth[a] + 1
                changed = True
        if not changed:
            break
    return depth


def _short(text: str) -> str:
    return text if len(text) <= _MAX_CHARS else text[:_MAX_CHARS - 1] + "…"


def _values_tip(node: Mapping[str, Any]) -> str:
    lines = [f"{node.get('name')} — {node.get('type')} ({node.get('kind')})"]
    for k, v in sorted((node.get("values") or {}).items()):
        text = str(v).replace("\n", " ⏎ ")
        lines.append(f"{k} = {text[:160]}{'…' if len(text) > 160 else ''}")
    return "\n".join(lines)


def _diagram(graph: Mapping[str, Any]) -> GraphDiagram:
    nodes = [n["name"] for n in graph.get("nodes", [])]
    by_name = {n["name"]: n for n in graph.get("nodes", [])}
    conns = graph.get("connections", [])
    edges = [(_node_of(c["src"]), _node_of(c["dst"])) for c in conns]
    depth = layout_depths(nodes, edges)
    cols: dict[int, list[str]] = {}
    for name in nodes:
        cols.setdefault(depth[name], []).append(name)
    node_w = max([NODE_W] + [min(_MAX_CHARS, len(n)) * _CHAR_W + 18 for n in nodes]
                 + [min(_MAX_CHARS, len(str(by_name[n].get("canonical_type", "")))) * 6.0 + 18
                    for n in nodes])
    n_cols = max(cols) + 1 if cols else 1
    n_rows = max((len(v) for v in cols.values()), default=1)
    w = 2 * PAD + n_cols * node_w + (n_cols - 1) * COL_GAP
    h = 2 * PAD + n_rows * NODE_H + (n_rows - 1) * ROW_GAP
    pos: dict[str, tuple[float, float]] = {}
    for d, names in cols.items():
        offset = (n_rows - len(names)) * (NODE_H + ROW_GAP) / 2
        for i, name in enumerate(names):
            pos[name] = (PAD + d * (node_w + COL_GAP), PAD + offset + i * (NODE_H + ROW_GAP))
    svg = Svg(w, h, label=f"action graph {graph.get('path', '')}", class_="graph-svg")
    # several connections between the same pair of nodes are drawn once, listed in the tip
    pairs: dict[tuple[str, str, str], list[str]] = {}
    for c, (a, b) in zip(conns, edges, strict=True):
        pairs.setdefault((a, b, c.get("kind", "data")), []).append(
            f"{c['src']} → {c['dst']}")
    for (a, b, kind), labels in pairs.items():
        if a not in pos or b not in pos:
            continue
        (ax, ay), (bx, by) = pos[a], pos[b]
        y1 = ay + NODE_H / 2 + (-5 if kind == "exec" else 5)
        y2 = by + NODE_H / 2 + (-5 if kind == "exec" else 5)
        if bx > ax:
            x1, x2 = ax + node_w, bx
            mid = (x1 + x2) / 2
            curve = (f"M{x1:.1f},{y1:.1f}C{mid:.1f},{y1:.1f} {mid:.1f},{y2:.1f} "
                     f"{x2 - 6:.1f},{y2:.1f}")
            head = f"M{x2:.1f},{y2:.1f}l-7,-4v8z"
        else:  # same column or backwards: loop around under the nodes
            x1, x2 = ax + node_w / 2, bx + node_w / 2
            low = max(ay, by) + NODE_H + ROW_GAP * 0.8
            curve = (f"M{x1:.1f},{ay + NODE_H:.1f}C{x1:.1f},{low:.1f} {x2:.1f},{low:.1f} "
                     f"{x2:.1f},{by + NODE_H + 6:.1f}")
            head = f"M{x2:.1f},{by + NODE_H:.1f}l-4,7h8z"
        svg.path(curve, class_=f"g-edge g-{kind}", title="\n".join(labels))
        svg.path(head, class_=f"g-head g-{kind}")
    for name in nodes:
        x, y = pos[name]
        node = by_name[name]
        kind = str(node.get("kind", "action"))
        svg.open("g", class_=f"g-node g-node-{kind}")
        svg.rect(x, y, node_w, NODE_H, rx="12" if kind == "event" else "3",
                 title=_values_tip(node))
        svg.text(x + 8, y + 16, _short(name), class_="g-name")
        ctype = str(node.get("canonical_type") or node.get("type", ""))
        svg.text(x + 8, y + 31, _short(ctype), class_="g-type")
        svg.close("g")
    return GraphDiagram(str(graph.get("path", "")), len(nodes), len(conns), svg.render())


def graph_diagrams(stage: Mapping[str, Any]) -> list[GraphDiagram]:
    """One diagram per graph of a :func:`harness.graph.dump.stage_to_dict` dump."""
    return [_diagram(g) for g in stage.get("graphs", [])]
