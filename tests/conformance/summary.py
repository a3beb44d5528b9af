"""Lines the conformance tests want shown at the end of the pytest run (see conftest.py)."""

from __future__ import annotations

__all__ = ["LINES"]

LINES: list[str] = []
