"""Tolerances for ``srr diff``: ``TOPIC_GLOB[:FIELD_GLOB]=ABS[,REL]``.

A tolerance says how far a numeric field of a candidate run may be from the baseline's and
still count as equal: ``|b - a| <= max(ABS, REL × |a|)`` per value (``a`` the baseline's).
Without a field glob it covers every numeric field of the matching topics. Globs know two
wildcards, ``*`` (any run of characters, ``/``, ``.`` and ``[`` included) and ``?`` (one
character); everything else, brackets included, is literal, so ``data[*]`` and
``transforms[0].transform.translation.x`` mean what they say.

When several tolerances match a field, the most specific wins: one with a field glob over one
without, then the longer literal part of the field glob, then of the topic glob, then the
later option.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

from harness.errors import SrrError

__all__ = ["SYNTAX", "Tolerance", "glob_match", "parse_tolerance", "tolerance_for"]

SYNTAX = "TOPIC_GLOB[:FIELD_GLOB]=ABS[,REL]"
EXAMPLE = "/odom:pose.pose.position.*=0.01,0.05"


@dataclass(frozen=True)
class Tolerance:
    """``topic`` and ``field`` globs (``field`` None: every field), absolute and relative
    allowance."""

    topic: str
    field: str | None
    abs: float
    rel: float = 0.0

    @property
    def spec(self) -> str:
        """The option text that gives this tolerance back."""
        where = self.topic if self.field is None else f"{self.topic}:{self.field}"
        return f"{where}={self.abs:g}" + (f",{self.rel:g}" if self.rel else "")

    def describe(self) -> str:
        """``±0.01`` or ``±max(0.01, 5% of |A|)``."""
        if not self.rel:
            return f"±{self.abs:g}"
        return f"±max({self.abs:g}, {self.rel * 100:g}% of |A|)"

    def specificity(self) -> tuple[int, int, int]:
        return (self.field is not None, _literal_len(self.field or ""), _literal_len(self.topic))


def _literal_len(glob: str) -> int:
    return len(glob.replace("*", "").replace("?", ""))


@lru_cache(maxsize=4096)
def _compiled(glob: str) -> re.Pattern[str]:
    parts = [".*" if c == "*" else "." if c == "?" else re.escape(c) for c in glob]
    return re.compile("".join(parts), re.DOTALL)


def glob_match(name: str, glob: str) -> bool:
    """Whether ``glob`` (``*`` and ``?`` wildcards only) matches all of ``name``."""
    return _compiled(glob).fullmatch(name) is not None


def _number(text: str, what: str, spec: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise SrrError(f"--tolerance {spec!r}: {what} {text!r} is not a number "
                       f"(expected {SYNTAX}, e.g. {EXAMPLE!r})") from None
    if not math.isfinite(v) or v < 0:
        raise SrrError(f"--tolerance {spec!r}: {what} must be a finite number >= 0, got {text}")
    return v


def parse_tolerance(spec: str) -> Tolerance:
    """Parse one ``--tolerance`` value; :class:`SrrError` (exit 2) naming the option when it
    is malformed."""
    where, eq, amounts = spec.rpartition("=")
    if not eq or not where.strip() or not amounts.strip():
        raise SrrError(f"--tolerance {spec!r}: expected {SYNTAX}, e.g. {EXAMPLE!r}")
    topic, colon, field = where.partition(":")
    topic, field = topic.strip(), field.strip()
    if not topic:
        raise SrrError(f"--tolerance {spec!r}: the topic glob is empty (expected {SYNTAX})")
    if colon and not field:
        raise SrrError(f"--tolerance {spec!r}: the field glob after ':' is empty "
                       f"(leave out ':' to cover every field of the topic)")
    if any(c.isspace() for c in topic + field):
        raise SrrError(f"--tolerance {spec!r}: globs must not contain whitespace")
    nums = amounts.split(",")
    if len(nums) > 2:
        raise SrrError(f"--tolerance {spec!r}: expected ABS or ABS,REL after '=', got "
                       f"{amounts!r}")
    abs_ = _number(nums[0].strip(), "ABS", spec)
    rel = _number(nums[1].strip(), "REL", spec) if len(nums) == 2 else 0.0
    return Tolerance(topic, field if colon else None, abs_, rel)


def tolerance_for(topic: str, field: str, tolerances: Sequence[Tolerance]) -> Tolerance | None:
    """The most specific tolerance covering ``field`` of ``topic``, or None."""
    best: Tolerance | None = None
    best_key: tuple[int, int, int, int] | None = None
    for i, t in enumerate(tolerances):
        if not glob_match(topic, t.topic):
            continue
        if t.field is not None and not glob_match(field, t.field):
            continue
        key = (*t.specificity(), i)
        if best_key is None or key > best_key:
            best, best_key = t, key
    return best
