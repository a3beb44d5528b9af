"""A run's recording checked against what its summary says was recorded: per topic, the
message count and the SHA-256 the recorder kept (:func:`~harness.recording.recorder.
digest_update`: log time, length, payload). A damaged or truncated MCAP can still parse, and a
run directory's bag can be swapped for another; a command that trusts a run (``srr baseline
bless``, ``srr report``, ``srr diff``, ``srr replay``, ``srr export``) checks it first."""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from harness.recording.bagread import open_recording
from harness.recording.errors import BagError
from harness.recording.recorder import digest_update

__all__ = ["check_read_back", "read_back", "verify_recording"]


def read_back(bag: Path) -> dict[str, tuple[int, str]]:
    """Topic → (messages, SHA-256) of the recording at ``bag``, every message read (its
    chunks' CRCs checked); :class:`BagError` when it does not read."""
    digests: dict[str, Any] = {}
    counts: dict[str, int] = {}
    with open_recording(bag) as rec:
        for conn, stamp, data in rec.messages():
            h = digests.get(conn.topic)
            if h is None:
                h = digests[conn.topic] = hashlib.sha256()
                counts[conn.topic] = 0
            digest_update(h, stamp, data)
            counts[conn.topic] += 1
    return {t: (counts[t], h.hexdigest()) for t, h in digests.items()}


def check_read_back(bag: Path, recorded: Mapping[str, Any],
                    read: Mapping[str, tuple[int, str | None]]) -> None:
    """:class:`BagError` naming the first topic whose read-back (messages, SHA-256) is not
    what ``recorded`` (a summary's ``topics``) says, or that only one of them has."""
    for name in sorted(set(recorded) | set(read)):
        entry = recorded.get(name)
        count, sha = read.get(name, (0, None))
        if sha is None and entry is None:
            continue
        if sha is None or entry is None or entry.get("sha256") != sha \
                or entry.get("count") != count:
            got = "absent" if sha is None else f"{count} messages"
            want = "absent" if entry is None else f"{entry.get('count')} messages"
            raise BagError(f"{bag}: {name}: does not match summary.json (read back: {got}; "
                           f"recorded: {want}, digest differs): the bag is damaged or "
                           "truncated, or the summary belongs to another recording")


def verify_recording(run_dir: Path, summary: Mapping[str, Any]) -> None:
    """Check the run's ``bag/`` against ``summary`` (its ``topics``; a summary from before
    srr kept per-topic digests, or of a run that recorded nothing, is not checked)."""
    recorded = summary.get("topics") or {}
    if not recorded or not all(isinstance(v, Mapping) and v.get("sha256")
                               for v in recorded.values()):
        return
    bag = Path(run_dir) / "bag"
    check_read_back(bag, recorded, read_back(bag))
