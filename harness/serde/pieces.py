"""Bytes assembled in order without copying large buffers: one accumulator for a message's CDR
in pieces (:meth:`harness.serde.cdr.Layout.serialize_pieces`) and for an MCAP chunk being filled
(:class:`harness.recording.mcap_writer.McapWriter`).

Small writes are appended to a ``bytearray``; a buffer of :data:`LARGE` bytes or more given to
:meth:`Pieces.keep` is kept as it is, after the bytes written before it. ``len`` counts every
byte written, like a ``bytearray``'s, so offsets and padding come out as if it had been one.
"""

from __future__ import annotations

from typing import Self

__all__ = ["LARGE", "Piece", "Pieces"]

#: Buffers of at least this many bytes are kept as they are, not copied.
LARGE = 64 * 1024

#: One piece of the bytes: a buffer kept, or a run of small writes.
Piece = bytes | bytearray | memoryview


class Pieces:
    """An ordered run of bytes held as pieces (see the module docstring). A kept buffer must
    not change while the pieces are in use."""

    __slots__ = ("_done", "_size", "_tail")

    def __init__(self, head: bytes = b"") -> None:
        self._done: list[Piece] = []
        self._size = 0  # bytes in _done
        self._tail = bytearray(head)

    def __len__(self) -> int:
        return self._size + len(self._tail)

    def __iadd__(self, data: Piece, /) -> Self:
        """Append ``data`` (copied, whatever its size)."""
        self._tail += data
        return self

    def append(self, head: bytes, data: Piece = b"") -> int:
        """Append ``head`` (copied) and then ``data`` (as :meth:`keep` does); returns the
        offset at which ``head`` starts. One call for a record's head and small payload."""
        tail = self._tail
        offset = self._size + len(tail)
        tail += head
        if len(data) < LARGE:
            tail += data
        else:
            self.keep(data)
        return offset

    def keep(self, data: Piece) -> None:
        """Append ``data``: kept as it is when it is :data:`LARGE` or more, else copied."""
        if len(data) < LARGE:
            self._tail += data
            return
        if self._tail:
            self._done.append(self._tail)
            self._size += len(self._tail)
            self._tail = bytearray()
        self._done.append(data)
        self._size += len(data)

    def pieces(self) -> tuple[Piece, ...]:
        """Every piece, in order (the small writes since the last kept buffer last)."""
        return (*self._done, self._tail) if self._tail else tuple(self._done)
