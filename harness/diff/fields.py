"""Walk two decoded messages of one type side by side, field by field.

Messages are the ``rosbags`` typestore's dataclasses. The walk reports, in field order:

* every numeric or boolean scalar as ``scalar(path, a, b)`` (floats; two booleans as
  ``bool``, a number 0 or 1 that shows as ``false``/``true``); ``path`` is the flattened
  field path, message sequences indexed (``transforms[0].transform.translation.x``);
* every primitive array as ``array(path, a, b)`` with both arrays as float64 (the caller
  indexes elements as ``path[i]``). ``data`` of a ``sensor_msgs/Image`` with a known
  multi-byte encoding (``32FC1`` depth, ``16UC1``) is read as that type, so a depth
  difference is in metres, not bytes;
* everything that cannot be a numeric difference as ``mismatch(path, detail)``: a string that
  differs, sequences or arrays of different lengths, different message types.

Sequences of different lengths are compared over their common prefix as well.
"""

from __future__ import annotations

import dataclasses
from functools import cache
from typing import Any, Protocol

import numpy as np

__all__ = ["Visitor", "as_float", "walk"]

IMAGE = "sensor_msgs/msg/Image"
# little-endian image encodings whose pixels are wider than a byte
_IMAGE_DTYPES = {"32fc1": "<f4", "64fc1": "<f8", "16uc1": "<u2", "mono16": "<u2",
                 "16sc1": "<i2", "32sc1": "<i4"}
MAX_TEXT = 40


class Visitor(Protocol):
    def scalar(self, path: str, a: float, b: float) -> None: ...

    def array(self, path: str, a: np.ndarray, b: np.ndarray) -> None: ...

    def mismatch(self, path: str, detail: str) -> None: ...


@cache
def _field_names(cls: type) -> tuple[str, ...]:
    return tuple(f.name for f in dataclasses.fields(cls) if not f.name.startswith("__"))


def _short(text: str) -> str:
    return repr(text if len(text) <= MAX_TEXT else text[:MAX_TEXT] + "…")


def as_float(a: np.ndarray) -> np.ndarray:
    """A 1-D float64 copy of a numeric or boolean array."""
    return np.asarray(a).reshape(-1).astype(np.float64)


def _image_data(msg: Any) -> np.ndarray:
    data = np.asarray(msg.data)
    dtype = _IMAGE_DTYPES.get(str(msg.encoding).lower())
    if dtype is None or msg.is_bigendian or data.dtype != np.uint8 \
            or data.size % np.dtype(dtype).itemsize:
        return data
    return data.view(dtype)


def walk(a: Any, b: Any, visitor: Visitor, path: str = "") -> None:
    """Compare ``a`` and ``b`` recursively, reporting to ``visitor`` in field order."""
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        if type(a) is not type(b):
            visitor.mismatch(path or "(message)", f"type {getattr(a, '__msgtype__', type(a))} "
                             f"vs {getattr(b, '__msgtype__', type(b))}")
            return
        image = (getattr(a, "__msgtype__", "") == IMAGE
                 and getattr(a, "encoding", None) == getattr(b, "encoding", None))
        for name in _field_names(type(a)):
            sub = f"{path}.{name}" if path else name
            if image and name == "data":
                walk(_image_data(a), _image_data(b), visitor, sub)
            else:
                walk(getattr(a, name), getattr(b, name), visitor, sub)
        return
    if isinstance(a, np.ndarray):
        b = np.asarray(b)
        if a.size != b.size:
            visitor.mismatch(path, f"length {a.size} vs {b.size}")
            n = min(a.size, b.size)
            a, b = a.reshape(-1)[:n], b.reshape(-1)[:n]
        if a.dtype.kind in "biuf" and b.dtype.kind in "biuf":
            visitor.array(path, a, b)
        elif not np.array_equal(a, b):
            visitor.mismatch(path, "values differ")
        return
    if isinstance(a, (list, tuple)):
        if len(a) != len(b):
            visitor.mismatch(path, f"length {len(a)} vs {len(b)}")
        for i, (x, y) in enumerate(zip(a, b, strict=False)):
            walk(x, y, visitor, f"{path}[{i}]")
        return
    if isinstance(a, str) or isinstance(b, str):
        if a != b:
            visitor.mismatch(path, f"{_short(str(a))} vs {_short(str(b))}")
        return
    if isinstance(a, (bool, np.bool_)) and isinstance(b, (bool, np.bool_)):
        visitor.scalar(path, bool(a), bool(b))  # a number (0, 1) that shows as false, true
        return
    if isinstance(a, (bool, int, float, np.number, np.bool_)) and \
            isinstance(b, (bool, int, float, np.number, np.bool_)):
        visitor.scalar(path, float(a), float(b))
        return
    if a != b:
        visitor.mismatch(path, "values differ")
