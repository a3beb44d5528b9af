"""`srr schema`: the JSON Schema generated from the scenario and suite dataclasses is a valid
draft 2020-12 schema, every bundled scenario, include fragment and suite file holds against
it by an independent validator (the ``jsonschema`` package), and files that ``srr validate``
refuses for a wrong type, an unknown key or a value out of range do not."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest
from jsonschema import Draft202012Validator

from harness import api, yamlio
from harness.cli import main
from harness.errors import ScenarioError
from harness.scenario import load_scenario
from harness.scenario.loader import scenario_from_mapping

ROOT = Path(__file__).resolve().parents[2]
FILES = sorted(p for p in (ROOT / "scenarios").rglob("*.yaml"))


def _kind(data: dict[str, Any]) -> str:
    """How srr tells the files apart: a suite has a `scenarios:` list, a scenario a `name:`
    (harness.suite.spec); anything else is a fragment some scenario includes."""
    if isinstance(data.get("scenarios"), list):
        return "suite"
    return "scenario" if "name" in data else "fragment"


def _read(path: Path) -> dict[str, Any]:
    data = yamlio.load(path.read_text(encoding="utf-8"))
    assert isinstance(data, dict)
    return data


@pytest.fixture(scope="module")
def validators() -> dict[str, Draft202012Validator]:
    scenario = Draft202012Validator(api.json_schema("scenario"))
    return {"scenario": scenario, "fragment": scenario,
            "suite": Draft202012Validator(api.json_schema("suite"))}


def _errors(v: Draft202012Validator, data: Any) -> list[str]:
    return [f"{'/'.join(map(str, e.absolute_path))}: {e.message}" for e in v.iter_errors(data)]


@pytest.mark.parametrize("kind", ["scenario", "suite"])
def test_schema_is_valid_draft_2020_12(kind: str) -> None:
    doc = api.json_schema(kind)
    assert doc["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    Draft202012Validator.check_schema(doc)


def test_bundled_files_are_scenarios_fragments_and_suites() -> None:
    kinds = {p.relative_to(ROOT).as_posix(): _kind(_read(p)) for p in FILES}
    included = {(p.parent / inc).resolve() for p in FILES
                for inc in ([_read(p).get("include")] if isinstance(_read(p).get("include"), str)
                            else _read(p).get("include") or [])}
    assert {k for k, v in kinds.items() if v == "fragment"} == {
        p.relative_to(ROOT).as_posix() for p in included}
    assert "suite" in kinds.values()


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_bundled_file_validates(path: Path, validators: dict[str, Draft202012Validator]) -> None:
    data = _read(path)
    assert _errors(validators[_kind(data)], data) == []


def _scenario() -> dict[str, Any]:
    """A bundled scenario as written (an include, a robot with a `control:` block)."""
    data = _read(ROOT / "scenarios" / "turtlebot3_room.yaml")
    assert data["robots"][0]["model"] == "turtlebot3_waffle_pi"
    return data


BROKEN: list[tuple[str, Any, str]] = [
    # (field path, value, what srr validate says)
    ("duration", "long", "expected a number"),
    ("seed", 1.5, "expected an integer"),
    ("duration", 0, "must be > 0"),
    ("physics.tick_hz", 5000, "must be <= 1000"),
    ("physics.integrator", "verlet", "expected one of"),
    ("physics.tick_rate", 60, "unknown field"),
    ("dureation", 10, "unknown field"),
    ("robots.0.spawn.position", [1.0, 2.0], "expected a list of 3 values"),
    ("robots.0.control.wheelbase", 1.2,  # a forklift's, on a TurtleBot3
     "belongs with drive 'swivel_drive', and robots\\[0\\].model is 'turtlebot3_waffle_pi'"),
    ("robots.0.control.wheel_radius", -0.1, "must be > 0"),
    ("render.overlap", "yes", "expected one of"),
    ("format_version", 2, "unsupported version"),
]


def _set(data: dict[str, Any], path: str, value: Any) -> None:
    *head, last = path.split(".")
    node: Any = data
    for part in head:
        node = node[int(part)] if isinstance(node, list) else node.setdefault(part, {})
    node[last] = value


@pytest.mark.parametrize(("path", "value", "message"), BROKEN,
                         ids=[f"{p}={v!r}" for p, v, _ in BROKEN])
def test_broken_scenario_fails_both(path: str, value: Any, message: str,
                                    validators: dict[str, Draft202012Validator],
                                    tmp_path: Path) -> None:
    good = _scenario()
    assert _errors(validators["scenario"], good) == []
    data = copy.deepcopy(good)
    robots = data["robots"]
    robots[0].setdefault("control", {})
    _set(data, path, value)
    assert _errors(validators["scenario"], data), f"the schema lets {path}={value!r} through"
    # and srr's own validator refuses it too (the schema says no more than srr does)
    (tmp_path / "s.yaml").write_text(yamlio.dump(data), encoding="utf-8")
    for inc in ([data["include"]] if isinstance(data.get("include"), str)
                else data.get("include") or []):
        (tmp_path / inc).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / inc).write_text((ROOT / "scenarios" / inc).read_text(), encoding="utf-8")
    with pytest.raises(ScenarioError, match=message):
        load_scenario(tmp_path / "s.yaml")


def test_control_block_follows_the_model(validators: dict[str, Draft202012Validator]) -> None:
    fork = {"name": "f", "model": "forklift", "control": {"wheelbase": 1.2}}
    diff = {"name": "d", "model": {"urdf": "r.urdf"}, "control": {"wheel_distance": 0.3}}
    swivel = {"name": "s", "model": {"urdf": "r.urdf", "drive": "swivel_drive"},
              "control": {"wheelbase": 1.2}}
    v = validators["scenario"]
    for robot in (fork, diff, swivel):
        assert _errors(v, {"robots": [robot]}) == []
        scenario_from_mapping({"format_version": 1, "name": "x", "robots": [robot]})
    wrong = {**swivel, "control": {"wheel_distance": 0.3}}
    assert _errors(v, {"robots": [wrong]})
    with pytest.raises(ScenarioError, match="belongs with drive 'diff_drive', and "
                       r"robots\[0\].model.drive is 'swivel_drive'"):
        scenario_from_mapping({"format_version": 1, "name": "x", "robots": [wrong]})


def test_include_and_extend_forms(validators: dict[str, Draft202012Validator]) -> None:
    v = validators["scenario"]
    assert _errors(v, {"include": "a.yaml", "robots+": [{"name": "b", "model": "forklift"}],
                       "routes+": {"r": {"waypoints": [[0, 0], [1, 1]]}}}) == []
    assert _errors(v, {"include": ["a.yaml", "b.yaml"]}) == []
    assert _errors(v, {"include": [3]})
    assert _errors(v, {"robots+": [{"name": "b", "model": "forklift", "colour": "red"}]})
    assert _errors(v, {"name+": "x"})  # only lists and mappings extend


def test_broken_suite_fails(validators: dict[str, Draft202012Validator]) -> None:
    data = _read(ROOT / "scenarios" / "suites" / "nightly.yaml")
    v = validators["suite"]
    assert _errors(v, data) == []
    for key, value in (("defaults", {"repeats": 2}), ("suite", 3), ("scenarios", "a.yaml")):
        assert _errors(v, {**data, key: value}), key
    assert _errors(v, {**data, "scenarios": [{"path": "a.yaml", "rpeat": 2}]})
    for entry in ({"repeat": 0}, {"repeat": 1001}, {"timeout": 0}, {"timeout": -1.5}):
        assert _errors(v, {**data, "scenarios": [{"path": "a.yaml", **entry}]}), entry
        assert _errors(v, {**data, "defaults": entry}), entry
    assert _errors(v, {"suite": "x"})  # scenarios is required


def test_cli_prints_and_writes_the_schema(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema"]) == 0
    assert json.loads(capsys.readouterr().out) == api.json_schema("scenario")
    out = tmp_path / "suite.schema.json"
    assert main(["schema", "suite", "--out", str(out)]) == 0
    assert json.loads(out.read_text(encoding="utf-8")) == api.json_schema("suite")
    assert main(["schema", "suite", "--out", str(tmp_path / "no" / "x.json")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_descriptions_come_from_the_dataclasses() -> None:
    """Hover texts: a dataclass's docstring, and the comments written with a field."""
    defs = api.json_schema("scenario")["$defs"]
    assert defs["PhysicsSpec"]["description"].startswith("Playback tick and physics step")
    assert defs["RobotSpec"]["properties"]["articulation_prim"]["description"] == \
        "default /World/<name>"
    assert "max silence" in defs["HealthScoring"]["properties"]["sut_outputs"]["description"]
    assert "description" not in defs["PhysicsSpec"]["properties"]["tick_hz"]


def _leaves(node: Any, path: tuple[Any, ...] = ()) -> list[tuple[tuple[Any, ...], Any]]:
    if isinstance(node, dict):
        return [leaf for k, v in node.items() for leaf in _leaves(v, (*path, k))]
    if isinstance(node, list):
        return [leaf for i, v in enumerate(node) for leaf in _leaves(v, (*path, i))]
    return [(path, node)]


def _wrong(value: Any) -> list[Any]:
    """Values of another type (a string for a number or a boolean, a number for a string),
    and for a number, numbers out of any range (below the least, above the greatest)."""
    if isinstance(value, str):
        return [12345]
    if isinstance(value, bool) or not isinstance(value, int | float):
        return ["wrong"]
    # an integer stays one: JSON has one number type, so a schema's "integer" also takes 2.0,
    # which srr refuses for an integer field
    return ["wrong", 0, -1, -10**12, 10**12] if isinstance(value, int) else \
        ["wrong", 0.0, -1.0, -1e12, 1e12]


@pytest.mark.slow
@pytest.mark.parametrize("name", ["turtlebot3_room", "diffbot_urdf", "camera_publishing"])
def test_schema_and_validator_agree_on_every_value(
        name: str, validators: dict[str, Draft202012Validator]) -> None:
    """Each value of a bundled scenario (without includes) replaced by one of another type:
    the schema refuses it exactly when srr's validator does (a plug-in's `params` take any
    value, in both)."""
    good = _read(ROOT / "scenarios" / f"{name}.yaml")
    assert "include" not in good
    refused = 0
    differ: list[str] = []
    for path, bad in ((path, bad) for path, value in _leaves(good) for bad in _wrong(value)):
        data = copy.deepcopy(good)
        node: Any = data
        for part in path[:-1]:
            node = node[part]
        node[path[-1]] = bad
        schema_ok = not _errors(validators["scenario"], data)
        try:
            scenario_from_mapping(data, f"{name}.yaml")
            srr_ok = True
        except ScenarioError:
            srr_ok = False
        if schema_ok != srr_ok:
            differ.append(f"{'.'.join(map(str, path))}={bad!r}: schema "
                          f"{'accepts' if schema_ok else 'refuses'}, srr "
                          f"{'accepts' if srr_ok else 'refuses'}")
        refused += not srr_ok
    assert differ == [], "\n".join(differ)
    assert refused > 20
