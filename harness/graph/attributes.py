"""Attribute declarations of node types and the value coercion behind them.

An :class:`Attr` names one port of a node type (without its ``inputs:`` / ``outputs:`` prefix),
its OmniGraph-style type string and its default. :func:`coerce` turns a user value (Python
scalars, sequences, numpy arrays, ``usdrt.Sdf.Path`` objects) into the canonical stored form of
a type, or raises :class:`ValueError` saying what was expected. Stored forms are immutable:
scalars are Python ``float`` / ``int`` / ``bool`` / ``str``; fixed tuples and arrays are Python
tuples; ``target`` is a tuple of absolute prim path strings; ``bundle`` / ``any`` are kept as is.
"""

from __future__ import annotations

import math
import numbers
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from harness.graph.errors import GraphError

__all__ = [
    "ATTRIBUTE_TYPES",
    "EXECUTION",
    "Attr",
    "coerce",
    "compatible",
    "converter",
    "is_valid_attr_name",
    "zero_value",
]

EXECUTION = "execution"

_INT_RANGES: dict[str, tuple[int, int]] = {
    "int": (-(2**31), 2**31 - 1),
    "uint": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint64": (0, 2**64 - 1),
}
_FLOAT_TYPES = frozenset({"double", "float"})
_TEXT_TYPES = frozenset({"string", "token", "path"})
_FIXED_TUPLES: dict[str, int] = {"double[2]": 2, "double[3]": 3, "double[4]": 4, "quatd[4]": 4}
_ARRAYS: dict[str, str] = {
    "double[]": "double",
    "float[]": "float",
    "int[]": "int",
    "token[]": "token",
    "string[]": "string",
}
_OPAQUE = frozenset({"bundle", "any"})

#: Every type string an :class:`Attr` may carry.
ATTRIBUTE_TYPES: frozenset[str] = frozenset(
    {EXECUTION, "bool", "target", *_INT_RANGES, *_FLOAT_TYPES, *_TEXT_TYPES, *_FIXED_TUPLES,
     *_ARRAYS, *_OPAQUE}
)

_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def is_valid_attr_name(name: str) -> bool:
    """True when ``name`` is usable as an attribute name (an identifier, no namespace prefix)."""
    return bool(_NAME_RE.match(name))


_FLOAT64 = np.dtype(np.float64)


def _describe(value: Any) -> str:
    text = repr(value)
    if len(text) > 60:
        text = text[:57] + "..."
    return f"{type(value).__name__} {text}"


def _unwrap_numpy(value: Any) -> Any:
    """Turn numpy scalars and 0-d arrays into Python scalars, leave everything else alone."""
    item = getattr(value, "item", None)
    if callable(item) and getattr(value, "ndim", None) == 0:
        return item()
    return value


def _real(value: Any, type_name: str) -> float:
    if type(value) is float:  # the common case, checked first: this runs on every tick
        return value
    value = _unwrap_numpy(value)
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"expected {type_name}, got {_describe(value)}")
    return float(value)


def _integer(value: Any, type_name: str) -> int:
    value = _unwrap_numpy(value)
    if isinstance(value, bool):
        raise ValueError(f"expected {type_name}, got {_describe(value)}")
    if isinstance(value, numbers.Integral):
        result = int(value)
    else:
        as_float = float(value) if isinstance(value, numbers.Real) else math.nan
        if not (math.isfinite(as_float) and as_float.is_integer()):
            raise ValueError(f"expected {type_name}, got {_describe(value)}")
        result = int(as_float)
    lo, hi = _INT_RANGES[type_name]
    if not lo <= result <= hi:
        raise ValueError(f"expected {type_name} in [{lo}, {hi}], got {result}")
    return result


def _boolean(value: Any, type_name: str) -> bool:
    value = _unwrap_numpy(value)
    if isinstance(value, bool):
        return value
    if isinstance(value, numbers.Integral) and int(value) in (0, 1):
        return bool(value)
    raise ValueError(f"expected {type_name}, got {_describe(value)}")


def _path_string(value: Any) -> str | None:
    """The path text of ``value`` when it is a path-like object, else None."""
    if isinstance(value, str):
        return value
    path_string = getattr(value, "pathString", None)
    if isinstance(path_string, str):
        return path_string
    return None


def _text(value: Any, type_name: str) -> str:
    value = _unwrap_numpy(value)
    if type_name == "path":
        text = _path_string(value)
        if text is not None:
            return text
    elif isinstance(value, str):
        return str(value)
    raise ValueError(f"expected {type_name}, got {_describe(value)}")


def _sequence(value: Any, type_name: str) -> list[Any]:
    if isinstance(value, (str, bytes)) or value is None:
        raise ValueError(f"expected {type_name}, got {_describe(value)}")
    ndim = getattr(value, "ndim", None)
    if ndim is not None and ndim != 1:
        raise ValueError(f"expected {type_name} (one-dimensional), got {ndim}-d array")
    try:
        return list(value)
    except TypeError:
        raise ValueError(f"expected {type_name}, got {_describe(value)}") from None


def _fixed_tuple(value: Any, type_name: str) -> tuple[float, ...]:
    size = _FIXED_TUPLES[type_name]
    if type(value) is tuple and len(value) == size:
        for v in value:  # a plain loop: cheaper than all(<genexpr>) on this per-tick path
            if type(v) is not float:
                break
        else:
            return value  # already in stored form
    if isinstance(value, np.ndarray) and value.dtype == _FLOAT64 and value.shape == (size,):
        return tuple(value.tolist())
    items = _sequence(value, type_name)
    if len(items) != size:
        raise ValueError(f"expected {type_name} ({size} numbers), got {len(items)} items")
    return tuple(_real(item, type_name) for item in items)


def _array(value: Any, type_name: str) -> tuple[Any, ...]:
    element = _ARRAYS[type_name]
    items = _sequence(value, type_name)
    convert = _SCALAR_CONVERTERS[element]
    try:
        return tuple(convert(item, element) for item in items)
    except ValueError as err:
        raise ValueError(f"expected {type_name}: {err}") from None


def _target(value: Any, type_name: str) -> tuple[str, ...]:
    single = _path_string(value)
    items = [value] if single is not None else _sequence(value, type_name)
    paths: list[str] = []
    for item in items:
        text = _path_string(item)
        if text is None or not text.startswith("/"):
            raise ValueError(
                f"expected {type_name} (absolute prim paths), got {_describe(item)}"
            )
        paths.append(text)
    return tuple(paths)


def _execution(value: Any, type_name: str) -> Any:
    raise ValueError("execution attributes carry no value")


_SCALAR_CONVERTERS: dict[str, Callable[[Any, str], Any]] = {
    "double": _real,
    "float": _real,
    "int": _integer,
    "uint": _integer,
    "int64": _integer,
    "uint64": _integer,
    "bool": _boolean,
    "string": _text,
    "token": _text,
    "path": _text,
}


Converter = Callable[[Any], Any]


def _identity(value: Any) -> Any:
    return value


def _conversion(type_name: str) -> Callable[..., Any]:
    """The ``(value, type_name) -> stored value`` function behind ``type_name``."""
    if type_name in _SCALAR_CONVERTERS:
        return _SCALAR_CONVERTERS[type_name]
    if type_name in _FIXED_TUPLES:
        return _fixed_tuple
    if type_name in _ARRAYS:
        return _array
    if type_name == "target":
        return _target
    if type_name == EXECUTION:
        return _execution
    raise ValueError(f"unknown attribute type {type_name!r}")


# The Python type an element of these arrays already has in its stored form (their element
# conversions give such a value back unchanged).
_PLAIN_ELEMENTS: dict[str, type] = {"double": float, "float": float, "token": str, "string": str}


def _make_converter(type_name: str) -> Converter:
    """The one-argument converter of ``type_name``. Fixed-size tuples and arrays of floats or
    text check for values already in their stored form first (a tuple of that many floats; a
    list or tuple of plain floats or strings, which becomes a tuple of the same elements):
    what most per-tick writes carry, handled without the general conversion. Every converter
    passes ``type_name`` positionally (a keyword ``functools.partial`` builds a dict per
    call)."""
    if type_name in _OPAQUE:
        return _identity
    conversion = _conversion(type_name)
    plain = _PLAIN_ELEMENTS.get(_ARRAYS.get(type_name, ""))
    if plain is not None:

        def plain_array(value: Any) -> Any:
            if type(value) is tuple or type(value) is list:
                for v in value:
                    if type(v) is not plain:
                        break
                else:
                    return tuple(value)
            return conversion(value, type_name)

        return plain_array
    if type_name in _FIXED_TUPLES:
        size = _FIXED_TUPLES[type_name]

        def fixed_tuple(value: Any) -> Any:
            if type(value) is tuple and len(value) == size:
                for v in value:
                    if type(v) is not float:
                        break
                else:
                    return value
            return conversion(value, type_name)

        return fixed_tuple

    def convert(value: Any) -> Any:
        return conversion(value, type_name)

    return convert


_CONVERTERS: dict[str, Converter] = {name: _make_converter(name) for name in ATTRIBUTE_TYPES}


def converter(type_name: str) -> Converter:
    """``coerce`` with the type already dispatched: ``converter(t)(v) == coerce(t, v)``.

    The engine resolves one per attribute when it plans a node (see
    :mod:`harness.graph.program`), so per-tick writes and reads skip the type dispatch.
    Unknown type names raise ValueError, as :func:`coerce` does.
    """
    found = _CONVERTERS.get(type_name)
    if found is None:
        raise ValueError(f"unknown attribute type {type_name!r}")
    return found


def coerce(type_name: str, value: Any) -> Any:
    """Return ``value`` in the stored form of ``type_name``; raise ValueError when it does not fit.

    Unknown type names raise ValueError too. ``bundle`` and ``any`` accept anything unchanged.
    """
    return converter(type_name)(value)


def zero_value(type_name: str) -> Any:
    """The value an attribute of ``type_name`` holds when its declaration gives no default."""
    if type_name in _FLOAT_TYPES:
        return 0.0
    if type_name in _INT_RANGES:
        return 0
    if type_name == "bool":
        return False
    if type_name in _TEXT_TYPES:
        return ""
    if type_name in _FIXED_TUPLES:
        return (0.0,) * _FIXED_TUPLES[type_name]
    if type_name in _ARRAYS or type_name == "target":
        return ()
    return None


_GROUPS: tuple[frozenset[str], ...] = (
    frozenset({*_FLOAT_TYPES, *_INT_RANGES}),
    _TEXT_TYPES,
    frozenset({"double[4]", "quatd[4]"}),
    frozenset({"double[]", "float[]"}),
    frozenset({"token[]", "string[]"}),
)


def compatible(src_type: str, dst_type: str) -> bool:
    """True when a data connection from a ``src_type`` port to a ``dst_type`` port is allowed.

    Execution ports only connect to execution ports; ``any`` / ``bundle`` connect to every data
    type; otherwise the types must be equal or belong to one family (numeric scalars, text,
    4-tuples, real arrays, text arrays). Values are still coerced when they are pulled.
    """
    if EXECUTION in (src_type, dst_type):
        return src_type == dst_type
    if src_type == dst_type or src_type in _OPAQUE or dst_type in _OPAQUE:
        return True
    return any(src_type in group and dst_type in group for group in _GROUPS)


@dataclass(frozen=True)
class Attr:
    """One port of a node type: ``Attr("topicName", "string", "clock")``.

    ``name`` carries no ``inputs:`` / ``outputs:`` prefix. ``default`` is coerced to ``type`` on
    construction; ``None`` means the zero value of the type (0.0, 0, False, "", zeros, empty).
    """

    name: str
    type: str
    default: Any = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not is_valid_attr_name(self.name):
            raise GraphError(
                f"attribute name {self.name!r} is not an identifier "
                "(give it without the inputs:/outputs: prefix)"
            )
        if self.type not in ATTRIBUTE_TYPES:
            raise GraphError(
                f"attribute {self.name!r}: unknown type {self.type!r} "
                f"(known: {', '.join(sorted(ATTRIBUTE_TYPES))})"
            )
        if self.default is None or self.type == EXECUTION:
            default = zero_value(self.type)
        else:
            try:
                default = coerce(self.type, self.default)
            except ValueError as err:
                raise GraphError(f"attribute {self.name!r}: bad default: {err}") from err
        object.__setattr__(self, "default", default)

    @property
    def is_execution(self) -> bool:
        """True for execution (control-flow) ports."""
        return self.type == EXECUTION
