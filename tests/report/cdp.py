"""A script-driven headless Chromium for the report tests, over the DevTools protocol
(``websockets``, a dev dependency): open a page, evaluate script in it (awaiting promises),
read what it returns. The browser runs with the network unreachable (the flags of
:data:`tests.report.browser.CHROMIUM_FLAGS`) and a fresh profile.

Waits are on the browser's own events (a promise the page script resolves, the DevTools
endpoint file Chromium writes); the timeouts only bound a broken browser.
"""

from __future__ import annotations

import json
import subprocess
import time
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from websockets.sync.client import ClientConnection, connect

from tests.report.browser import CHROMIUM_FLAGS, VIEWPORT

__all__ = ["LOOPBACK_ONLY", "VIDEO_READY", "Page", "open_page"]

STARTUP_S = 60.0


class Page:
    """One page target: :meth:`eval` runs an expression (a promise is awaited)."""

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        self._id = 0

    def call(self, method: str, timeout: float = 60.0, **params: Any) -> dict[str, Any]:
        """Send a command and return its result (events in between are dropped)."""
        self._id += 1
        mid = self._id
        self.ws.send(json.dumps({"id": mid, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv(timeout=timeout))
            if msg.get("id") == mid:
                if "error" in msg:
                    raise AssertionError(f"{method}: {msg['error']}")
                return dict(msg.get("result", {}))

    def eval(self, expression: str, timeout: float = 60.0) -> Any:
        res = self.call("Runtime.evaluate", timeout=timeout, expression=expression,
                        awaitPromise=True, returnByValue=True)
        if "exceptionDetails" in res:
            d = res["exceptionDetails"]
            why = d.get("exception", {}).get("description") or d
            raise AssertionError(f"page script failed: {why}")
        return res["result"].get("value")


#: Page script defining ``ready(v)``: a promise that resolves once the ``<video>`` ``v`` has a
#: frame to show (``readyState`` 2 or more) and fails on a media error. Waiting for
#: ``loadeddata`` alone can hang: the report's cursor seeks a video as soon as its metadata
#: is in, so ``loadeddata`` may come while that seek holds ``readyState`` at 1, and it does
#: not come again (``seeked`` does).
VIDEO_READY = """function ready(v) { return new Promise(function (ok, no) {
  function check() { if (v.readyState >= 2) { ok(v); } }
  function fail() { no(new Error(v.src + ": " + v.error.message)); }
  if (v.error) { fail(); return; }
  ["loadeddata", "canplay", "seeked"].forEach(function (n) { v.addEventListener(n, check); });
  v.addEventListener("error", fail);
  check(); }); }"""


#: The host-resolver rule that, with ``loopback``, lets a page reach a server of the test's
#: on 127.0.0.1 (and nothing else).
LOOPBACK_ONLY = "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1"


@contextmanager
def open_page(binary: str, tmp: Path, url: str, *, loopback: bool = False) -> Iterator[Page]:
    """Chromium with ``url`` loaded (its ``load`` event fired), driven over DevTools.
    ``loopback``: 127.0.0.1 is reachable (a server the test runs), nothing else is."""
    profile = tmp / f"cdp-profile-{len(list(tmp.glob('cdp-profile-*')))}"
    profile.mkdir()
    flags = [LOOPBACK_ONLY if loopback and f.startswith("--host-resolver-rules=") else f
             for f in CHROMIUM_FLAGS]
    cmd = [binary, *flags, f"--user-data-dir={profile}", "--remote-debugging-port=0",
           f"--window-size={VIEWPORT[0]},{VIEWPORT[1]}",
           "--autoplay-policy=no-user-gesture-required", "--mute-audio",
           # file:// pages are one origin: a canvas with a drawn video frame can be read back
           "--allow-file-access-from-files", "about:blank"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        port_file = profile / "DevToolsActivePort"
        deadline = time.monotonic() + STARTUP_S
        while not (port_file.is_file() and port_file.read_text().strip()):
            if proc.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"chromium did not open its DevTools port (exit "
                                     f"{proc.poll()})")
            time.sleep(0.05)
        port = int(port_file.read_text().split()[0])
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=30) as r:
            targets = json.loads(r.read())
        page_ws = next(t["webSocketDebuggerUrl"] for t in targets if t["type"] == "page")
        with connect(page_ws, max_size=2**26, open_timeout=30) as ws:
            page = Page(ws)
            page.call("Page.navigate", url=url)
            # the page is ours once its document has loaded (an evaluation in the blank
            # page it replaces may fail: the context goes away)
            check = (f"location.href === {json.dumps(url)} && "
                     "document.readyState === 'complete'")
            deadline = time.monotonic() + STARTUP_S
            while True:
                try:
                    if page.eval(check) is True:
                        break
                except AssertionError:
                    pass
                if time.monotonic() > deadline:
                    raise AssertionError(f"{url} did not load")
                time.sleep(0.05)
            yield page
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
