"""The run package is below the suite and the API: nothing in harness.run imports the API or
the suite, and the suite imports the run package, never the API (at module level or inside a
function), so there is no cycle between them."""

from __future__ import annotations

import ast
from pathlib import Path

HARNESS = Path(__file__).resolve().parents[2] / "harness"


def _imports(path: Path) -> set[str]:
    """Every module ``path`` imports, wherever the import statement is."""
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
            out |= {f"{node.module}.{a.name}" for a in node.names}
    return out


def _offending(package: str, banned: tuple[str, ...]) -> dict[str, list[str]]:
    found = {}
    for path in sorted((HARNESS / package).glob("*.py")):
        bad = sorted(m for m in _imports(path)
                     if any(m == b or m.startswith(f"{b}.") for b in banned))
        if bad:
            found[path.name] = bad
    return found


def test_the_run_package_imports_neither_the_api_nor_the_suite() -> None:
    assert _offending("run", ("harness.api", "harness.suite", "harness.cli")) == {}


def test_the_suite_imports_the_run_package_not_the_api() -> None:
    assert _offending("suite", ("harness.api", "harness.cli")) == {}
    assert any("harness.run" in m for p in (HARNESS / "suite").glob("*.py")
               for m in _imports(p) if m.startswith("harness.run"))
