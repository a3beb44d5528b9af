"""Dumps of a :class:`GraphStage`: a JSON-able dict, stable JSON text and a Mermaid flowchart.

Graphs, nodes and connections keep their creation order (it is the evaluation order); dict
keys are sorted in the JSON text so equal stages give byte-identical dumps.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from typing import Any

from harness.graph.engine import Graph, GraphStage, Node

__all__ = ["stage_to_dict", "stage_to_json", "stage_to_mermaid"]


def _jsonable(value: Any) -> Any:
    """A JSON-safe copy of an attribute value (tuples -> lists, numpy -> Python, paths -> str)."""
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else repr(value)
    tolist = getattr(value, "tolist", None)
    if callable(tolist):
        return _jsonable(tolist())
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, set, frozenset)):
        items = sorted(value, key=repr) if isinstance(value, (set, frozenset)) else value
        return [_jsonable(v) for v in items]
    path_string = getattr(value, "pathString", None)
    if isinstance(path_string, str):
        return path_string
    return repr(value)


def _node_to_dict(node: Node) -> dict[str, Any]:
    values = {}
    for full, value in node.values.items():
        attr = node.attr(full)
        if attr is not None and value != attr.default:
            values[full] = _jsonable(value)
    return {
        "name": node.name,
        "type": node.type_name,
        "canonical_type": node.canonical_type,
        "kind": node.kind,
        "values": values,
        "dynamic_attributes": {full: attr.type for full, attr in node.dynamic_attributes.items()},
    }


def _graph_to_dict(graph: Graph) -> dict[str, Any]:
    return {
        "path": graph.path,
        "evaluator_name": graph.evaluator_name,
        "nodes": [_node_to_dict(node) for node in graph.nodes],
        "connections": [
            {"src": c.src, "dst": c.dst, "kind": c.kind} for c in graph.connections
        ],
    }


def stage_to_dict(stage: GraphStage) -> dict[str, Any]:
    """``{"graphs": [{"path", "evaluator_name", "nodes": [...], "connections": [...]}]}``.

    Each node gives ``name``, ``type`` (as written), ``canonical_type``, ``kind``, the input
    ``values`` that differ from their defaults and its ``dynamic_attributes`` (name -> type);
    each connection ``src`` / ``dst`` (``"Node.outputs:x"``) and ``kind`` (``exec`` / ``data``).
    """
    return {"graphs": [_graph_to_dict(graph) for graph in stage.graphs()]}


def stage_to_json(stage: GraphStage) -> str:
    """:func:`stage_to_dict` as indented JSON with sorted keys and a trailing newline."""
    return json.dumps(stage_to_dict(stage), sort_keys=True, indent=2, ensure_ascii=False) + "\n"


_UNSAFE_ID = re.compile(r"[^A-Za-z0-9_]")


def _mermaid_id(text: str) -> str:
    return _UNSAFE_ID.sub("_", text)


def _label(text: str) -> str:
    return '"' + text.replace('"', "#quot;") + '"'


_SHAPES = {"event": ("([", "])"), "data": ("[/", "/]"), "action": ("[", "]")}
_PLAIN_EXEC_OUTPUTS = frozenset({"outputs:tick", "outputs:execOut"})


def stage_to_mermaid(stage: GraphStage) -> str:
    """A ``flowchart LR`` with one subgraph per graph.

    Event nodes are stadiums, data nodes parallelograms, action nodes boxes. Execution edges are
    solid (``-->``, labelled only when the output is not ``tick`` / ``execOut``); data edges are
    dotted (``-.->``) and labelled ``source attr -> destination attr``.
    """
    lines = ["flowchart LR"]
    for index, graph in enumerate(stage.graphs()):
        prefix = f"g{index}"
        lines.append(f"  subgraph {prefix}[{_label(graph.path)}]")
        for node in graph.nodes:
            left, right = _SHAPES.get(node.kind, ("[", "]"))
            label = _label(f"{node.name}<br/><small>{node.canonical_type}</small>")
            lines.append(f"    {prefix}_{_mermaid_id(node.name)}{left}{label}{right}")
        lines.append("  end")
        for conn in graph.connections:
            src = f"{prefix}_{_mermaid_id(conn.src_node)}"
            dst = f"{prefix}_{_mermaid_id(conn.dst_node)}"
            src_name = conn.src_attr.split(":", 1)[1]
            dst_name = conn.dst_attr.split(":", 1)[1]
            if conn.kind == "exec":
                if conn.src_attr in _PLAIN_EXEC_OUTPUTS:
                    lines.append(f"  {src} --> {dst}")
                else:
                    lines.append(f"  {src} -->|{_label(src_name)}| {dst}")
            else:
                lines.append(f"  {src} -.->|{_label(f'{src_name} → {dst_name}')}| {dst}")
    return "\n".join(lines) + "\n"
