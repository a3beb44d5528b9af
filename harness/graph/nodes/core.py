"""Built-in node types: ticks, simulation time, gates, script nodes and small data helpers.

Each type is registered under ``srr.<Name>`` plus the Isaac Sim / OmniGraph names builders use.
Time comes from the evaluation context: ``ctx.tick`` (tick index) and ``ctx.time_ns`` (simulated
time in nanoseconds). Stage units are metres, so unit scaling is the identity.
"""

from __future__ import annotations

import builtins
from collections.abc import Callable
from pathlib import Path
from typing import Any, cast

from harness.graph.attributes import Attr
from harness.graph.errors import GraphError
from harness.graph.node import Database, NodeType
from harness.graph.registry import register

__all__ = [
    "BreakVector3",
    "ConstantBool",
    "ConstantDouble",
    "ConstantInt",
    "ConstantString",
    "ConstantToken",
    "ConstructArray",
    "OnPlaybackTick",
    "OnTick",
    "ROS2Context",
    "ReadSimulationTime",
    "ScaleToFromStageUnit",
    "ScriptNode",
    "SimulationGate",
]

_TICK_OUTPUTS = (
    Attr("tick", "execution"),
    Attr("time", "double"),
    Attr("frame", "double"),
    Attr("deltaSeconds", "double"),
)


class _TickSource(NodeType):
    """The tick event nodes: each firing writes ``time`` (sim seconds), ``frame`` (the tick
    index) and ``deltaSeconds`` (since this node last fired, 0 the first time). Fires on every
    evaluation unless a subclass's :meth:`compute` says otherwise.

    The three values are floats, the stored form of ``double``, so a planned node writes
    them straight into its output values (``db.stored``): every graph has a tick node, and
    ``db.outputs.<name> = value`` would check and convert three times a tick what needs
    neither."""

    kind = "event"
    outputs = _TICK_OUTPUTS

    def __init__(self) -> None:
        self._last_fire_ns: int | None = None

    def compute(self, db: Database, ctx: Any) -> bool:
        now = int(ctx.time_ns)
        last = self._last_fire_ns
        delta = 0.0 if last is None else (now - last) / 1e9
        self._last_fire_ns = now
        stored = db.stored
        if stored is None:  # not planned yet: the checked writes
            out = db.outputs
            out.time, out.frame, out.deltaSeconds = now / 1e9, float(ctx.tick), delta
            return True
        stored["outputs:time"] = now / 1e9
        stored["outputs:frame"] = float(ctx.tick)
        stored["outputs:deltaSeconds"] = delta
        return True

    def reset(self) -> None:
        self._last_fire_ns = None


@register("srr.OnPlaybackTick", aliases=("omni.graph.action.OnPlaybackTick",))
class OnPlaybackTick(_TickSource):
    """Fires every evaluation. ``time`` is sim seconds, ``frame`` the tick index,
    ``deltaSeconds`` the time since this node last fired (0 on the first tick)."""


@register("srr.OnTick", aliases=("omni.graph.action.OnTick",))
class OnTick(_TickSource):
    """Fires on the first evaluation and then every ``framePeriod + 1`` evaluations.

    The harness always plays back, so ``onlyPlayback`` changes nothing.
    """

    inputs = (Attr("framePeriod", "uint", 0), Attr("onlyPlayback", "bool", True))

    def __init__(self) -> None:
        super().__init__()
        self._count = 0

    def compute(self, db: Database, ctx: Any) -> bool:
        count = self._count
        self._count += 1
        if count % (int(db.inputs.framePeriod) + 1) != 0:
            return False
        return super().compute(db, ctx)

    def reset(self) -> None:
        super().reset()
        self._count = 0


@register(
    "srr.ReadSimulationTime",
    aliases=(
        "omni.isaac.core_nodes.IsaacReadSimulationTime",
        "isaacsim.core.nodes.IsaacReadSimulationTime",
    ),
)
class ReadSimulationTime(NodeType):
    """``simulationTime`` = ``ctx.time_ns / 1e9`` seconds."""

    kind = "data"
    inputs = (Attr("resetOnStop", "bool", True), Attr("swhFrameNumber", "int", 0))
    outputs = (Attr("simulationTime", "double"),)

    def compute(self, db: Database, ctx: Any) -> bool:
        stored = db.stored  # a float, the stored form of double (see _TickSource)
        assert stored is not None
        stored["outputs:simulationTime"] = int(ctx.time_ns) / 1e9
        return True


@register(
    "srr.SimulationGate",
    aliases=(
        "omni.isaac.core_nodes.IsaacSimulationGate",
        "isaacsim.core.nodes.IsaacSimulationGate",
    ),
)
class SimulationGate(NodeType):
    """Passes execution on its 1st, (1+step)th, (1+2*step)th... execution; step 0 never."""

    kind = "action"
    inputs = (Attr("execIn", "execution"), Attr("step", "uint", 1))
    outputs = (Attr("execOut", "execution"),)

    def __init__(self) -> None:
        self._count = 0

    def compute(self, db: Database, ctx: Any) -> bool:
        step = int(db.inputs.step)
        count = self._count
        self._count += 1
        return step > 0 and count % step == 0

    def reset(self) -> None:
        self._count = 0


ScriptCompute = Callable[[Database], Any]


@register("srr.ScriptNode", aliases=("omni.graph.scriptnode.ScriptNode",))
class ScriptNode(NodeType):
    """Runs ``compute(db)`` from ``inputs:script`` (or the file at ``inputs:scriptPath`` when
    ``inputs:usePath``). The source is compiled once per text, in a fresh namespace for this
    node; an optional ``setup(db)`` runs once after compiling. A falsy return stops execution.
    The script sees the node's dynamic attributes as ``db.inputs.x`` / ``db.outputs.y``.
    """

    kind = "action"
    inputs = (
        Attr("execIn", "execution"),
        Attr("script", "string"),
        Attr("usePath", "bool", False),
        Attr("scriptPath", "string"),
    )
    outputs = (Attr("execOut", "execution"),)

    def __init__(self) -> None:
        self._source: str | None = None
        self._compute: ScriptCompute | None = None

    def reset(self) -> None:
        self._source = None
        self._compute = None

    def _read_source(self, db: Database) -> str:
        if db.inputs.usePath:
            script_path = str(db.inputs.scriptPath)
            if not script_path:
                raise GraphError(
                    f"{db.node_path}: inputs:usePath is set but inputs:scriptPath is empty"
                )
            try:
                return Path(script_path).read_text(encoding="utf-8")
            except OSError as err:
                raise GraphError(
                    f"{db.node_path}: cannot read inputs:scriptPath {script_path!r}: {err}"
                ) from err
        source = str(db.inputs.script)
        if not source.strip():
            raise GraphError(f"{db.node_path}: inputs:script is empty")
        return source

    def _load(self, db: Database) -> ScriptCompute:
        source = self._read_source(db)
        if self._compute is not None and source == self._source:
            return self._compute
        where = db.node_path
        try:
            code = compile(source, f"<script {where}>", "exec")
        except SyntaxError as err:
            raise GraphError(
                f"{where}: script syntax error at line {err.lineno}: {err.msg}"
            ) from err
        namespace: dict[str, Any] = {"__name__": "__srr_script__", "__builtins__": builtins}
        try:
            exec(code, namespace)
        except Exception as err:
            raise GraphError(
                f"{where}: script failed while loading: {type(err).__name__}: {err}"
            ) from err
        compute = namespace.get("compute")
        if not callable(compute):
            raise GraphError(f"{where}: script defines no compute(db) function")
        setup = namespace.get("setup")
        if callable(setup):
            try:
                setup(db)
            except Exception as err:
                raise GraphError(
                    f"{where}: script setup(db) raised {type(err).__name__}: {err}"
                ) from err
        self._source = source
        self._compute = cast(ScriptCompute, compute)
        return self._compute

    def compute(self, db: Database, ctx: Any) -> bool:
        script_compute = self._load(db)
        try:
            result = script_compute(db)
        except Exception as err:
            raise GraphError(
                f"{db.node_path}: script compute(db) raised {type(err).__name__}: {err}"
            ) from err
        return bool(result)


@register("srr.BreakVector3", aliases=("omni.graph.nodes.BreakVector3",))
class BreakVector3(NodeType):
    """Splits a 3-vector into ``x``, ``y``, ``z``."""

    kind = "data"
    inputs = (Attr("tuple", "double[3]"),)
    outputs = (Attr("x", "double"), Attr("y", "double"), Attr("z", "double"))

    def compute(self, db: Database, ctx: Any) -> bool:
        x, y, z = db.inputs.tuple
        db.outputs.x = x
        db.outputs.y = y
        db.outputs.z = z
        return True


@register(
    "srr.ConstructArray",
    aliases=("srr.MakeArray", "omni.graph.nodes.ConstructArray", "omni.graph.nodes.MakeArray"),
)
class ConstructArray(NodeType):
    """``array`` = (input0, ..., input{arraySize-1}); inputs past input3 are dynamic attributes."""

    kind = "data"
    inputs = (
        Attr("arraySize", "int", 1),
        Attr("input0", "any"),
        Attr("input1", "any"),
        Attr("input2", "any"),
        Attr("input3", "any"),
    )
    outputs = (Attr("array", "any"),)

    def compute(self, db: Database, ctx: Any) -> bool:
        size = int(db.inputs.arraySize)
        if size < 0:
            raise GraphError(f"{db.node_path}.inputs:arraySize: must be >= 0, got {size}")
        items = []
        for i in range(size):
            try:
                items.append(getattr(db.inputs, f"input{i}"))
            except AttributeError:
                raise GraphError(
                    f"{db.node_path}: inputs:arraySize is {size} but there is no inputs:input{i}"
                ) from None
        db.outputs.array = tuple(items)
        return True


def _constant(type_name: str) -> tuple[tuple[Attr, ...], tuple[Attr, ...]]:
    return (Attr("value", type_name),), (Attr("value", type_name),)


class _Constant(NodeType):
    """``outputs:value`` = ``inputs:value`` (``inputs:value`` may also be used as a source)."""

    kind = "data"

    def compute(self, db: Database, ctx: Any) -> bool:
        db.outputs.value = db.inputs.value
        return True


@register("srr.ConstantDouble", aliases=("omni.graph.nodes.ConstantDouble",))
class ConstantDouble(_Constant):
    inputs, outputs = _constant("double")


@register("srr.ConstantInt", aliases=("omni.graph.nodes.ConstantInt",))
class ConstantInt(_Constant):
    inputs, outputs = _constant("int")


@register("srr.ConstantBool", aliases=("omni.graph.nodes.ConstantBool",))
class ConstantBool(_Constant):
    inputs, outputs = _constant("bool")


@register("srr.ConstantString", aliases=("omni.graph.nodes.ConstantString",))
class ConstantString(_Constant):
    inputs, outputs = _constant("string")


@register("srr.ConstantToken", aliases=("omni.graph.nodes.ConstantToken",))
class ConstantToken(_Constant):
    inputs, outputs = _constant("token")


@register(
    "srr.ScaleToFromStageUnit",
    aliases=(
        "omni.isaac.core_nodes.OgnIsaacScaleToFromStageUnit",
        "isaacsim.core.nodes.OgnIsaacScaleToFromStageUnit",
    ),
)
class ScaleToFromStageUnit(NodeType):
    """``result`` = ``value``: the harness stage unit is the metre, so both directions are 1:1."""

    kind = "data"
    inputs = (Attr("value", "any"), Attr("conversion", "token", "Convert to stage units"))
    outputs = (Attr("result", "any"),)

    def compute(self, db: Database, ctx: Any) -> bool:
        db.outputs.result = db.inputs.value
        return True


@register(
    "srr.ROS2Context",
    aliases=("omni.isaac.ros2_bridge.ROS2Context", "isaacsim.ros2.bridge.ROS2Context"),
)
class ROS2Context(NodeType):
    """A ROS 2 context handle; the harness bus has one context, so ``context`` is always 0."""

    kind = "data"
    inputs = (Attr("domain_id", "int", 0), Attr("useDomainIDEnvVar", "bool", True))
    outputs = (Attr("context", "uint64", 0),)

    def compute(self, db: Database, ctx: Any) -> bool:
        db.outputs.context = 0
        return True
