"""ROS 2 topic-name rules: validation and resolution against a namespace."""

from __future__ import annotations

import re

__all__ = ["FrameIdError", "TopicNameError", "remap_topic", "resolve_topic",
           "validate_frame_id", "validate_namespace", "validate_topic"]

_TOKEN = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


class TopicNameError(ValueError):
    """A topic name breaks the ROS 2 naming rules."""


class FrameIdError(ValueError):
    """A TF frame id that tf2 would refuse or mishandle."""


def validate_topic(name: str) -> None:
    """Raise :class:`TopicNameError` unless ``name`` is a valid ROS 2 topic name.

    Rules (REP/ROS 2 design "Topic and Service name mapping"): non-empty, tokens of letters,
    digits and underscores separated by single ``/``, no token starting with a digit, no
    trailing ``/``, no ``//``; a leading ``~`` is not supported by srr.
    """
    if not name:
        raise TopicNameError("topic name is empty")
    body = name[1:] if name.startswith("/") else name
    if not body:
        raise TopicNameError(f"{name!r} is not a topic name")
    if body.endswith("/"):
        raise TopicNameError(f"{name!r} ends with '/'")
    for token in body.split("/"):
        if not token:
            raise TopicNameError(f"{name!r} contains '//'")
        if not _TOKEN.match(token):
            raise TopicNameError(f"{name!r}: token {token!r} must be letters, digits and '_' "
                                 "and must not start with a digit")


def resolve_topic(name: str, namespace: str = "") -> str:
    """Fully qualify ``name``: absolute names stay, relative ones go under ``namespace``."""
    validate_topic(name)
    if name.startswith("/"):
        return name
    ns = namespace.strip("/")
    if ns:
        validate_topic(ns)
        return f"/{ns}/{name}"
    return f"/{name}"


def validate_namespace(ns: str) -> None:
    """Raise :class:`TopicNameError` unless ``ns`` is a valid ROS 2 namespace: empty (the
    root), ``/``, or a topic-like name (``fleet/a``, ``/fleet/a``)."""
    if ns in ("", "/"):
        return
    try:
        validate_topic(ns)
    except TopicNameError as err:
        raise TopicNameError(f"namespace {err}") from None


def validate_frame_id(frame: str) -> None:
    """Raise :class:`FrameIdError` unless tf2 accepts ``frame`` as a frame id: not empty, no
    leading ``/`` (tf2 refuses it), no whitespace or control characters."""
    if not frame:
        raise FrameIdError("frame id is empty")
    if frame.startswith("/"):
        raise FrameIdError(f"frame id {frame!r} starts with '/' (tf2 refuses it)")
    if any(c.isspace() or not c.isprintable() for c in frame):
        raise FrameIdError(f"frame id {frame!r} contains whitespace or control characters")


def remap_topic(name: str, namespace: str, rules: dict[str, str]) -> str:
    """Resolve ``name`` in ``namespace``, then apply remapping ``rules`` (from → to, both
    resolved in the same namespace), as ROS 2 matches remap rules on fully qualified names."""
    full = resolve_topic(name, namespace)
    for src, dst in rules.items():
        if resolve_topic(src, namespace) == full:
            return resolve_topic(dst, namespace)
    return full
