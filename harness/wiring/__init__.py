"""Wiring checks: what publishes and subscribes which topic, and whether the TF edges form one
valid tree — before a run (:func:`plan_wiring`, :func:`check_wiring`) and on a recorded bag
(:func:`tree_problems`, used by the TF health gate)."""

from harness.wiring.check import check_wiring
from harness.wiring.plan import Plan, PlannedEdge, PlannedTopic, plan_wiring
from harness.wiring.tree import Edge, TreeProblem, roots, tree_problems

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
