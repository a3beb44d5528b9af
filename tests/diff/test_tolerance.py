"""``--tolerance TOPIC_GLOB[:FIELD_GLOB]=ABS[,REL]``: parsing, globs, which one applies."""

from __future__ import annotations

import pytest

from harness.diff.tolerance import Tolerance, glob_match, parse_tolerance, tolerance_for
from harness.errors import SrrError


@pytest.mark.parametrize(("spec", "expected"), [
    ("/odom=0.01", Tolerance("/odom", None, 0.01, 0.0)),
    ("/odom:pose.pose.position.*=0.01,0.05", Tolerance("/odom", "pose.pose.position.*", 0.01,
                                                       0.05)),
    ("/gt/*/tf:transforms[*].transform.translation.?=1e-3",
     Tolerance("/gt/*/tf", "transforms[*].transform.translation.?", 0.001, 0.0)),
    ("*=0", Tolerance("*", None, 0.0, 0.0)),
])
def test_parses(spec: str, expected: Tolerance) -> None:
    t = parse_tolerance(spec)
    assert t == expected
    assert parse_tolerance(t.spec) == t  # the spec round-trips


@pytest.mark.parametrize(("spec", "says"), [
    ("/odom", "expected TOPIC_GLOB[:FIELD_GLOB]=ABS[,REL]"),
    ("=0.1", "expected TOPIC_GLOB"),
    ("/odom=", "expected TOPIC_GLOB"),
    ("/odom=abc", "ABS 'abc' is not a number"),
    ("/odom=0.1,x", "REL 'x' is not a number"),
    ("/odom=-1", "must be a finite number >= 0"),
    ("/odom=nan", "must be a finite number >= 0"),
    ("/odom=1,2,3", "expected ABS or ABS,REL"),
    ("/odom:=0.1", "field glob after ':' is empty"),
    (":x=0.1", "topic glob is empty"),
    ("/od om=0.1", "whitespace"),
])
def test_refuses_malformed(spec: str, says: str) -> None:
    with pytest.raises(SrrError) as err:
        parse_tolerance(spec)
    text = str(err.value)
    assert text.startswith(f"--tolerance {spec!r}: ") and says in text
    assert err.value.exit_code == 2


def test_globs_treat_brackets_literally() -> None:
    assert glob_match("data[*]", "data[*]")
    assert glob_match("data[*]", "data*")
    assert glob_match("transforms[0].transform.translation.x", "transforms[0].*")
    assert not glob_match("transforms[1].transform.translation.x", "transforms[0].*")
    assert glob_match("/gt/character_0/tf", "/gt/*/tf")
    assert glob_match("/gt/a/b/tf", "/gt/*/tf")  # * crosses '/'
    assert not glob_match("/odom", "/odo")  # the whole name must match
    assert glob_match("/odom", "/odo?")


def test_most_specific_tolerance_wins() -> None:
    every = Tolerance("*", None, 1.0)
    topic = Tolerance("/odom", None, 0.5)
    pos = Tolerance("/odom", "pose.pose.*", 0.1)
    x = Tolerance("/o*", "pose.pose.position.x", 0.01)
    tols = [x, pos, topic, every]
    assert tolerance_for("/odom", "pose.pose.position.x", tols) is x
    assert tolerance_for("/odom", "pose.pose.position.y", tols) is pos
    assert tolerance_for("/odom", "twist.twist.linear.x", tols) is topic
    assert tolerance_for("/tf", "transforms[0].transform.translation.x", tols) is every
    assert tolerance_for("/tf", "x", [pos]) is None
    # equally specific: the later option wins
    later = Tolerance("/odom", None, 0.2)
    assert tolerance_for("/odom", "a", [topic, later]) is later
