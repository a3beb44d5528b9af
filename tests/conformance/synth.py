"""Seeded messages of any typestore type with every field filled, for round-trip tests.

Values are chosen to be awkward for a serializer: floats include ±0, ±inf, NaN, subnormals
and the extremes of float32/float64; integers span their type's whole range; strings and
sequences are sometimes empty (an empty sequence of doubles is where Fast CDR's size estimate
and the exact size part); bounded strings and sequences respect their bound.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from rosbags.interfaces import Nodetype

from harness.serde.messages import TYPESTORE

__all__ = ["random_message"]

# rosbags decodes ROS 'byte' (IDL octet) as int8 and 'char' as uint8; generate what it decodes
_INT = {
    "bool": np.bool_, "byte": np.int8, "octet": np.int8, "char": np.uint8,
    "int8": np.int8, "uint8": np.uint8, "int16": np.int16, "uint16": np.uint16,
    "int32": np.int32, "uint32": np.uint32, "int64": np.int64, "uint64": np.uint64,
}
_FLOAT = {"float32": np.float32, "float64": np.float64}
_SPECIAL = (0.0, -0.0, float("inf"), float("-inf"), float("nan"), 1e-310, 1.5, -2.25)
_TEXT = "abcdefghijklmnopqrstuvwxyz_/0123456789 "


def _floats(rng: np.random.Generator, dtype: Any, n: int) -> np.ndarray:
    info = np.finfo(dtype)
    pool = np.array([*_SPECIAL, float(info.max), float(info.tiny), float(info.smallest_subnormal)],
                    dtype=dtype)
    values = (rng.standard_normal(n) * 10.0 ** rng.integers(-8, 9, n)).astype(dtype)
    special = rng.random(n) < 0.3
    values[special] = pool[rng.integers(0, len(pool), int(special.sum()))]
    return values


def _ints(rng: np.random.Generator, dtype: Any, n: int) -> np.ndarray:
    if dtype is np.bool_:
        return rng.random(n) < 0.5
    info = np.iinfo(dtype)
    pick = rng.integers(0, 4, n)
    values = rng.integers(info.min, info.max, n, dtype=dtype, endpoint=True)
    values[pick == 0] = info.min
    values[pick == 1] = info.max
    return values


def _base(rng: np.random.Generator, name: str, bound: int) -> Any:
    if name in ("string", "wstring"):
        n = int(rng.integers(0, min(bound, 12) + 1 if bound else 13))
        return "".join(rng.choice(list(_TEXT), n)) if n else ""
    if name in _FLOAT:
        return float(_floats(rng, _FLOAT[name], 1)[0])
    if name == "bool":
        return bool(rng.random() < 0.5)
    return int(_ints(rng, _INT[name], 1)[0])


def _array(rng: np.random.Generator, desc: Any, n: int) -> Any:
    kind, sub = desc
    if kind == Nodetype.BASE and sub[0] in _FLOAT:
        return _floats(rng, _FLOAT[sub[0]], n)
    if kind == Nodetype.BASE and sub[0] not in ("string", "wstring"):
        return _ints(rng, _INT[sub[0]], n)
    return [_value(rng, desc) for _ in range(n)]


def _value(rng: np.random.Generator, desc: Any) -> Any:
    kind, sub = desc
    if kind == Nodetype.BASE:
        return _base(rng, sub[0], sub[1])
    if kind == Nodetype.NAME:
        return random_message(sub, rng)
    if kind == Nodetype.ARRAY:
        return _array(rng, sub[0], sub[1])
    inner, bound = sub
    limit = bound if bound else (40 if inner == (Nodetype.BASE, ("uint8", 0)) else 4)
    length = int(rng.integers(0, limit + 1))
    return _array(rng, inner, length)


def random_message(typename: str, rng: np.random.Generator) -> Any:
    """A rosbags message of ``typename`` with every field set from ``rng``."""
    _consts, fields = TYPESTORE.fielddefs[typename]
    cls = TYPESTORE.types[typename]
    return cls(**{name: _value(rng, desc) for name, desc in fields})
