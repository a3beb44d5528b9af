"""CDR serialization of ROS 2 messages from layouts compiled once per message type.

The bytes are those of the rosbags typestore's serializer (little-endian XCDR1 as ROS 2 writes
it: the 4-byte encapsulation header ``00 01 00 00``, then every primitive aligned to its own
size, at most 8, counted from the end of the header; no trailing padding). rosbags generates
one Python function per type that packs field by field; here a type is compiled into
*segments* instead:

* a :class:`_Run` is a stretch of the flattened message with no sequence in it: numbers,
  strings and fixed-size numeric arrays, read with one :func:`operator.attrgetter` over their
  dotted paths and written with one precompiled :class:`struct.Struct`. The padding inside a
  run depends only on where the run starts modulo 8 and on the byte lengths of its strings, so
  a run keeps one ``Struct`` per such shape (a frame id does not change from message to
  message, so in practice one or two);
* a :class:`_Sequence` is a sequence field: its count, then its elements (numbers as one block
  of bytes, strings, or messages through the element type's own segments).

A message is written by its segments in order into one ``bytearray``. Anything the layout
does not expect (a value of another type, an array of another length or dtype, a string of a
type rosbags could not encode) makes the :class:`Serializer` hand the message to rosbags, so
what comes out — bytes or error — is always what rosbags would give. Types this module does not
compile (fixed arrays of strings or messages; none in ROS 2 Jazzy's standard set) go to
rosbags too.

A publisher whose messages keep one shape (the same frame ids, the same number of
transforms) does not need message objects at all: a :class:`Packer` lays out the whole
message once, from a template message, and packs each message from the values of its
varying numbers alone, with one ``Struct`` call.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass
from operator import attrgetter, itemgetter
from typing import Any, Protocol, Self

import numpy as np
from rosbags.interfaces import Nodetype
from rosbags.typesys.store import Typestore

from harness.serde.pieces import Piece, Pieces

__all__ = ["CDR_HEADER", "Layout", "Packer", "Serializer", "Unsupported"]

#: Encapsulation header of little-endian plain CDR (what ROS 2 publishes).
CDR_HEADER = b"\x00\x01\x00\x00"
_HEADER_LEN = len(CDR_HEADER)

# Struct codes of the base types, as rosbags packs them (``byte`` signed, ``char`` unsigned).
_CODES: dict[str, str] = {
    "bool": "?", "byte": "b", "char": "B", "int8": "b", "uint8": "B",
    "int16": "h", "uint16": "H", "int32": "i", "uint32": "I", "int64": "q", "uint64": "Q",
    "float32": "f", "float64": "d",
}
_SIZES: dict[str, int] = {name: struct.calcsize("<" + code) for name, code in _CODES.items()}
_COUNT = struct.Struct("<i")  # sequence counts and string lengths (rosbags packs int32)


class Unsupported(Exception):
    """The type has a field this module does not lay out; rosbags serializes it."""


class _Mismatch(Exception):
    """A value does not fit the layout; rosbags serializes the message (and judges it)."""


# -- leaves of a run ---------------------------------------------------------------------------

class _Out(Protocol):
    """Where a message's bytes are written: a ``bytearray``, or :class:`Pieces`."""

    def __len__(self) -> int: ...

    def __iadd__(self, data: bytes | memoryview, /) -> Self: ...


@dataclass(frozen=True)
class _Leaf:
    """One value of a run: a number (``count`` 0), a string, or a fixed numeric array."""

    path: str
    base: str  # base type name, or "string"
    count: int = 0  # elements of a fixed array; 0 for a single value

    @property
    def align(self) -> int:
        return 4 if self.base == "string" else _SIZES[self.base]


def _pad(offset: int, align: int) -> int:
    return -offset % align


class _Run:
    """Consecutive leaves without a sequence between them, packed with one Struct per shape.

    The shape is the start offset modulo 8 plus the encoded length of each string; the
    :class:`struct.Struct` of a shape is built the first time it is met.
    """

    __slots__ = ("_arrays", "_get", "_leaves", "_single", "_strings", "_structs")

    def __init__(self, leaves: list[_Leaf]) -> None:
        self._leaves = tuple(leaves)
        paths = [leaf.path for leaf in leaves]
        self._get = attrgetter(*paths)
        self._single = len(paths) == 1  # attrgetter of one path gives the value, not a tuple
        self._strings = tuple(i for i, leaf in enumerate(leaves) if leaf.base == "string")
        self._arrays = tuple((i, _SIZES[leaf.base], leaf.count)
                             for i, leaf in enumerate(leaves) if leaf.count)
        self._structs: dict[tuple[int, ...], struct.Struct] = {}

    def write(self, out: _Out, msg: Any) -> None:
        got = self._get(msg)
        values: list[Any] = [got] if self._single else list(got)
        shape: tuple[int, ...] = ((len(out) - _HEADER_LEN) & 7,)
        for i in self._strings:
            text = values[i]
            if type(text) is not str:
                raise _Mismatch
            data = text.encode()
            values[i] = _COUNT.pack(len(data) + 1) + data  # the 's' code pads the NUL
            shape += (len(data),)
        for i, size, count in self._arrays:
            values[i] = _array_bytes(values[i], size, count)
        packer = self._structs.get(shape)
        if packer is None:
            packer = self._structs[shape] = self._struct(shape)
        try:
            out += packer.pack(*values)
        except struct.error as err:  # a value of the wrong type or range
            raise _Mismatch from err

    def _struct(self, shape: tuple[int, ...]) -> struct.Struct:
        offset, lengths = shape[0], iter(shape[1:])
        fmt = ["<"]
        for leaf in self._leaves:
            pad = _pad(offset, leaf.align)
            if pad:
                fmt.append(f"{pad}x")
            offset += pad
            if leaf.base == "string":
                size = 4 + next(lengths) + 1
                fmt.append(f"{size}s")
            elif leaf.count:
                size = leaf.count * _SIZES[leaf.base]
                fmt.append(f"{size}s")
            else:
                size = _SIZES[leaf.base]
                fmt.append(_CODES[leaf.base])
            offset += size
        return struct.Struct("".join(fmt))


def _array_view(value: Any, size: int) -> memoryview:
    """The raw bytes of a 1-d numpy array of elements of ``size`` bytes, without a copy (an
    image's data is copied once, into the message); anything else is a mismatch."""
    if (type(value) is not np.ndarray or value.ndim != 1 or value.itemsize != size
            or not value.flags.c_contiguous):
        raise _Mismatch
    return memoryview(value.data).cast("B")


def _array_bytes(value: Any, size: int, count: int | None) -> bytes:
    """The raw bytes of a 1-d numpy array of ``count`` elements (any count when None) of
    ``size`` bytes each, as rosbags copies them; anything else is a mismatch."""
    if type(value) is not np.ndarray or value.ndim != 1 or value.itemsize != size:
        raise _Mismatch
    if count is not None and len(value) != count:
        raise _Mismatch
    if not value.flags.c_contiguous:
        raise _Mismatch
    return value.tobytes()


# -- sequences ---------------------------------------------------------------------------------

class _Sequence:
    """A sequence field: its int32 count, then the elements."""

    __slots__ = ("_align", "_base", "_get", "_layout")

    def __init__(self, path: str, base: str | None, element: Layout | None) -> None:
        self._get = attrgetter(path)
        self._base = base  # "string" or a number type; None for messages
        self._align = _SIZES[base] if base is not None and base != "string" else 0
        self._layout = element

    def write(self, out: _Out, msg: Any) -> None:
        items = self._get(msg)
        out += bytes(_pad(len(out) - _HEADER_LEN, 4))
        if self._layout is not None:
            out += _COUNT.pack(len(items))
            for item in items:
                self._layout.write(out, item)
        elif self._base == "string":
            out += _COUNT.pack(len(items))
            for text in items:
                if type(text) is not str:
                    raise _Mismatch
                encoded = text.encode()
                out += bytes(_pad(len(out) - _HEADER_LEN, 4))
                out += _COUNT.pack(len(encoded) + 1) + encoded + b"\0"
        else:
            view = _array_view(items, self._align)
            out += _COUNT.pack(len(items))
            if len(view):
                out += bytes(_pad(len(out) - _HEADER_LEN, self._align))
                if isinstance(out, Pieces):
                    out.keep(view.toreadonly())
                else:
                    out += view


# -- layouts -----------------------------------------------------------------------------------

class Layout:
    """The segments of one message type (see the module docstring)."""

    __slots__ = ("msgtype", "segments")

    def __init__(self, msgtype: str, segments: tuple[_Run | _Sequence, ...]) -> None:
        self.msgtype = msgtype
        self.segments = segments

    def write(self, out: _Out, msg: Any) -> None:
        """Append ``msg``'s CDR body to ``out`` (which starts with the 4-byte header)."""
        for segment in self.segments:
            segment.write(out, msg)

    def serialize(self, msg: Any) -> bytes:
        """``msg`` as CDR bytes; raises :class:`_Mismatch` when it does not fit the layout."""
        out = bytearray(CDR_HEADER)
        for segment in self.segments:
            segment.write(out, msg)
        return bytes(out)

    def serialize_pieces(self, msg: Any) -> tuple[Piece, ...]:
        """``msg``'s CDR bytes as pieces in order, each numeric array of
        :data:`~harness.serde.pieces.LARGE` bytes or more as a read-only view of the message's
        own array (not copied); raises :class:`_Mismatch` when it does not fit the layout."""
        out = Pieces(CDR_HEADER)
        for segment in self.segments:
            segment.write(out, msg)
        return out.pieces()


def _fields(typestore: Typestore, msgtype: str) -> list[tuple[str, Nodetype, Any]]:
    """``(name, kind, detail)`` of each field of ``msgtype`` (``detail`` as the typestore
    gives it: a base type and bound, a type name, or an element and a length)."""
    _, fields = typestore.fielddefs[msgtype]
    return [(name, desc[0], desc[1]) for name, desc in fields]


def _compile(typestore: Typestore, msgtype: str, element: Callable[[str], Layout]) -> Layout:
    segments: list[_Run | _Sequence] = []
    leaves: list[_Leaf] = []

    def flush() -> None:
        if leaves:
            segments.append(_Run(list(leaves)))
            leaves.clear()

    def walk(name: str, prefix: str) -> None:
        for field, kind, detail in _fields(typestore, name):
            path = prefix + field
            if kind == Nodetype.BASE:
                base = detail[0]
                if base != "string" and base not in _CODES:
                    raise Unsupported(f"{name}.{field}: base type {base}")
                leaves.append(_Leaf(path, base))
            elif kind == Nodetype.NAME:
                walk(detail, path + ".")
            elif kind == Nodetype.ARRAY:
                (sub_kind, sub), count = detail
                if sub_kind != Nodetype.BASE or sub[0] not in _CODES:
                    raise Unsupported(f"{name}.{field}: fixed array of {sub}")
                leaves.append(_Leaf(path, sub[0], count))
            elif kind == Nodetype.SEQUENCE:
                (sub_kind, sub), _ = detail
                flush()
                if sub_kind == Nodetype.NAME:
                    segments.append(_Sequence(path, None, element(sub)))
                elif sub[0] == "string" or sub[0] in _CODES:
                    segments.append(_Sequence(path, sub[0], None))
                else:
                    raise Unsupported(f"{name}.{field}: sequence of {sub}")
            else:
                raise Unsupported(f"{name}.{field}: field kind {kind}")

    walk(msgtype, "")
    flush()
    return Layout(msgtype, tuple(segments))


class Serializer:
    """CDR serialization for the types of one typestore: compiled layouts where they exist,
    ``fallback`` (rosbags) for the rest and for any message a layout does not fit, so the
    result — bytes or error — is always the fallback's."""

    def __init__(self, typestore: Typestore, fallback: Callable[[Any, str], bytes]) -> None:
        self._typestore = typestore
        self._fallback = fallback
        self._layouts: dict[str, Layout | None] = {}

    def layout(self, msgtype: str) -> Layout | None:
        """The compiled layout of ``msgtype``, or None when rosbags must serialize it."""
        try:
            return self._layouts[msgtype]
        except KeyError:
            pass
        if msgtype not in self._typestore.fielddefs:
            return None  # unknown (for now): the fallback says so, and it may be added later
        try:
            made: Layout | None = self._compile(msgtype)
        except Unsupported:
            made = None
        self._layouts[msgtype] = made
        return made

    def _compile(self, msgtype: str) -> Layout:
        def element(name: str) -> Layout:
            compiled = self.layout(name)
            if compiled is None:
                raise Unsupported(f"{msgtype}: elements of type {name}")
            return compiled

        return _compile(self._typestore, msgtype, element)

    def __call__(self, msg: Any, msgtype: str) -> bytes:
        compiled = self._layouts.get(msgtype) or self.layout(msgtype)
        if compiled is not None:
            try:
                return compiled.serialize(msg)
            except Exception:
                pass
        return self._fallback(msg, msgtype)

    def pieces(self, msg: Any, msgtype: str) -> tuple[Piece, ...]:
        """The same bytes as calling the serializer, as :meth:`Layout.serialize_pieces`
        gives them (one piece from the fallback). The large pieces are views of the
        message's arrays: the message must not change while they are in use."""
        compiled = self._layouts.get(msgtype) or self.layout(msgtype)
        if compiled is not None:
            try:
                return compiled.serialize_pieces(msg)
            except Exception:
                pass
        return (self._fallback(msg, msgtype),)


# -- packers: a fixed shape, from values ---------------------------------------------------------

def _flatten(typestore: Typestore, msgtype: str, msg: Any, prefix: str,
             out: list[tuple[str, str, Any]]) -> None:
    """Every value of ``msg`` in serialization order as ``(path, kind, value)``: ``kind`` is a
    base type name for numbers, ``"string"``, ``"count"`` (a sequence's length) or
    ``"bytes:<size>"`` (the data of a numeric array; ``value`` is the array)."""
    for field, kind, detail in _fields(typestore, msgtype):
        path, value = prefix + field, getattr(msg, field)
        if kind == Nodetype.BASE:
            out.append((path, detail[0], value))
        elif kind == Nodetype.NAME:
            _flatten(typestore, detail, value, path + ".", out)
        elif kind == Nodetype.ARRAY:
            (_, sub), _ = detail
            out.append((path, f"bytes:{_SIZES[sub[0]]}", value))
        else:
            (sub_kind, sub), _ = detail
            out.append((path, "count", len(value)))
            if sub_kind == Nodetype.NAME:
                for i, item in enumerate(value):
                    _flatten(typestore, sub, item, f"{path}[{i}].", out)
            elif sub[0] == "string":
                for i, item in enumerate(value):
                    out.append((f"{path}[{i}]", "string", item))
            elif len(value):
                out.append((path, f"bytes:{_SIZES[sub[0]]}", value))


class Packer:
    """CDR bytes of messages of one fixed shape, from the values of their varying numbers.

    ``template`` is a message of ``msgtype`` with the strings, sequence lengths and constant
    values every message will have; ``variables`` are the dotted paths of the numbers that
    vary (sequence elements are indexed: ``transforms[0].header.stamp.sec``), in the order
    :meth:`pack` takes them. The bytes are those of the template with those numbers
    replaced, as rosbags would serialize it.
    """

    __slots__ = ("_constants", "_order", "_struct", "msgtype", "variables")

    def __init__(self, typestore: Typestore, msgtype: str, template: Any,
                 variables: tuple[str, ...]) -> None:
        self.msgtype = msgtype
        self.variables = variables
        leaves: list[tuple[str, str, Any]] = []
        _flatten(typestore, msgtype, template, "", leaves)
        numbers = {path: kind for path, kind, _ in leaves if kind in _CODES}
        unknown = [v for v in variables if v not in numbers]
        if unknown:
            raise ValueError(f"{msgtype}: no number field {unknown[0]!r} in the template")
        constants: list[Any] = [CDR_HEADER]
        sources: list[int] = [0]  # per Struct argument: its index in constants + values
        variable_at = {path: i for i, path in enumerate(variables)}
        fmt, offset = ["<4s"], 0
        for path, kind, value in leaves:
            if kind == "string":
                data = _COUNT.pack(len(value.encode()) + 1) + value.encode()
                align, size, code, value = 4, len(data) + 1, f"{len(data) + 1}s", data
            elif kind == "count":
                align, size, code = 4, 4, "i"
            elif kind.startswith("bytes:"):
                align = int(kind.partition(":")[2])
                value = _array_bytes(value, align, None)
                size, code = len(value), f"{len(value)}s"
            else:
                align = size = _SIZES[kind]
                code = _CODES[kind]
            pad = _pad(offset, align)
            if pad:
                fmt.append(f"{pad}x")
            offset += pad + size
            fmt.append(code)
            if path in variable_at and kind in _CODES:
                sources.append(-1 - variable_at[path])  # resolved below
            else:
                sources.append(len(constants))
                constants.append(value)
        n = len(constants)
        self._constants = tuple(constants)
        self._order = itemgetter(*(i if i >= 0 else n + (-1 - i) for i in sources))
        self._struct = struct.Struct("".join(fmt))

    def pack(self, *values: Any) -> bytes:
        """The message with ``values`` for :attr:`variables`, as CDR bytes."""
        if len(values) != len(self.variables):
            raise ValueError(f"{self.msgtype}: {len(self.variables)} values expected, "
                             f"got {len(values)}")
        return self._struct.pack(*self._order(self._constants + values))
