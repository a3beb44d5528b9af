"""Headless Chromium for the report tests: a fresh profile per call and no network."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path

__all__ = ["CHROMIUM_FLAGS", "VIEWPORT", "chromium_path", "page_requests", "run_chromium"]

CHROMIUM_FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--hide-scrollbars",
    # any network request the page might make fails instead of leaving the machine
    "--proxy-server=127.0.0.1:9", "--host-resolver-rules=MAP * ~NOTFOUND",
]
VIEWPORT = (1280, 900)


def chromium_path() -> str | None:
    explicit = os.environ.get("SRR_CHROMIUM")
    if explicit:
        return explicit
    for name in ("/usr/bin/chromium", "chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return found
    return None


def run_chromium(binary: str, tmp: Path, url: str, extra: Sequence[str], *,
                 console: list[str] | None = None) -> str:
    """Run Chromium once with a fresh profile; return stdout (the DOM for --dump-dom).
    With ``console``, the page's console messages (errors included) are appended to it."""
    profile = tmp / f"profile-{len(list(tmp.glob('profile-*')))}"
    logging = ["--enable-logging=stderr", "--v=0"] if console is not None else []
    cmd = [binary, *CHROMIUM_FLAGS, *logging, f"--user-data-dir={profile}",
           f"--window-size={VIEWPORT[0]},{VIEWPORT[1]}", *extra, url]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False)
    if proc.returncode != 0:
        raise AssertionError(f"chromium exited {proc.returncode}: {proc.stderr[-2000:]}")
    if console is not None:
        console += [line for line in proc.stderr.splitlines() if ":CONSOLE" in line]
    return proc.stdout


def page_requests(netlog: Path) -> list[str]:
    """URLs the page itself asked for, from a ``--log-net-log`` file (the browser's own
    background traffic, e.g. update checks, has no file:// isolation key and is left out)."""
    log = json.loads(netlog.read_text(encoding="utf-8"))
    start = log["constants"]["logEventTypes"]["URL_REQUEST_START_JOB"]
    out = []
    for e in log["events"]:
        p = e.get("params") or {}
        if e["type"] == start and "file://" in str(p.get("network_isolation_key", "")):
            url = str(p.get("url", ""))
            if not url.startswith(("file:", "data:")):
                out.append(url)
    return out
