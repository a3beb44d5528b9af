"""The live view's listening socket: a front that lets clients of either name of the Foxglove
WebSocket protocol reach foxglove-sdk's server.

The protocol is named ``foxglove.websocket.v1`` in its specification (foxglove/ws-protocol)
and by the clients built on it: Lichtblick (the open-source fork of Foxglove Studio),
``@foxglove/ws-protocol``, older Foxglove apps. foxglove-sdk's server names the same protocol
``foxglove.sdk.v1`` and answers a WebSocket handshake that offers only the old name with
HTTP 400. Every foxglove-sdk release up to the newest (0.30.3) does so, and none has a setting
for it, so neither an upgrade nor an option helps; the two names carry the same messages
(Foxglove's bridge moved from one name to the other without changing them, and clients that
added the new name changed nothing else).

So srr listens itself, on the address the user gave, and hands every connection to the SDK's
server on a loopback port of its own: a handshake offering ``foxglove.websocket.v1`` without
``foxglove.sdk.v1`` is passed on offering ``foxglove.sdk.v1``, and the server's answer is
passed back naming ``foxglove.websocket.v1`` (the name the client asked for; the handshake's
``Sec-WebSocket-Accept`` depends only on the client's key). Any other handshake, and every
byte after the handshake in both directions, goes through unchanged.
"""

from __future__ import annotations

import contextlib
import socket
import threading
import time

__all__ = ["LEGACY_SUBPROTOCOL", "MAX_HEAD", "SDK_SUBPROTOCOL", "SubprotocolFront"]

SDK_SUBPROTOCOL = "foxglove.sdk.v1"
LEGACY_SUBPROTOCOL = "foxglove.websocket.v1"
#: Largest HTTP head (request line and headers) accepted before the connection is dropped.
MAX_HEAD = 64 * 1024
_CHUNK = 1 << 20
_HEADER = b"sec-websocket-protocol:"


def _read_head(sock: socket.socket) -> tuple[bytes, bytes] | None:
    """An HTTP head (up to and including the blank line) and the bytes read after it; None
    when the peer closed first or the head is too long."""
    buf = b""
    while b"\r\n\r\n" not in buf:
        if len(buf) > MAX_HEAD:
            return None
        data = sock.recv(65536)
        if not data:
            return None
        buf += data
    end = buf.index(b"\r\n\r\n") + 4
    return buf[:end], buf[end:]


def _offered(head: bytes) -> list[str]:
    """The subprotocols a handshake request offers (every ``Sec-WebSocket-Protocol`` line)."""
    names: list[str] = []
    for line in head.split(b"\r\n")[1:]:
        if line.lower().startswith(_HEADER):
            names += [n.strip() for n in line[len(_HEADER):].decode("latin-1").split(",")]
    return [n for n in names if n]


def _with_subprotocol(head: bytes, name: str) -> bytes:
    """``head`` with its ``Sec-WebSocket-Protocol`` lines replaced by one naming ``name``."""
    lines = head.split(b"\r\n")
    kept = [ln for ln in lines[:-2] if not ln.lower().startswith(_HEADER)]
    return b"\r\n".join([*kept, b"Sec-WebSocket-Protocol: " + name.encode("ascii"), b"", b""])


def _pump(src: socket.socket, dst: socket.socket) -> None:
    """Copy ``src`` to ``dst`` until ``src`` ends, then end ``dst``'s sending side."""
    try:
        while data := src.recv(_CHUNK):
            dst.sendall(data)
    except OSError:
        pass
    finally:
        with contextlib.suppress(OSError):
            dst.shutdown(socket.SHUT_WR)


class SubprotocolFront:
    """Listens on ``host:port`` (port 0: a free one, see :attr:`port`) and relays every
    connection to ``127.0.0.1:backend_port``, renaming the subprotocol as the module says.
    Binding errors are the ``OSError`` of the bind, raised by the constructor."""

    def __init__(self, host: str, port: int, backend_port: int) -> None:
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        self._listener = socket.create_server((host, port), family=family)
        self.port = int(self._listener.getsockname()[1])
        self._backend = ("127.0.0.1", backend_port)
        self._lock = threading.Lock()
        self._sockets: set[socket.socket] = set()
        self._greeting: set[socket.socket] = set()  # clients whose handshake is not through
        self._threads: list[threading.Thread] = []
        self._closing = False
        self._acceptor = threading.Thread(target=self._accept, name="srr-live-front",
                                          daemon=True)
        self._acceptor.start()

    def _accept(self) -> None:
        while True:
            try:
                client, _addr = self._listener.accept()
            except OSError:  # the listener was shut down by close()
                return
            t = threading.Thread(target=self._relay, args=(client,), name="srr-live-relay",
                                 daemon=True)
            with self._lock:
                if self._closing:
                    client.close()
                    return
                self._sockets.add(client)
                self._greeting.add(client)
                self._threads = [x for x in self._threads if x.is_alive()] + [t]
            t.start()

    def _relay(self, client: socket.socket) -> None:
        """One connection: the handshake (renamed when needed), then bytes both ways until
        both sides have ended."""
        backend: socket.socket | None = None
        try:
            got = _read_head(client)
            if got is None:
                return
            head, rest = got
            offered = _offered(head)
            rename = LEGACY_SUBPROTOCOL in offered and SDK_SUBPROTOCOL not in offered
            backend = socket.create_connection(self._backend)
            with self._lock:
                self._sockets.add(backend)
            for s in (client, backend):
                s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            backend.sendall((_with_subprotocol(head, SDK_SUBPROTOCOL) if rename else head)
                            + rest)
            if rename:  # the answer names the protocol the client asked for
                answer = _read_head(backend)
                if answer is None:
                    return
                ahead, arest = answer
                if SDK_SUBPROTOCOL in _offered(ahead):
                    ahead = _with_subprotocol(ahead, LEGACY_SUBPROTOCOL)
                client.sendall(ahead + arest)
            with self._lock:
                self._greeting.discard(client)
            back = threading.Thread(target=_pump, args=(backend, client),
                                    name="srr-live-relay", daemon=True)
            back.start()
            _pump(client, backend)
            back.join()
        except OSError:
            pass
        finally:
            for end in (client, backend):
                if end is not None:
                    with self._lock:
                        self._sockets.discard(end)
                        self._greeting.discard(end)
                    end.close()

    def stop_accepting(self) -> None:
        """Take no new connection (the ones open go on)."""
        with self._lock:
            if self._closing:
                return
            self._closing = True
        with contextlib.suppress(OSError):
            self._listener.shutdown(socket.SHUT_RDWR)
        self._listener.close()
        self._acceptor.join()

    def cut(self) -> None:
        """End every open connection now, from this side (a client that stopped reading
        holds its relay, and the server's send to it, until its socket is shut down)."""
        with self._lock:
            left = list(self._sockets)
        for s in left:  # wakes their relays, which close them
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)

    def close(self, timeout_s: float = 5.0) -> None:
        """Stop accepting and wait, at most ``timeout_s``, for the open connections to end
        (call it after stopping the server behind, which ends them); then cut what is left.
        Safe to call twice."""
        self.stop_accepting()
        deadline = time.monotonic() + timeout_s
        with self._lock:
            threads = list(self._threads)
            greeting = list(self._greeting)
        for s in greeting:  # the server never saw these: nothing will end them
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)
        for t in threads:
            t.join(max(0.0, deadline - time.monotonic()))
        self.cut()
        for t in threads:
            t.join(1.0)
