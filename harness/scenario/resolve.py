"""Filling in what a scenario leaves to be derived: robot namespaces and frame prefixes, the
systems under test's namespaces, graph names and the robot a graph or scoring block is for."""

from __future__ import annotations

import dataclasses

from harness.scenario.schema import ControlScoring, GraphSpec, Scenario, ScoringSpec

__all__ = ["graph_name", "resolve_names"]


def graph_name(spec: GraphSpec) -> str:
    """A ``graphs:`` entry's name: its own, else the builder function's name, else (for a
    function called ``build``) the module's last component."""
    if spec.name is not None:
        return spec.name
    module, _, func = spec.builder.partition(":")
    return func if func and func != "build" else module.rsplit(".", 1)[-1]


def resolve_names(sc: Scenario) -> Scenario:
    """Fill in the robots' namespaces and frame prefixes and the systems under test's
    namespaces (see :class:`~harness.scenario.schema.RobotSpec`).

    With more than one enabled robot, a robot without ``namespace`` gets its name, and one
    without ``frame_prefix`` gets its namespace (or name) + ``/``, like robot_state_publisher's
    ``frame_prefix`` in ROS 2 multi-robot launches; with one robot both stay empty, so a
    single robot keeps the seeds' names. A prefix always ends in ``/``. A system under test
    bound to a robot takes the robot's namespace unless it sets its own.
    """
    multi = sum(r.enabled for r in sc.robots) > 1
    robots = []
    for r in sc.robots:
        ns = r.namespace if r.namespace is not None else (r.name if multi else "")
        if r.frame_prefix is not None:
            prefix = r.frame_prefix
        else:
            prefix = (ns.strip("/") or r.name) if multi else ""
        if prefix and not prefix.endswith("/"):
            prefix += "/"
        robots.append(dataclasses.replace(r, namespace=ns, frame_prefix=prefix))
    by_name = {r.name: r for r in robots}
    suts = []
    for sut in sc.systems_under_test:
        sut_ns = sut.namespace
        if sut_ns is None:
            sut_ns = by_name[sut.robot].ns if sut.robot in by_name else ""
        suts.append(dataclasses.replace(sut, namespace=sut_ns))
    enabled = [r.name for r in robots if r.enabled]
    only = enabled[0] if len(enabled) == 1 else ""
    graphs = tuple(dataclasses.replace(g, name=graph_name(g), robot=g.robot or only)
                   for g in sc.graphs)
    return dataclasses.replace(sc, robots=tuple(robots), systems_under_test=tuple(suts),
                               graphs=graphs, scoring=_default_scored_robot(sc.scoring, only))


def _default_scored_robot(scoring: ScoringSpec, only: str) -> ScoringSpec:
    """``scoring.control`` blocks and ``scoring.safety`` that leave ``robot`` out score the
    only enabled robot ``only``, as ``graphs:`` entries do."""
    def fill(block: ControlScoring) -> ControlScoring:
        return dataclasses.replace(block, robot=block.robot or only)

    c = scoring.control
    control = None if c is None else fill(c) if not isinstance(c, tuple) else \
        tuple(fill(b) for b in c)
    s = scoring.safety
    safety = None if s is None else dataclasses.replace(s, robot=s.robot or only)
    return dataclasses.replace(scoring, control=control, safety=safety)
