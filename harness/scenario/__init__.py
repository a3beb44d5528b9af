"""Scenario files: the typed model and its loader."""

from harness.scenario.loader import (
    apply_overrides,
    degree_warnings,
    load_scenario,
    parse_override,
    rate_warnings,
    robot_warnings,
    scenario_from_mapping,
    scenario_to_mapping,
    tripwire_warnings,
    validate_dataclass,
    worker_warnings,
)
from harness.scenario.schema import *  # noqa: F403
from harness.scenario.schema import __all__ as _schema_all

__all__ = [
    "apply_overrides",
    "degree_warnings",
    "robot_warnings",
    "tripwire_warnings",
    "worker_warnings",
    "load_scenario",
    "parse_override",
    "rate_warnings",
    "scenario_from_mapping",
    "scenario_to_mapping",
    "validate_dataclass",
    *_schema_all,
]
