"""ROS 2 topic-name rules: validation and resolution against a namespace."""

from __future__ import annotations

import re

__all__ = ["TopicNameError", "resolve_topic", "validate_topic"]

_TOKEN = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


class TopicNameError(ValueError):
    """A topic name breaks the ROS 2 naming rules."""


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
