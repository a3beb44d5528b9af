"""The one validator (harness.validation) reads any frozen dataclass from parsed data, with the
same one-line errors whatever the file: the field path, what was expected and what was given."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Literal

import pytest

from harness.errors import ScenarioError
from harness.validation import validate


@dataclass(frozen=True)
class Inner:
    kind: Literal["a", "b"]
    size: float = dataclasses.field(default=1.0, metadata={"range": (0, 10, True)})


@dataclass(frozen=True)
class Outer:
    name: str
    start: int | float = dataclasses.field(metadata={"key": "from"})
    inner: Inner | None = None
    items: tuple[str | Inner, ...] = ()
    more: dict[str, Any] = dataclasses.field(default_factory=dict)


def test_reads_a_dataclass_with_its_types_and_keys() -> None:
    got = validate(Outer, {"name": "x", "from": 3, "inner": {"kind": "a", "size": 2},
                           "items": ["s", {"kind": "b"}]}, "f.json")
    assert got == Outer("x", 3, Inner("a", 2.0), ("s", Inner("b")))
    assert isinstance(got.start, int)  # an int | float keeps an integer
    assert isinstance(validate(Outer, {"name": "x", "from": 2.5}, "f").start, float)


@pytest.mark.parametrize(("raw", "field", "message"), [
    ({"from": 1}, "name", "missing (not this file)"),
    ({"name": "x"}, "from", "missing (not this file)"),
    ({"name": "x", "from": 1, "inner": {"size": 1}}, "inner.kind", "required field is missing"),
    ({"name": "x", "from": "1"}, "from", "expected a number, got '1'"),
    ({"name": "x", "from": float("inf")}, "from", "expected a finite number, got inf"),
    ({"name": "x", "from": 1, "inner": {"kind": "a", "size": 0}}, "inner.size",
     "must be > 0, got 0"),
    ({"name": "x", "from": 1, "inner": {"kind": "c"}}, "inner.kind",
     "expected one of 'a', 'b', got 'c'"),
    ({"name": "x", "from": 1, "inner": {"knd": "a"}}, "inner.knd",
     "unknown field (did you mean 'kind'?)"),
    ({"name": "x", "from": 1, "inner": {"colour": "a"}}, "inner.colour",
     "unknown field (expected kind, size)"),
    ({"name": "x", "from": 1, "items": [5]}, "items[0]", "expected a string or a mapping, got 5"),
    ({"name": "x", "from": 1, "inner": [1]}, "inner", "expected a mapping, got [1]"),
    ({"name": "x", "from": 1, "more": {"k": 1}, "extra": 1}, "extra",
     "unknown field (expected name, from, inner, items, more)"),
])
def test_errors_name_the_field(raw: dict[str, Any], field: str, message: str) -> None:
    with pytest.raises(ScenarioError) as err:
        validate(Outer, raw, "f.json", missing="missing (not this file)")
    assert (err.value.file, err.value.field, err.value.message) == ("f.json", field, message)
    assert str(err.value) == f"f.json: {field}: {message}"


def test_unknown_keys_can_be_ignored_and_long_values_are_cut() -> None:
    assert validate(Outer, {"name": "x", "from": 1, "later": 2}, "f", unknown="ignore").name == "x"
    with pytest.raises(ScenarioError) as err:
        validate(Outer, {"name": ["y" * 500], "from": 1}, "f")
    assert len(str(err.value)) < 120 and "…" in str(err.value)


def test_a_class_s_type_hints_are_resolved_once_and_forgotten_with_it(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Resolving string annotations compiles each one: a scenario read many blocks of the
    same classes and resolved them again for each (a quarter of checking a suite). A class
    made at run time, as a plug-in's module is, leaves no trace once it is gone."""
    import gc
    import weakref

    import harness.validation as validation

    calls: list[type] = []
    real = validation.get_type_hints

    def counting(cls: type) -> dict[str, Any]:
        calls.append(cls)
        return real(cls)

    monkeypatch.setattr(validation, "get_type_hints", counting)
    namespace: dict[str, Any] = {}
    exec("from __future__ import annotations\nfrom dataclasses import dataclass\n"
         "@dataclass(frozen=True)\nclass Made:\n    a: int\n    b: 'tuple[str, ...]' = ()\n",
         namespace)
    made = namespace.pop("Made")
    for _ in range(3):
        assert validate(made, {"a": 1, "b": ["x"]}, "f") == made(1, ("x",))
        validate(Outer, {"name": "x", "from": 1, "items": [{"kind": "a"}, {"kind": "b"}]}, "f")
    assert calls.count(made) == 1
    assert calls.count(Inner) <= 1 and calls.count(Outer) <= 1  # (an earlier test may own it)
    with pytest.raises(ScenarioError, match=r"f: b\[0\]: expected a string, got 2"):
        validate(made, {"a": 1, "b": [2]}, "f")  # the kept hints still check
    gone = weakref.ref(made)
    calls.clear()
    del made, namespace
    gc.collect()
    assert gone() is None
