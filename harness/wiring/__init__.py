"""Wiring checks: what publishes and subscribes which topic, and whether the TF edges form one
valid tree — before a run (:func:`plan_wiring`, :func:`check_wiring`) and on a recorded bag
(:func:`tree_problems` of :mod:`harness.tf_tree`, used by the TF health gate).

Names are imported from their submodules on first use (:mod:`harness._lazy`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from harness._lazy import lazy_exports

if TYPE_CHECKING:
    from harness.tf_tree import Edge, TreeProblem, roots, tree_problems
    from harness.wiring.check import check_wiring
    from harness.wiring.plan import Plan, PlannedEdge, PlannedTopic, plan_wiring

__all__ = [
    "Edge",
    "Plan",
    "PlannedEdge",
    "PlannedTopic",
    "TreeProblem",
    "check_wiring",
    "plan_wiring",
    "roots",
    "tree_problems",
]

_WHERE = {
    "Edge": "harness.tf_tree",
    "TreeProblem": "harness.tf_tree",
    "roots": "harness.tf_tree",
    "tree_problems": "harness.tf_tree",
    "check_wiring": "check",
    "Plan": "plan",
    "PlannedEdge": "plan",
    "PlannedTopic": "plan",
    "plan_wiring": "plan",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
