"""Fixtures of the action-graph tests: a private registry with test node types, a stage, ticks.

The test node types live in a child :class:`~harness.graph.Registry`, so they never touch the
shared registry, and they shadow the real ROS bridge types (registered by another module) under
the same Isaac names; the tests behave the same whether or not those are registered.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest

from harness.graph import Attr, Database, GraphStage, NodeType, Registry
from harness.graph.registry import DEFAULT_REGISTRY

TICK_HZ = 60


@dataclass
class Ctx:
    """A recording evaluation context: what the test nodes did, in order."""

    tick: int = 0
    time_ns: int = 0
    log: list[tuple[str, Any]] = field(default_factory=list)
    published: list[dict[str, Any]] = field(default_factory=list)


def run_ticks(stage: GraphStage, n: int, ctx: Ctx | None = None, hz: int = TICK_HZ) -> Ctx:
    """Evaluate ``stage`` for ticks ``0..n-1`` at ``hz`` and return the context."""
    ctx = ctx if ctx is not None else Ctx()
    for k in range(n):
        ctx.tick = k
        ctx.time_ns = k * 1_000_000_000 // hz
        stage.evaluate(ctx)
    return ctx


class Record(NodeType):
    """Action: logs ``(node name, inputs:value)`` and passes execution on."""

    kind = "action"
    inputs = (Attr("execIn", "execution"), Attr("value", "any"))
    outputs = (Attr("execOut", "execution"), Attr("count", "int"))

    def compute(self, db: Database, ctx: Any) -> bool:
        ctx.log.append((db.node_path.rsplit("/", 1)[-1], db.inputs.value))
        db.outputs.count = db.outputs.count + 1
        return True


class Stop(NodeType):
    """Action: logs its name and stops execution."""

    kind = "action"
    inputs = (Attr("execIn", "execution"),)
    outputs = (Attr("execOut", "execution"),)

    def compute(self, db: Database, ctx: Any) -> bool:
        ctx.log.append((db.node_path.rsplit("/", 1)[-1], None))
        return False


class Branch(NodeType):
    """Action: fires ``execTrue`` or ``execFalse`` depending on ``condition``."""

    kind = "action"
    inputs = (Attr("execIn", "execution"), Attr("condition", "bool"))
    outputs = (Attr("execTrue", "execution"), Attr("execFalse", "execution"))

    def compute(self, db: Database, ctx: Any) -> bool:
        db.outputs.execTrue = db.inputs.condition
        db.outputs.execFalse = not db.inputs.condition
        return True


class Counter(NodeType):
    """Data: ``value`` = 10 * tick; counts its computes in ``calls``."""

    kind = "data"
    inputs = (Attr("offset", "double"),)
    outputs = (Attr("value", "double"),)

    def __init__(self) -> None:
        self.calls = 0

    def compute(self, db: Database, ctx: Any) -> bool:
        self.calls += 1
        db.outputs.value = 10.0 * ctx.tick + db.inputs.offset
        return True


class _FakePublisher(NodeType):
    """Action: records its topic, stamp and the extra inputs listed in ``recorded``."""

    kind = "action"
    recorded: tuple[str, ...] = ()
    outputs = (Attr("execOut", "execution"),)

    def compute(self, db: Database, ctx: Any) -> bool:
        entry = {
            "node": db.node_path,
            "topic": db.inputs.topicName,
            "stamp": db.inputs.timeStamp,
        }
        entry.update({name: getattr(db.inputs, name) for name in self.recorded})
        ctx.published.append(entry)
        return True


class FakePublishClock(_FakePublisher):
    inputs = (
        Attr("execIn", "execution"),
        Attr("topicName", "string", "clock"),
        Attr("timeStamp", "double"),
    )


class FakePublishTransformTree(_FakePublisher):
    recorded = ("targetPrims", "parentPrim")
    inputs = (
        Attr("execIn", "execution"),
        Attr("topicName", "string", "tf"),
        Attr("timeStamp", "double"),
        Attr("targetPrims", "target"),
        Attr("parentPrim", "target"),
        Attr("nodeNamespace", "string"),
    )


class FakePublishRawTransformTree(_FakePublisher):
    recorded = ("parentFrameId", "childFrameId", "rotation", "translation")
    inputs = (
        Attr("execIn", "execution"),
        Attr("topicName", "string", "tf"),
        Attr("timeStamp", "double"),
        Attr("parentFrameId", "string", "odom"),
        Attr("childFrameId", "string", "base_link"),
        Attr("rotation", "double[4]", (1.0, 0.0, 0.0, 0.0)),
        Attr("translation", "double[3]"),
    )


def make_test_registry() -> Registry:
    """A child of the shared registry holding the test node types."""
    registry = Registry(parent=DEFAULT_REGISTRY)
    registry.register("test.Record")(Record)
    registry.register("test.Stop")(Stop)
    registry.register("test.Branch")(Branch)
    registry.register("test.Counter")(Counter)
    registry.register(
        "test.PublishClock",
        aliases=("omni.isaac.ros_bridge.ROS1PublishClock", "isaacsim.ros2.bridge.ROS2PublishClock"),
    )(FakePublishClock)
    registry.register(
        "test.PublishTransformTree",
        aliases=(
            "omni.isaac.ros_bridge.ROS1PublishTransformTree",
            "isaacsim.ros2.bridge.ROS2PublishTransformTree",
        ),
    )(FakePublishTransformTree)
    registry.register(
        "test.PublishRawTransformTree",
        aliases=("isaacsim.ros2.bridge.ROS2PublishRawTransformTree",),
    )(FakePublishRawTransformTree)
    return registry


@pytest.fixture
def registry() -> Registry:
    return make_test_registry()


@pytest.fixture
def stage(registry: Registry) -> Iterator[GraphStage]:
    """A fresh stage over the test registry, current for the whole test."""
    with GraphStage(registry=registry) as current:
        yield current
