"""What a graph node or a system under test declares about its wiring, before anything runs.

Node types and plug-ins declare the topics they publish and subscribe (:class:`Endpoint`) and
the TF edges they publish (:class:`TfEdge`); :mod:`harness.wiring` collects them into a plan
and checks it (types per topic, publishers for every needed subscription, one TF tree).

Names are declared as set (``name`` relative or absolute, plus the ``namespace`` it resolves
in) so that the plan, which knows which scenario field set them, reports a bad name against
that field. ``input`` names the node input (or plug-in parameter) that set the topic.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from harness.bus.names import remap_topic

__all__ = ["Endpoint", "TfEdge", "is_static_tf_topic", "tf_tree_of"]


@dataclass(frozen=True)
class Endpoint:
    """One end of a topic: ``kind`` "pub" or "sub", the topic ``name`` as set, the
    ``namespace`` it resolves in, remapping ``rules`` applied after resolution, and the type.
    ``required``: a subscription its owner cannot work without (a control graph's
    ``cmd_vel``); an unfed required subscription is an error, any other a warning."""

    kind: Literal["pub", "sub"]
    name: str
    msgtype: str
    namespace: str = ""
    input: str = "topicName"
    required: bool = False
    rules: tuple[tuple[str, str], ...] = ()

    @property
    def topic(self) -> str:
        """The fully qualified topic (raises TopicNameError for a bad name)."""
        return remap_topic(self.name, self.namespace, dict(self.rules))


@dataclass(frozen=True)
class TfEdge:
    """A transform ``parent → child`` published on ``topic`` (fully qualified), static or
    dynamic. ``parent_input`` / ``child_input`` name the inputs that set the frames."""

    parent: str
    child: str
    static: bool
    topic: str
    parent_input: str = "parentFrameId"
    child_input: str = "childFrameId"


def is_static_tf_topic(topic: str) -> bool:
    """Whether ``topic`` is a static TF topic by its name: its leaf is ``tf_static``
    (``/tf_static``, ``/fleet/tf_static``)."""
    return topic.rsplit("/", 1)[-1] == "tf_static"


def tf_tree_of(topic: str) -> str | None:
    """The TF tree a ``tf2_msgs/TFMessage`` topic belongs to: its namespace (``/`` for
    ``/tf`` and ``/tf_static``, ``/fleet`` for ``/fleet/tf``), or None for a topic that is not
    a TF tree (the ground-truth topics ``/gt/<name>/tf``, or any other leaf name)."""
    head, _, leaf = topic.rpartition("/")
    if leaf not in ("tf", "tf_static") or topic.startswith("/gt/"):
        return None
    return head or "/"
