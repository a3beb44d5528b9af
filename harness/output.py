"""The run's output kind: ROS 2 (a rosbag2 directory, MCAP) or ROS 1 (a ``.bag``, or MCAP with
the ``ros1`` profile), decided once per run, before its first tick.

* ``output: {ros: 1 | 2, format: mcap | bag}`` in the scenario says it (``--set
  output.ros=2`` records seed 000's ROS 1 graphs as ROS 2);
* left out, the ``graphs:`` builders decide: bridge nodes spelled as Isaac Sim's ROS 1 bridge
  (``omni.isaac.ros_bridge.ROS1*``, seed 000) mean ROS 1, spelled as its ROS 2 bridge
  (``isaacsim.ros2.bridge.ROS2*``, ``omni.isaac.ros2_bridge.ROS2*``) or not at all, ROS 2;
  ``format: bag`` alone means ROS 1.

ROS 1 and ROS 2 bridge nodes in one scenario's builders is a
:class:`~harness.errors.ScenarioError` (exit 2, ``srr validate`` too). The built-in graphs are
srr's own and record whichever the run records. With ROS 1, every
published topic's type must have a Noetic counterpart (:mod:`harness.serde.ros1`), and the live
ROS 2 bridge and the Foxglove live view (both speak ROS 2) are refused.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from harness.errors import ScenarioError
from harness.graph import GraphStage
from harness.recording.bagfile import ChunkPolicy
from harness.recording.recorder import Recorder
from harness.recording.ros1bag import Ros1Recorder
from harness.scenario import Scenario
from harness.serde.ros1 import Ros1TypeError, dropped_fields, ros1_type

__all__ = ["ROS2_OUTPUT", "OutputKind", "bridge_ros_version", "check_output_topics",
           "decide_output"]

_ROS1_PREFIXES = ("omni.isaac.ros_bridge.",)
_ROS2_PREFIXES = ("isaacsim.ros2.", "omni.isaac.ros2_bridge.")


@dataclass(frozen=True)
class OutputKind:
    """What a run records: ``ros`` 1 or 2, ``format`` ``mcap`` or ``bag`` (ROS 1 only), and
    ``because``: how that was decided, for messages."""

    ros: Literal[1, 2]
    format: Literal["mcap", "bag"]
    because: str = "the default"

    @property
    def label(self) -> str:
        if self.ros == 2:
            return "ROS 2 (rosbag2, MCAP)"
        return "ROS 1 (.bag)" if self.format == "bag" else "ROS 1 (MCAP, ros1 profile)"

    def recorder(self, bag_dir: Path, chunks: ChunkPolicy,
                 unrecorded: Collection[str] = ()) -> Recorder:
        """The recorder writing this kind into ``bag_dir``; ``unrecorded`` topics are
        counted, not written (raw images a camera records only compressed)."""
        if self.ros == 2:
            return Recorder(bag_dir, chunks=chunks, unrecorded=unrecorded)
        return Ros1Recorder(bag_dir, self.format, chunks=chunks, unrecorded=unrecorded)

    def summary(self) -> dict[str, Any]:
        """As ``summary.json`` keeps it (``output``)."""
        return {"ros": self.ros, "format": self.format, "because": self.because}


ROS2_OUTPUT = OutputKind(2, "mcap")


def bridge_ros_version(type_name: str) -> Literal[1, 2] | None:
    """1 for a node type spelled as Isaac Sim's ROS 1 bridge's, 2 for its ROS 2 bridge's,
    None for any other (srr's own names, core nodes)."""
    if type_name.startswith(_ROS1_PREFIXES):
        return 1
    if type_name.startswith(_ROS2_PREFIXES):
        return 2
    return None


def _bridge_nodes(stage: GraphStage, custom_graphs: Mapping[str, str]
                  ) -> dict[int, tuple[str, str, str]]:
    """ROS version → (field, node path, type) of the first bridge node of that version in
    the graphs the ``graphs:`` entries built (``custom_graphs``: graph path → field), in
    build order."""
    found: dict[int, tuple[str, str, str]] = {}
    for path, field in custom_graphs.items():
        if not stage.has_graph(path):
            continue
        for node in stage.graph(path).nodes:
            version = bridge_ros_version(node.type_name)
            if version is not None and version not in found:
                found[version] = (field, node.path, node.type_name)
    return found


def decide_output(sc: Scenario, stage: GraphStage, custom_graphs: Mapping[str, str],
                  source: str = "<scenario>") -> OutputKind:
    """The run's output kind (see the module docstring); ScenarioError when the builders
    mix ROS 1 and ROS 2 bridge nodes."""
    nodes = _bridge_nodes(stage, custom_graphs)
    if 1 in nodes and 2 in nodes:
        (_, p1, t1), (_, p2, t2) = nodes[1], nodes[2]
        later = list(nodes.values())[-1][0]  # the entry that brought the second version
        raise ScenarioError(sc.file_for(later, source), later, f"mixes ROS 1 and ROS 2 "
                            f"bridge nodes ({p1} is {t1}, {p2} is {t2}): a run records one "
                            "ROS version; spell every bridge node for one of them")
    out = sc.output
    implied: Literal[1, 2] | None = 1 if 1 in nodes else 2 if 2 in nodes else None
    if out.ros is not None:
        ros, because = out.ros, "output.ros"
    elif out.format == "bag":
        ros, because = 1, "output.format: bag"
    elif implied is not None:
        field_, _, type_name = nodes[implied]
        ros, because = implied, f"{field_} builds ROS {implied} bridge nodes: {type_name}"
    else:
        return ROS2_OUTPUT
    if ros == 2:
        return OutputKind(2, "mcap", because)
    if sc.ros2.enabled:
        raise ScenarioError(sc.file_for("ros2", source), "ros2.enabled", "the live ROS 2 "
                            f"bridge needs ROS 2 output, and this run records ROS 1 ({because}); "
                            "set output.ros: 2 to record ROS 2")
    return OutputKind(1, out.format or "mcap", because)


def check_output_topics(kind: OutputKind, topics: Iterable[Any], sc: Scenario,
                        source: str = "<scenario>") -> list[str]:
    """Refuse, before the run, a published topic whose type ROS 1 has no counterpart for
    (``topics``: the wiring plan's :class:`~harness.wiring.plan.PlannedTopic` s); returns
    warnings naming fields ROS 1 drops. Nothing to check for ROS 2."""
    if kind.ros == 2:
        return []
    warnings: list[str] = []
    seen: set[str] = set()
    for t in topics:
        if t.kind != "pub" or t.msgtype in seen:
            continue
        seen.add(t.msgtype)
        try:
            ros1_type(t.msgtype)
        except Ros1TypeError as err:
            raise ScenarioError(sc.file_for(t.field, source), t.field, f"{t.owner} publishes "
                                f"{t.topic} as {t.msgtype}, which {err.detail}; the run "
                                f"records ROS 1 ({kind.because})") from err
        dropped = dropped_fields(t.msgtype)
        if dropped:
            warnings.append(f"ROS 1 output: {t.msgtype} ({t.topic}) is recorded without "
                            f"{', '.join(f.rsplit('.', 1)[1] for f in dropped)} (ROS 1 has "
                            "no such fields)")
    return warnings
