"""Field-by-field comparison of decoded ROS 2 messages, whoever decoded them.

Both sides may be a rosbags typestore dataclass or an rclpy message class instance; the walk
normalises what differs only in representation and reports everything else:

* messages: the field names (in order) must agree, then every field is compared;
* primitive arrays: ``numpy.ndarray`` (rosbags), ``array.array`` / ``numpy.ndarray`` / list
  (rclpy) are compared as arrays of the same shape; floats bit for bit (a CDR round
  trip must not change a single bit, so ``-0.0 != 0.0`` and NaN payloads count); one-byte
  integers as raw bytes (ROS ``byte``/``octet`` is signed in rosbags, ``bytes`` in rclpy);
* scalars: floats bit for bit, ints and bools by value and kind, strings exactly; rclpy's
  ``bytes`` of length 1 (a ``byte`` field) equals rosbags' int with the same low byte.

Padding never enters: only decoded values are compared.
"""

from __future__ import annotations

import array
import dataclasses
import struct
from collections.abc import Sequence
from typing import Any

import numpy as np

from harness.serde.messages import TYPESTORE

__all__ = ["message_fields", "value_diff"]

_MAX_REPORTS = 20
# An empty .msg (std_msgs/Empty) gets this uint8 member in IDL; rosbags shows it, rclpy hides it
# and always writes 0: it carries no value.
_EMPTY_PLACEHOLDER = "structure_needs_at_least_one_member"


def message_fields(value: Any) -> list[str] | None:
    """The field names of a decoded message, in definition order, or None for a non-message."""
    rclpy_fields = getattr(type(value), "get_fields_and_field_types", None)
    if rclpy_fields is not None:
        return list(rclpy_fields())
    msgtype = getattr(value, "__msgtype__", None)
    if msgtype is not None and dataclasses.is_dataclass(value):
        _consts, fields = TYPESTORE.fielddefs[msgtype]
        return [name for name, _ in fields if name != _EMPTY_PLACEHOLDER]
    return None


def _is_message(value: Any) -> bool:
    return message_fields(value) is not None


def _float_bits(x: float) -> bytes:
    return struct.pack("<d", float(x))


def _as_array(value: Any) -> np.ndarray | None:
    """A primitive array as numpy, or None if ``value`` is not one."""
    if isinstance(value, np.ndarray):
        return value
    if isinstance(value, array.array):
        return np.asarray(value)
    if isinstance(value, list | tuple):
        if all(isinstance(v, bytes) and len(v) == 1 for v in value) and value:
            return np.frombuffer(b"".join(value), dtype=np.uint8)
        if all(isinstance(v, bool | int | float | np.generic) for v in value):
            return np.asarray(value)
    return None


def _array_diff(a: np.ndarray, b: np.ndarray, path: str) -> list[str]:
    if a.shape != b.shape:
        return [f"{path}: shape {a.shape} != {b.shape}"]
    if a.size == 0:
        return []
    kinds = {a.dtype.kind, b.dtype.kind}
    if "f" in kinds:
        if kinds != {"f"}:
            return [f"{path}: dtype {a.dtype} != {b.dtype}"]
        bits_a = a.astype(np.float64).view(np.uint64)
        bits_b = b.astype(np.float64).view(np.uint64)
        bad = np.flatnonzero(bits_a != bits_b)
    elif a.dtype.itemsize == 1 and b.dtype.itemsize == 1 and kinds <= {"i", "u", "b"}:
        # byte/octet/uint8/int8/bool arrays: compare the raw bytes
        bad = np.flatnonzero(a.view(np.uint8) != b.view(np.uint8))
    else:
        if not kinds <= {"i", "u"} and len(kinds) > 1:
            return [f"{path}: dtype {a.dtype} != {b.dtype}"]
        bad = np.flatnonzero(a.astype(object) != b.astype(object))
    if bad.size == 0:
        return []
    i = int(bad[0])
    return [f"{path}[{i}]: {a.flat[i]!r} != {b.flat[i]!r} ({bad.size} of {a.size} differ)"]


def _scalar_diff(a: Any, b: Any, path: str) -> list[str]:
    if isinstance(a, np.generic):
        a = a.item()
    if isinstance(b, np.generic):
        b = b.item()
    # ROS 'byte'/'octet' scalar: rclpy gives bytes of length 1, rosbags a (signed) int
    if isinstance(a, bytes) and len(a) == 1 and isinstance(b, int):
        return [] if a[0] == b % 256 else [f"{path}: {a!r} != {b!r}"]
    if isinstance(b, bytes) and len(b) == 1 and isinstance(a, int):
        return _scalar_diff(b, a, path)
    if isinstance(a, float) or isinstance(b, float):
        if not (isinstance(a, float) and isinstance(b, float)):
            return [f"{path}: {type(a).__name__} {a!r} != {type(b).__name__} {b!r}"]
        return [] if _float_bits(a) == _float_bits(b) else [f"{path}: {a!r} != {b!r}"]
    if isinstance(a, bool) != isinstance(b, bool):
        return [f"{path}: {type(a).__name__} {a!r} != {type(b).__name__} {b!r}"]
    if isinstance(a, int | str | bytes) and type(a) is type(b):
        return [] if a == b else [f"{path}: {a!r} != {b!r}"]
    return [f"{path}: cannot compare {type(a).__name__} {a!r} with {type(b).__name__} {b!r}"]


def _seq_diff(a: Sequence[Any], b: Sequence[Any], path: str) -> list[str]:
    if len(a) != len(b):
        return [f"{path}: length {len(a)} != {len(b)}"]
    out: list[str] = []
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        out += _diff(x, y, f"{path}[{i}]")
        if len(out) >= _MAX_REPORTS:
            break
    return out


def _diff(a: Any, b: Any, path: str) -> list[str]:
    fa, fb = message_fields(a), message_fields(b)
    if fa is not None or fb is not None:
        if fa is None or fb is None:
            return [f"{path or '<msg>'}: message vs {type(a if fa is None else b).__name__}"]
        if fa != fb:
            return [f"{path or '<msg>'}: fields {fa} != {fb}"]
        out: list[str] = []
        for name in fa:
            out += _diff(getattr(a, name), getattr(b, name), f"{path}.{name}" if path else name)
            if len(out) >= _MAX_REPORTS:
                break
        return out
    arr_a, arr_b = _as_array(a), _as_array(b)
    if arr_a is not None and arr_b is not None:
        return _array_diff(arr_a, arr_b, path)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return _seq_diff(a, b, path)
    if (arr_a is None) != (arr_b is None):
        return [f"{path}: {type(a).__name__} {a!r:.60} != {type(b).__name__} {b!r:.60}"]
    return _scalar_diff(a, b, path)


def value_diff(a: Any, b: Any) -> list[str]:
    """Every difference between two decoded messages (at most ~20), as ``path: a != b``;
    an empty list means the values are identical."""
    return _diff(a, b, "")[:_MAX_REPORTS]
