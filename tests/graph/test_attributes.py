"""Value coercion of attribute types."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from harness.graph import Attr, coerce, usdrt
from harness.graph.attributes import ATTRIBUTE_TYPES, compatible, zero_value


@pytest.mark.parametrize(("type_name", "value", "expected"), [
    ("double", 1, 1.0),
    ("double", np.float32(0.5), 0.5),
    ("double", np.array(2.0), 2.0),
    ("float", 3, 3.0),
    ("int", 2.0, 2),
    ("int", np.int64(-4), -4),
    ("uint", 7, 7),
    ("uint64", 2**64 - 1, 2**64 - 1),
    ("int64", -(2**63), -(2**63)),
    ("bool", True, True),
    ("bool", 0, False),
    ("bool", np.bool_(True), True),
    ("string", "abc", "abc"),
    ("token", np.str_("tok"), "tok"),
    ("path", usdrt.Sdf.Path("/World/x"), "/World/x"),
    ("path", "/World/y", "/World/y"),
    ("double[2]", [1, 2], (1.0, 2.0)),
    ("double[3]", np.array([1.0, 2.0, 3.0]), (1.0, 2.0, 3.0)),
    ("double[4]", (0.5, -0.5, 0.5, 0.5), (0.5, -0.5, 0.5, 0.5)),
    ("quatd[4]", [1, 0, 0, 0], (1.0, 0.0, 0.0, 0.0)),
    ("double[]", np.arange(3), (0.0, 1.0, 2.0)),
    ("float[]", [], ()),
    ("int[]", [1, 2.0], (1, 2)),
    ("token[]", ["a", "b"], ("a", "b")),
    ("string[]", ("a",), ("a",)),
    # a value that is almost in stored form goes through the element conversions
    ("double[]", [1.0, 2], (1.0, 2.0)),
    ("double[]", (0.5, np.float64(1.5)), (0.5, 1.5)),
    ("double[3]", (1.0, 2, 3.0), (1.0, 2.0, 3.0)),
    ("token[]", ("a", np.str_("b")), ("a", "b")),
    ("target", [usdrt.Sdf.Path("/World/cam")], ("/World/cam",)),
    ("target", "/World/robot", ("/World/robot",)),
    ("target", (), ()),
    ("any", [1, "x"], [1, "x"]),
    ("bundle", None, None),
])
def test_coerce_accepts(type_name: str, value: Any, expected: Any) -> None:
    result = coerce(type_name, value)
    assert result == expected
    assert type(result) is type(expected)


@pytest.mark.parametrize(("type_name", "value", "message"), [
    ("double", "1.0", "expected double, got str"),
    ("double", True, "expected double, got bool"),
    ("int", 1.5, "expected int"),
    ("int", 2**31, r"expected int in \["),
    ("uint", -1, r"expected uint in \["),
    ("bool", 2, "expected bool"),
    ("string", 3, "expected string"),
    ("path", 3, "expected path"),
    ("double[3]", [1.0, 2.0], r"expected double\[3\] \(3 numbers\), got 2 items"),
    ("double[3]", "abc", r"expected double\[3\]"),
    ("double[]", np.zeros((2, 2)), "one-dimensional"),
    ("token[]", "ab", r"expected token\[\]"),
    ("token[]", ["a", 1], "expected token"),
    ("int[]", [1.5], "expected int"),
    ("double[]", [1.0, True], "expected double, got bool"),
    ("double[3]", (1.0, 2.0, True), r"expected double\[3\], got bool"),
    ("target", ["World/relative"], "absolute prim paths"),
    ("target", [3], "absolute prim paths"),
    ("execution", 1, "carry no value"),
    ("vector", 1, "unknown attribute type"),
])
def test_coerce_refuses(type_name: str, value: Any, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        coerce(type_name, value)


def test_defaults_are_coerced_or_zero() -> None:
    assert Attr("x", "double").default == 0.0
    assert Attr("x", "double", 1).default == 1.0
    assert Attr("x", "double[3]").default == (0.0, 0.0, 0.0)
    assert Attr("x", "target", ["/a"]).default == ("/a",)
    assert Attr("x", "execution").default is None
    assert Attr("x", "execution").is_execution
    assert all(Attr("x", t).default == zero_value(t) for t in ATTRIBUTE_TYPES)


def test_attr_is_frozen() -> None:
    attr = Attr("x", "double")
    with pytest.raises(AttributeError):
        attr.name = "y"  # type: ignore[misc]


@pytest.mark.parametrize(("src", "dst", "ok"), [
    ("double", "double", True),
    ("int", "double", True),
    ("double", "string", False),
    ("token", "string", True),
    ("double[4]", "quatd[4]", True),
    ("double[3]", "double[4]", False),
    ("double[]", "float[]", True),
    ("any", "double[3]", True),
    ("target", "bundle", True),
    ("execution", "execution", True),
    ("execution", "any", False),
])
def test_compatible(src: str, dst: str, ok: bool) -> None:
    assert compatible(src, dst) is ok


def test_sdf_path_shim() -> None:
    path = usdrt.Sdf.Path("/World/floating_camera")
    assert str(path) == "/World/floating_camera"
    assert path.pathString == "/World/floating_camera"
    assert path.name == "floating_camera"
    assert path.GetParentPath() == usdrt.Sdf.Path("/World")
    assert path == usdrt.Sdf.Path("/World/floating_camera")
    with pytest.raises(TypeError):
        usdrt.Sdf.Path(3)  # type: ignore[arg-type]
