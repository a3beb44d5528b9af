"""The generic ROS 2 subscriber node: any message type, its fields as dynamic outputs.

Isaac Sim's ``ROS2Subscriber`` takes its type as ``messagePackage`` / ``messageSubfolder`` /
``messageName`` (``std_msgs`` / ``msg`` / ``Bool``) and, once the type is set, grows one
dynamic output per message field. Here the fields come from the typestore's definition of the
type (:data:`harness.serde.messages.TYPESTORE`): scalar fields (bool, integers, floats,
strings) become outputs of the matching attribute type, fields of nested messages are
flattened with ``_`` (``header_frame_id``, ``linear_x``), and arrays and sequences are left
out. ``std_msgs/Bool`` thus gives ``outputs:data`` (bool).

The outputs exist once :func:`define_message_outputs` has run on the node: builders call it
right after setting the type, so they can connect to ``outputs:data`` in the same build (what
Isaac does when the type attributes change); otherwise the node adds the missing ones on its
first compute. An output already there with another type is refused.

On a tick when messages have arrived since the last one, the outputs take the newest message
and ``execOut`` fires; otherwise execution stops here and the outputs keep their values (the
type's zero values before the first message). ``qosProfile`` is accepted for compatibility and
not used: the in-process bus delivers every message.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import cache
from typing import Any

from rosbags.interfaces import Nodetype

from harness.bus.endpoints import Endpoint, TfEdge
from harness.graph import Attr, GraphStage, Node, NodeType, register
from harness.graph.errors import GraphError
from harness.graph.nodes.ros_bridge import BRIDGE_INPUTS, topic_of
from harness.serde.messages import TYPESTORE, UnknownMessageType, require_msgtype

__all__ = ["MessageField", "Subscriber", "define_message_outputs", "message_fields"]

_SCALARS: dict[str, str] = {
    "bool": "bool",
    "byte": "uint",
    "char": "uint",
    "int8": "int",
    "uint8": "uint",
    "int16": "int",
    "uint16": "uint",
    "int32": "int",
    "uint32": "uint",
    "int64": "int64",
    "uint64": "uint64",
    "float32": "float",
    "float64": "double",
    "string": "string",
    "wstring": "string",
}

#: One output: its name, the attribute path inside the message and the attribute type.
MessageField = tuple[str, tuple[str, ...], str]


@cache
def message_fields(msgtype: str) -> tuple[MessageField, ...]:
    """The outputs a subscriber of ``msgtype`` (``pkg/msg/Name``) gets, in definition order."""
    if msgtype not in TYPESTORE.fielddefs:
        raise KeyError(f"unknown ROS 2 message type {msgtype!r}")
    out: list[MessageField] = []

    def walk(typename: str, prefix: tuple[str, ...]) -> None:
        for name, (nodetype, args) in TYPESTORE.fielddefs[typename][1]:
            path = (*prefix, name)
            if nodetype == Nodetype.BASE and args[0] in _SCALARS:
                out.append(("_".join(path), path, _SCALARS[args[0]]))
            elif nodetype == Nodetype.NAME:
                walk(str(args), path)

    walk(msgtype, ())
    return tuple(out)


def _msgtype(package: str, subfolder: str, name: str, where: str) -> str:
    if not package or not name:
        raise GraphError(f"{where}: set inputs:messagePackage and inputs:messageName "
                         "(e.g. std_msgs / Bool)")
    msgtype = f"{package}/{subfolder or 'msg'}/{name}"
    try:
        return require_msgtype(msgtype)
    except UnknownMessageType as err:
        raise GraphError(f"{where}: {err}") from err


def define_message_outputs(node: Node) -> tuple[str, ...]:
    """Give a subscriber node one output per field of its message type (idempotent).

    Returns the output names. An existing output of another type raises GraphError.
    """
    def value(attr: str) -> str:
        return str(node.graph.get_value(node.name, f"inputs:{attr}"))

    msgtype = _msgtype(value("messagePackage"), value("messageSubfolder"),
                       value("messageName"), node.path)
    names = []
    for name, _, type_name in message_fields(msgtype):
        full = f"outputs:{name}"
        existing = node.attr(full)
        if existing is None:
            node.graph.create_attribute(node.name, full, type_name)
        elif existing.type != type_name:
            raise GraphError(f"{node.path}.{full}: is {existing.type}, but {msgtype} field "
                             f"{name!r} needs {type_name}")
        names.append(name)
    return tuple(names)


@register("srr.Subscriber", aliases=(
    "isaacsim.ros2.bridge.ROS2Subscriber",
    "omni.isaac.ros2_bridge.ROS2Subscriber",
))
class Subscriber(NodeType):
    """Subscribes to ``topicName`` with the type given by the message inputs."""

    kind = "action"
    inputs = (
        *BRIDGE_INPUTS,
        Attr("messagePackage", "string", ""),
        Attr("messageSubfolder", "string", "msg"),
        Attr("messageName", "string", ""),
        Attr("topicName", "string", ""),
    )
    outputs = (Attr("execOut", "execution"),)

    def __init__(self) -> None:
        self._pending: list[Any] = []
        self._bus: Any = None

    def initialize(self, db: Any, ctx: Any) -> None:
        i = db.inputs
        msgtype = _msgtype(i.messagePackage, i.messageSubfolder, i.messageName, db.node_path)
        self._fields = message_fields(msgtype)
        have = set(dir(db.outputs))
        if any(name not in have for name, _, _ in self._fields):
            try:
                stage = GraphStage.current()
            except GraphError as err:
                raise GraphError(f"{db.node_path}: cannot add the message outputs: {err}; "
                                 "call define_message_outputs() when building") from None
            define_message_outputs(stage.graph(db.graph_path).node(db.node_path.rsplit("/")[-1]))
        topic = topic_of(db)
        self._pending.clear()
        if self._bus is not ctx.bus:  # a reset re-initializes; subscribe once per bus
            ctx.bus.subscribe(topic, msgtype, self._pending.append)
            self._bus = ctx.bus

    def endpoints(self, value: Callable[[str], Any]) -> Sequence[Endpoint | TfEdge]:
        msgtype = _msgtype(str(value("messagePackage")), str(value("messageSubfolder")),
                           str(value("messageName")), "inputs:messageName")
        return (Endpoint("sub", str(value("topicName")), msgtype, str(value("nodeNamespace")),
                         required=True),)

    def compute(self, db: Any, ctx: Any) -> bool:
        if not self._pending:
            return False
        msg = self._pending[-1]
        self._pending.clear()
        for name, path, _ in self._fields:
            value = msg
            for part in path:
                value = getattr(value, part)
            setattr(db.outputs, name, value)
        return True
