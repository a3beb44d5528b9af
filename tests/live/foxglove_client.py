"""A small real Foxglove WebSocket client for the live-view tests (the ``websockets`` library,
the protocol's JSON control messages and binary data frames), independent of foxglove-sdk."""

from __future__ import annotations

import json
import struct
import threading
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect
from websockets.typing import Subprotocol

# The protocol's two names: foxglove-sdk's, and the ws-protocol specification's, which Lichtblick
# and @foxglove/ws-protocol clients offer alone (Foxglove offers both).
SUBPROTOCOL = "foxglove.sdk.v1"
LEGACY_SUBPROTOCOL = "foxglove.websocket.v1"
OP_MESSAGE_DATA = 0x01
OP_TIME = 0x02


@dataclass
class Received:
    server_info: dict[str, Any] = field(default_factory=dict)
    channels: dict[str, dict[str, Any]] = field(default_factory=dict)  # topic → advertised
    messages: dict[str, list[tuple[int, bytes]]] = field(default_factory=dict)  # (ns, CDR)
    times: list[int] = field(default_factory=list)  # server time broadcasts, ns
    texts: list[dict[str, Any]] = field(default_factory=list)  # other JSON messages
    subprotocol: str | None = None  # the one the server chose
    error: BaseException | None = None


def open_client(port: int, timeout: float = 30.0,
                subprotocol: str = SUBPROTOCOL) -> ClientConnection:
    """Connect to ``ws://127.0.0.1:port`` offering only ``subprotocol``, retrying while the
    server is not up yet."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            return connect(f"ws://127.0.0.1:{port}", subprotocols=[Subprotocol(subprotocol)],
                           open_timeout=5, max_size=None)
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.05)


class LiveClient:
    """Connects, waits for ``topics`` to be advertised, subscribes to them and records what
    arrives, on a thread, until the server closes the connection (or :meth:`close`).

    ``confirm``: send the subscription twice; the server warns "already subscribed" for each
    topic of the second once it took the first (it handles a client's messages in order), and
    :attr:`confirmed` is set when all warnings came (or the client ended: check ``error``)."""

    def __init__(self, port: int, topics: Iterable[str], *, timeout: float = 30.0,
                 subprotocol: str = SUBPROTOCOL, confirm: bool = False) -> None:
        self.port = port
        self.subprotocol = subprotocol
        self.confirm = confirm
        self.confirmed = threading.Event()
        self._acks = 0
        self.topics = list(topics)
        self.timeout = timeout
        self.got = Received()
        self.subscribed = threading.Event()
        self._ws: ClientConnection | None = None
        self._thread = threading.Thread(target=self._run, name="foxglove-test-client",
                                        daemon=True)

    def start(self) -> LiveClient:
        self._thread.start()
        return self

    def join(self, timeout: float | None = None) -> Received:
        self._thread.join(timeout if timeout is not None else self.timeout)
        assert not self._thread.is_alive(), "the client did not see the server close"
        if self.got.error is not None:
            raise self.got.error
        return self.got

    def close(self) -> None:
        if self._ws is not None:
            self._ws.close()

    def _run(self) -> None:
        try:
            self._ws = ws = open_client(self.port, self.timeout, self.subprotocol)
            self.got.subprotocol = ws.subprotocol
            with ws:
                self._handshake(ws)
                self._receive(ws)
        except ConnectionClosed:
            pass
        except BaseException as err:  # re-raised on the test's thread by join()
            self.got.error = err
        finally:
            self.confirmed.set()

    def _handshake(self, ws: ClientConnection) -> None:
        deadline = time.monotonic() + self.timeout
        while not set(self.topics) <= set(self.got.channels):
            msg = ws.recv(timeout=max(0.1, deadline - time.monotonic()))
            if isinstance(msg, bytes):
                self._binary(msg, {})
                continue
            data = json.loads(msg)
            if data["op"] == "serverInfo":
                self.got.server_info = data
            elif data["op"] == "advertise":
                self.got.channels.update({c["topic"]: c for c in data["channels"]})
            else:
                self.got.texts.append(data)
        self._subs = {i: topic for i, topic in enumerate(self.topics)}
        subscribe = json.dumps({"op": "subscribe", "subscriptions": [
            {"id": i, "channelId": self.got.channels[topic]["id"]}
            for i, topic in self._subs.items()]})
        ws.send(subscribe)
        if self.confirm:
            ws.send(subscribe)
        self.subscribed.set()

    def _receive(self, ws: ClientConnection) -> None:
        for msg in ws:
            if isinstance(msg, bytes):
                self._binary(msg, self._subs)
            else:
                data = json.loads(msg)
                if data["op"] == "advertise":
                    self.got.channels.update({c["topic"]: c for c in data["channels"]})
                elif self.confirm and data["op"] == "status" \
                        and "already subscribed" in data["message"]:
                    self._acks += 1
                    if self._acks == len(self.topics):
                        self.confirmed.set()
                else:
                    self.got.texts.append(data)

    def _binary(self, msg: bytes, subs: dict[int, str]) -> None:
        if msg[0] == OP_MESSAGE_DATA:
            sub_id, log_time = struct.unpack_from("<IQ", msg, 1)
            self.got.messages.setdefault(subs[sub_id], []).append((log_time, msg[13:]))
        elif msg[0] == OP_TIME:
            self.got.times.append(struct.unpack_from("<Q", msg, 1)[0])
