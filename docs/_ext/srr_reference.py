"""Reference pages generated from the code at build time, so they cannot drift from it.

``generate(out_dir)`` writes Markdown fragments into ``out_dir`` (``docs/_generated``, git-
ignored) that the reference pages pull in with MyST's ``include``: the fields of the scenario,
suite and ``summary.json`` dataclasses (name, type, default, range, read the way
:mod:`harness.validation` reads them) and the graph node types with their Isaac Sim names.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
import types
import typing
from pathlib import Path
from typing import Any

from sphinx.application import Sphinx

from harness.validation import layout

_MISSING = dataclasses.MISSING


def _type_name(tp: Any) -> str:
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        return " | ".join(_type_name(a) for a in args)
    if origin is typing.Literal:
        return " | ".join(repr(a) for a in args)
    if origin is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return f"list of {_type_name(args[0])}"
        return "[" + ", ".join(_type_name(a) for a in args) + "]"
    if origin is not None and args:
        name = getattr(origin, "__name__", str(origin))
        name = {"dict": "mapping", "Mapping": "mapping"}.get(name, name)
        return f"{name}[{', '.join(_type_name(a) for a in args)}]"
    if tp is type(None):
        return "null"
    if tp is Any:
        return "any"
    return {"str": "text", "float": "number", "int": "integer", "bool": "true/false"}.get(
        getattr(tp, "__name__", str(tp)), getattr(tp, "__name__", str(tp)))


def _nested(tp: Any) -> list[type]:
    """The dataclasses a field's type holds (directly, in a union, list or mapping value)."""
    if dataclasses.is_dataclass(tp) and isinstance(tp, type):
        return [tp]
    found: list[type] = []
    args = typing.get_args(tp)
    if typing.get_origin(tp) in (dict, typing.Mapping) and len(args) == 2:
        args = (args[1],)
    for a in args:
        for c in _nested(a):
            if c not in found:
                found.append(c)
    return found


def _default(f: dataclasses.Field[Any]) -> str:
    if f.default is not _MISSING:
        value = f.default
    elif f.default_factory is not _MISSING:
        value = f.default_factory()
    else:
        return "**required**"
    if dataclasses.is_dataclass(value):
        return "(the block's defaults)"
    if value in ((), {}, []):
        return "empty"
    if value is None:
        return "none"
    if isinstance(value, bool):
        return "`true`" if value else "`false`"
    if isinstance(value, str) and value == "":
        return '`""`'
    text = str(value)
    if len(text) > 60:
        return f"{len(value)} items, see the class" if isinstance(value, tuple) else "see the class"
    return f"`{text}`".replace("|", "\\|")


def _num(x: float) -> str:
    return str(int(x)) if float(x).is_integer() else f"{x:g}"


def _range(f: dataclasses.Field[Any]) -> str:
    rng = f.metadata.get("range")
    if not rng:
        return ""
    lo, hi, lo_open = rng
    parts = []
    if lo is not None:
        parts.append(f"{'>' if lo_open else '≥'} {_num(lo)}")
    if hi is not None:
        parts.append(f"≤ {_num(hi)}")
    return ", ".join(parts)


def _doc(cls: type) -> str:
    doc = inspect.getdoc(cls) or ""
    if doc.startswith(f"{cls.__name__}("):  # the dataclass's generated signature
        return ""
    return _plain(" ".join(doc.split("\n\n")[0].split()))


def _plain(text: str) -> str:
    """Sphinx roles in a docstring (``:meth:`to_json```) as code for Markdown."""
    return re.sub(r":\w+:`~?([^`]+)`", r"`\1`", text).replace("|", "\\|")


def _label(page: str, cls: type) -> str:
    return f"{page}-{cls.__name__.lower()}"


def _rows(cls: type, prefix: str, seen: set[type], rows: list[str],
          blocks: list[tuple[str, type]], page: str) -> None:
    hints, fields = layout(cls)
    for key, f in fields.items():
        if f.name.startswith("_"):
            continue
        tp = hints[f.name]
        path = f"{prefix}{key}"
        nested = _nested(tp)
        type_text = _type_name(tp).replace("|", "\\|")
        for sub in nested:  # the block's name links to its table below
            type_text = re.sub(rf"\b{sub.__name__}\b",
                               f"{{ref}}`{sub.__name__} <{_label(page, sub)}>`", type_text)
        rows.append(f"| `{path}` | {type_text} | {_default(f)} | {_range(f)} |")
        for sub in nested:
            if sub in seen:
                continue
            seen.add(sub)
            sub_prefix = path + ("[]." if typing.get_origin(tp) is tuple
                                 or "list of" in _type_name(tp) else
                                 ".<name>." if typing.get_origin(tp) in (dict, typing.Mapping)
                                 else ".")
            blocks.append((sub_prefix, sub))


def fields_table(root: type, page: str) -> str:
    """Every field under ``root``, one table per block, in file order."""
    out: list[str] = []
    queue: list[tuple[str, type]] = [("", root)]
    seen: set[type] = {root}
    while queue:
        prefix, cls = queue.pop(0)
        title = prefix.rstrip(".") or "top level"
        out.append(f"\n({_label(page, cls)})=\n## `{title}`\n")
        doc = _doc(cls)
        if doc:
            out.append(f"{doc} (`{cls.__module__}.{cls.__qualname__}`)\n")
        else:
            out.append(f"(`{cls.__module__}.{cls.__qualname__}`)\n")
        out.append("| field | type | default | range |\n| --- | --- | --- | --- |")
        rows: list[str] = []
        blocks: list[tuple[str, type]] = []
        _rows(cls, prefix, seen, rows, blocks, page)
        out.extend(rows)
        queue.extend(blocks)
    return "\n".join(out) + "\n"


def node_table() -> str:
    import harness.graph  # noqa: F401  (registers the node types)
    from harness.graph import registry

    rows = ["| node type | Isaac Sim names (aliases) | what it does |", "| --- | --- | --- |"]
    for name, cls in sorted(registry.all_types().items()):
        aliases = ", ".join(f"`{a}`" for a in registry.DEFAULT_REGISTRY.aliases(name)) or "—"
        doc = _plain(" ".join((inspect.getdoc(cls) or "").split("\n\n")[0].split()))
        rows.append(f"| `{name}` | {aliases} | {doc} |")
    return "\n".join(rows) + "\n"


def metrics_table(baseline: Path) -> str:
    """Every metric a scored run of ``baseline``'s scenario gives (control, perception and
    safety), with its unit and better direction, as srr wrote them when blessing it."""
    import json

    metrics = json.loads(baseline.read_text(encoding="utf-8"))["metrics"]
    better = {"lower": "lower", "higher": "higher", "none": "—"}
    rows = ["| metric | unit | better |", "| --- | --- | --- |"]
    for name, m in sorted(metrics.items()):
        rows.append(f"| `{name}` | {m.get('unit') or '—'} | "
                    f"{better.get(str(m.get('direction')), m.get('direction'))} |")
    return "\n".join(rows) + "\n"


def generate(out_dir: Path) -> None:
    from harness.run.summary import RunSummary
    from harness.scenario.schema import Scenario
    from harness.suite.spec import SuiteFile

    out_dir.mkdir(parents=True, exist_ok=True)
    pages = {
        "scenario-fields.md": fields_table(Scenario, "scenario"),
        "suite-fields.md": fields_table(SuiteFile, "suite"),
        "summary-fields.md": fields_table(RunSummary, "summary"),
        "graph-nodes.md": node_table(),
        "metrics.md": metrics_table(Path(__file__).resolve().parents[2] / "baselines"
                                    / "dock_worker_crossing.json"),
    }
    for name, text in pages.items():
        path = out_dir / name
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")


def setup(app: Sphinx) -> dict[str, Any]:
    generate(Path(app.srcdir) / "_generated")
    return {"parallel_read_safe": True, "parallel_write_safe": True}
