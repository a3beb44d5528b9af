"""JSON Schema (draft 2020-12) of a scenario file as written, for editors: generated from the
:class:`~harness.scenario.schema.Scenario` dataclasses by :mod:`harness.schemagen`, plus what
the loader accepts before it reads them (:mod:`harness.scenario.loader`,
:mod:`harness.scenario.includes`):

- ``include:`` (a file name or a list of them) and ``key+:`` for a top-level list or mapping
  (extends the included value; an item schema is the same as ``key:``'s);
- a robot's ``control:`` is the block its ``model`` calls for (the loader's ``_refine``);
- ``format_version`` is the version this srr reads.

One schema serves scenario files and the fragments they include: a fragment holds some of
a scenario's top-level keys, so no top-level key is required (the merged scenario's
``format_version`` and ``name`` are checked by ``srr validate``).
"""

from __future__ import annotations

import dataclasses
from typing import Any, get_origin

from harness.scenario.loader import _CONTROL_BY_MODEL
from harness.scenario.schema import FORMAT_VERSION, DiffDriveControl, ForkliftControl, Scenario
from harness.schemagen import SchemaBuilder, json_schema
from harness.validation import layout

__all__ = ["scenario_schema"]

#: A top-level key the file may write as ``key+`` (a list or a mapping, or a block the
#: loader merges as a mapping).
_EXTENDABLE = (tuple, dict)


def scenario_schema() -> dict[str, Any]:
    b = SchemaBuilder()
    doc = json_schema(Scenario, title="srr scenario file", builder=b)
    doc["description"] = (
        "An srr scenario file, or a fragment that scenario files include (`include:`). "
        "`srr validate FILE` checks the merged scenario, with the cross-field rules no "
        "schema says.")
    props: dict[str, Any] = doc["properties"]
    props["format_version"] = {**props["format_version"], "const": FORMAT_VERSION}
    hints, fields = layout(Scenario)
    extended: dict[str, Any] = {}
    for key, f in fields.items():
        tp: Any = hints[f.name]
        if get_origin(tp) in _EXTENDABLE or dataclasses.is_dataclass(tp):
            item = {k: v for k, v in props[key].items() if k != "default"}
            extended[f"{key}+"] = {"description": f"Extends the included `{key}`.", **item}
    props.update(extended)
    props["include"] = {
        "description": "Files merged under this one (relative to it); its keys win, `key+` "
                       "extends theirs.",
        "anyOf": [{"type": "string", "minLength": 1},
                  {"type": "array", "items": {"type": "string", "minLength": 1}}]}
    doc.pop("required", None)
    _control_by_model(doc["$defs"]["RobotSpec"], b)
    return doc


def _control_by_model(robot: dict[str, Any], b: SchemaBuilder) -> None:
    """``control:`` as the block the robot's ``model`` calls for: a built-in model's, or by a
    model file's ``drive`` (``swivel_drive``: the forklift's)."""
    def control(cls: type) -> dict[str, Any]:
        return {"properties": {"control": {"anyOf": [b.ref(cls), {"type": "null"}]}}}

    rules: list[dict[str, Any]] = [
        {"if": {"properties": {"model": {"const": name}}, "required": ["model"]},
         "then": control(cls)} for name, cls in _CONTROL_BY_MODEL.items()]
    rules.append({"if": {"properties": {"model": {"type": "object", "required": ["drive"],
                                                  "properties": {"drive": {
                                                      "const": "swivel_drive"}}}},
                         "required": ["model"]},
                  "then": control(ForkliftControl)})
    rules.append({"if": {"properties": {"model": {"type": "object", "not": {
                      "required": ["drive"], "properties": {"drive": {
                          "const": "swivel_drive"}}}}}, "required": ["model"]},
                  "then": control(DiffDriveControl)})
    robot["allOf"] = rules
