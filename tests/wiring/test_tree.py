"""The TF tree checks on hand-made edges: each problem found, named, and nothing else."""

from __future__ import annotations

from harness.wiring import Edge, roots, tree_problems


def e(parent: str, child: str, static: bool = False, source: str = "a") -> Edge:
    return Edge(parent, child, static, source)


ROBOT = [e("world", "r/odom", True), e("r/odom", "r/base_link"),
         e("r/base_link", "r/lidar", True)]


def test_a_valid_forest_has_no_problem_and_its_roots() -> None:
    other = [e("world", "s/odom", True, "b"), e("s/odom", "s/base", source="b"),
             e("map", "m/x", True, "c")]
    assert tree_problems(ROBOT + other) == []
    assert roots(ROBOT + other) == ["map", "world"]
    assert tree_problems(ROBOT + ROBOT) == []  # the same edge twice is one edge


def test_two_parents_named_with_their_sources() -> None:
    (p,) = tree_problems([*ROBOT, e("other", "r/base_link", source="b")])
    assert p.kind == "two_parents" and p.frames == ("r/base_link", "other", "r/odom")
    assert p.detail == ("frame 'r/base_link' has 2 parents: 'r/odom' from a; 'other' from b")


def test_static_and_dynamic_for_one_frame() -> None:
    (p,) = tree_problems([*ROBOT, e("r/base_link", "r/lidar", False, "b")])
    assert p.kind == "static_dynamic" and p.frames == ("r/lidar",)
    assert "static from a" in p.detail and "dynamic from b" in p.detail


def test_two_sources_of_one_edge() -> None:
    (p,) = tree_problems([*ROBOT, e("r/odom", "r/base_link", source="b")])
    assert p.kind == "two_sources" and "by 2 sources: a, b" in p.detail


def test_cycles_are_found_once() -> None:
    problems = tree_problems([e("a", "b"), e("b", "c"), e("c", "a"), e("self", "self")])
    kinds = sorted((p.kind, p.frames) for p in problems)
    assert kinds == [("cycle", ("a", "b", "c")), ("cycle", ("self",))]
    assert any("a → b → c → a" in p.detail for p in problems)


def test_frame_ids_tf2_refuses() -> None:
    problems = tree_problems([e("world", "/odom"), e("world", "base link"), e("", "x")])
    bad = sorted(p.frames[0] for p in problems if p.kind == "frame_id")
    assert bad == ["", "/odom", "base link"]
