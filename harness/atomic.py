"""Writing output files atomically: a reader sees the old file or the whole new one, never a
half-written one (a run directory must not look valid when it is not)."""

from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path
from typing import Any

from harness.errors import SrrError

__all__ = ["discard_partial", "write_json_atomic", "write_text_atomic"]


def discard_partial(path: Path) -> None:
    """Remove a partial output file, if there is one, after a write failed: quietly where
    that fails too (a read-only filesystem refuses the removal even of nothing), so that the
    write's own error is the one said."""
    with contextlib.suppress(OSError):
        path.unlink(missing_ok=True)


def write_text_atomic(path: Path, text: str) -> None:
    """Write ``text`` to a temporary file next to ``path`` and rename it into place."""
    tmp = path.with_name(path.name + ".tmp")
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    except OSError as err:
        discard_partial(tmp)
        raise SrrError(f"{path}: cannot write: {err.strerror or err}") from err


def write_json_atomic(path: Path, data: Any) -> None:
    """Pretty, key-sorted JSON with a final newline, written atomically."""
    write_text_atomic(path, json.dumps(data, indent=2, sort_keys=True) + "\n")
