"""Two sizes of a message in CDR (XCDR1, little endian), computed from its rosbags values.

``exact`` is what a CDR writer produces: the 4-byte encapsulation header, then each value
aligned to its own size (strings and sequence lengths to 4), relative to the end of the
header; an empty sequence's elements add no alignment. rosbags writes exactly this.

``fastrtps`` is the length rclpy's ``serialize_message`` returns with rmw_fastrtps: the
type support's *size estimate* rather than the bytes written. It differs from ``exact`` in two
ways, both trailing and uninitialised:

* a fixed-size ("plain") type (no strings or sequences anywhere) is rounded up to a multiple
  of 4 (std_msgs/Bool: 8 bytes, exact 5);
* an empty sequence still gets the alignment of its element type, and from then on every
  alignment is computed from that shifted offset.

Asserting rclpy's length equals ``fastrtps`` and the recording's equals ``exact`` turns
"same length" into an exact check instead of a tolerance.
"""

from __future__ import annotations

from typing import Any

from rosbags.interfaces import Nodetype

from harness.serde.messages import TYPESTORE

__all__ = ["exact_size", "fastrtps_size", "is_plain"]

_SIZE = {
    "bool": 1, "byte": 1, "octet": 1, "char": 1, "int8": 1, "uint8": 1,
    "int16": 2, "uint16": 2, "int32": 4, "uint32": 4, "float32": 4,
    "int64": 8, "uint64": 8, "float64": 8,
}


def _align(offset: int, size: int) -> int:
    return (offset + size - 1) // size * size


def _string(offset: int, text: str) -> int:
    return _align(offset, 4) + 4 + len(text.encode("utf-8")) + 1


def _items(offset: int, desc: Any, values: Any, estimate: bool) -> int:
    kind, sub = desc
    if kind == Nodetype.BASE and sub[0] in ("string", "wstring"):
        for text in values:
            offset = _string(offset, text)
        return offset
    if kind == Nodetype.BASE:
        size = _SIZE[sub[0]]
        if len(values) == 0 and not estimate:
            return offset
        return _align(offset, size) + size * len(values)
    for value in values:
        offset = _message(offset, sub, value, estimate)
    return offset


def _fields(typename: str) -> list[tuple[str, Any]]:
    _consts, fields = TYPESTORE.fielddefs[typename]
    return [(name, desc) for name, desc in fields]


def _message(offset: int, typename: str, msg: Any, estimate: bool) -> int:
    for name, (kind, sub) in _fields(typename):
        value = getattr(msg, name)
        if kind == Nodetype.BASE and sub[0] in ("string", "wstring"):
            offset = _string(offset, value)
        elif kind == Nodetype.BASE:
            size = _SIZE[sub[0]]
            offset = _align(offset, size) + size
        elif kind == Nodetype.NAME:
            offset = _message(offset, sub, value, estimate)
        elif kind == Nodetype.ARRAY:
            offset = _items(offset, sub[0], value, estimate)
        else:  # SEQUENCE: uint32 length, then the items
            offset = _items(_align(offset, 4) + 4, sub[0], value, estimate)
    return offset


def is_plain(typename: str) -> bool:
    """No strings and no sequences anywhere inside: a fixed-size type."""
    for _name, (kind, sub) in _fields(typename):
        if kind == Nodetype.SEQUENCE:
            return False
        inner_kind, inner = sub[0] if kind == Nodetype.ARRAY else (kind, sub)
        if inner_kind == Nodetype.BASE and inner[0] in ("string", "wstring"):
            return False
        if inner_kind == Nodetype.NAME and not is_plain(inner):
            return False
    return True


def exact_size(typename: str, msg: Any) -> int:
    """Bytes a CDR writer produces for ``msg``, header included."""
    return 4 + _message(0, typename, msg, estimate=False)


def fastrtps_size(typename: str, msg: Any) -> int:
    """The buffer length rmw_fastrtps's serialize_message reports for ``msg``."""
    size = 4 + _message(0, typename, msg, estimate=True)
    return _align(size, 4) if is_plain(typename) else size
