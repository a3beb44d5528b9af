"""Check a wiring plan before anything runs (``srr validate`` and the start of ``srr run``).

Errors (a :class:`~harness.errors.ScenarioError`, exit 2, naming the file and the field):

* one topic declared with two message types;
* two graphs publishing one topic that is not a TF topic (two robots in one namespace);
* a subscription a graph needs (a control graph's ``cmd_vel``, a safety indicator's state)
  that nothing publishes while something publishes that type under the same last name (a
  namespace or a remapping away: ``/cmd_vel`` for ``/forklift_b/cmd_vel``);
* a topic the scoring block names (health outputs and rates, perception markers, the safety
  state) that nothing publishes, or that carries another type than the scoring reads;
* TF: a frame id tf2 refuses, a frame with two parents, a frame published static and
  dynamic or by two sources, a cycle (see :mod:`harness.tf_tree`).

Warnings (returned, printed, kept in the summary): any other subscription nothing publishes (a
parked robot's ``cmd_vel``, a system under test's input), and a topic published by a graph
and a system under test, or by two systems under test.
"""

from __future__ import annotations

import re
from collections import defaultdict
from collections.abc import Sequence

from harness.bus import FrameIdError, resolve_topic, validate_frame_id
from harness.bus.endpoints import tf_tree_of
from harness.errors import ScenarioError
from harness.scenario import Scenario
from harness.tf_tree import Edge, roots, tree_problems
from harness.wiring.plan import Plan, PlannedEdge, PlannedTopic

__all__ = ["check_wiring"]


class _Checker:
    def __init__(self, plan: Plan, sc: Scenario, source: str) -> None:
        self.plan, self.sc, self.source = plan, sc, source
        self.warnings: list[str] = []

    def error(self, field: str, message: str) -> ScenarioError:
        return ScenarioError(self.sc.file_for(field, self.source), field, message)

    def warn(self, field: str, message: str) -> None:
        self.warnings.append(f"{self.sc.file_for(field, self.source)}: {field}: {message}")

    # ------------------------------------------------------------------ topics
    def topics(self) -> None:
        by_topic: dict[str, list[PlannedTopic]] = defaultdict(list)
        for t in self.plan.topics:
            by_topic[t.topic].append(t)
        for topic, eps in by_topic.items():
            first = eps[0]
            for ep in eps[1:]:
                if ep.msgtype != first.msgtype:
                    raise self.error(ep.field, f"{ep.verb} {topic} as {ep.msgtype}, but "
                                     f"{first.field} {first.verb} it as {first.msgtype}: a "
                                     "topic carries one message type")
            self.publishers(topic, [e for e in eps if e.kind == "pub"])
        for topic, eps in by_topic.items():
            if any(e.kind == "pub" for e in eps):
                continue
            for sub in eps:
                near, hint = self.near_misses(sub)
                if sub.required and near:
                    raise self.error(sub.field, f"nothing publishes {topic} "
                                     f"({sub.msgtype}), which this graph subscribes to{hint}")
                what = "this graph" if sub.graph else sub.owner
                self.warn(sub.field, f"{what} subscribes to {topic} ({sub.msgtype}), which "
                          f"nothing in the scenario publishes{hint}")

    def publishers(self, topic: str, pubs: list[PlannedTopic]) -> None:
        if len(pubs) < 2 or tf_tree_of(topic) is not None:
            return
        graphs = [p for p in pubs if p.graph]
        if len(graphs) > 1:
            a, b = graphs[0], graphs[1]
            hint = ""
            if a.field.startswith("robots[") and b.field.startswith("robots["):
                hint = ("; robots that share a namespace publish the same topics: give each its "
                        "own `namespace`")
            raise self.error(b.field, f"publishes {topic}, which {a.field} publishes too: two "
                             f"publishers of one topic{hint}")
        for p in pubs[1:]:
            self.warn(p.field, f"{p.owner} publishes {topic}, which {pubs[0].owner} publishes "
                      "too")

    def near_misses(self, sub: PlannedTopic) -> tuple[list[str], str]:
        """Published topics of the same type and last name as an unfed subscription (a
        namespace or a spelling away), and a hint saying what to do about them."""
        leaf = sub.topic.rsplit("/", 1)[-1]
        near = sorted({t.topic for t in self.plan.topics
                       if t.kind == "pub" and t.topic.rsplit("/", 1)[-1] == leaf
                       and t.msgtype == sub.msgtype})
        if not near:
            if sub.graph and ".control." in sub.field:
                return [], " (the robot will not be driven)"
            return [], ""
        owners = sorted({t.owner for t in self.plan.topics
                         if t.kind == "pub" and t.topic in near})
        text = f" (published: {', '.join(near)} by {', '.join(owners)})"
        robot_field = re.match(r"robots\[(\d+)\]\.(\w+)", sub.field)
        if robot_field and sub.graph:
            robot = self.sc.robots[int(robot_field.group(1))]
            block = robot_field.group(2)
            text += (f"; bind the system under test that feeds it with `robot: {robot.name}` "
                     f"(or give it this robot's namespace), or set `{block}: {{enabled: false}}` "
                     f"for a robot nothing drives")
        return near, text

    # ------------------------------------------------------------------ scoring
    def scoring(self) -> None:
        """Topics the scoring block names must be published by something in the scene."""
        sc = self.sc.scoring
        refs: list[tuple[str, str, str]] = []  # (field, topic, type or "")
        for topic in sc.health.sut_outputs:
            refs.append((f"scoring.health.sut_outputs.{topic}", topic, ""))
        for topic in sc.health.expected_rates:
            refs.append((f"scoring.health.expected_rates.{topic}", topic, ""))
        if sc.perception is not None and sc.perception.enabled:
            refs += [(f"scoring.perception.marker_topics[{i}]", t,
                      "visualization_msgs/msg/MarkerArray")
                     for i, t in enumerate(sc.perception.marker_topics)]
        if sc.safety is not None and sc.safety.enabled:
            refs.append(("scoring.safety.muted_topic", sc.safety.muted_topic,
                         "std_msgs/msg/Bool"))
        published = {t.topic: t for t in self.plan.topics if t.kind == "pub"}
        for field, name, msgtype in refs:
            topic = resolve_topic(name)
            pub = published.get(topic)
            if pub is None:
                leaf = topic.rsplit("/", 1)[-1]
                near = sorted(t for t in published if t.rsplit("/", 1)[-1] == leaf)
                hint = f" (published: {', '.join(near)})" if near else ""
                raise self.error(field, f"nothing in the scenario publishes {topic}, so it "
                                 f"cannot be scored{hint}")
            if msgtype and pub.msgtype != msgtype:
                raise self.error(field, f"{topic} carries {pub.msgtype} ({pub.field}), "
                                 f"scoring needs {msgtype}")

    # ------------------------------------------------------------------ TF
    def tf(self) -> None:
        groups: dict[str, list[PlannedEdge]] = defaultdict(list)
        for pe in self.plan.edges:
            tree = tf_tree_of(pe.edge.topic)
            if tree is not None:
                groups[tree].append(pe)
        for planned in groups.values():
            for pe in planned:
                for frame, field in ((pe.edge.parent, pe.parent_field),
                                     (pe.edge.child, pe.child_field)):
                    try:
                        validate_frame_id(frame)
                    except FrameIdError as err:
                        raise self.error(field, str(err)) from err
            edges = [Edge(pe.edge.parent, pe.edge.child, pe.edge.static, pe.child_field)
                     for pe in planned]
            problems = tree_problems(edges)
            if problems:
                first = problems[0]
                blame = first.edges[-1].source if first.kind != "cycle" \
                    else first.edges[0].source
                raise self.error(blame, f"TF: {first.detail}")
            self._base_frames(edges)

    _BASE = ".odometry.base_frame"

    def _base_frames(self, edges: Sequence[Edge]) -> None:
        """A warning for an ``odometry.base_frame`` that is no frame of its robot's link tree:
        odom → that frame joins nothing, and the links hang from a root of their own, where a
        lookup from odom (RViz, Nav2) cannot reach them."""
        parents = {e.parent for e in edges}
        for e in edges:
            if not e.source.endswith(self._BASE) or e.child in parents:
                continue
            links = [x for x in edges if x.source == e.source.removesuffix(self._BASE)
                     + ".tf_tree"]
            tops = roots(links)
            if tops:
                self.warn(e.source, f"'{e.child}' is no frame of the robot's link tree (its "
                          f"root: '{tops[0]}'), so odom → {e.child} joins nothing and the "
                          "links hang from a root of their own, where nothing looking up "
                          f"from odom finds them; name '{tops[0]}' or leave the field out")


def check_wiring(plan: Plan, sc: Scenario, source: str = "<scenario>") -> tuple[str, ...]:
    """Raise :class:`ScenarioError` for the first wiring error; return the warnings
    (``file: field: message`` lines)."""
    checker = _Checker(plan, sc, source)
    checker.topics()
    checker.scoring()
    checker.tf()
    return tuple(checker.warnings)
