"""A graph's execution flow compiled into closures: what ``Graph.evaluate`` calls each tick.

:func:`compile_flow` turns a :class:`~harness.graph.plan.GraphPlan` into one function per
step, each with its node, ``db``, binding and the functions of the steps it leads to bound as
closure variables, so a tick is one call per node run and no look-ups by name. It does what
``Graph._fire_step`` and ``Graph._run`` do step by step, in the same order and with the same
errors:

* a node's compute runs (initialized first when needed); exceptions other than
  :class:`~harness.errors.SrrError` become a GraphError naming the node;
* when it returns true, execution goes on along its execution outputs in connection order,
  only along those it selected when it set any (``db.outputs.execOut = True``);
* a compute may edit the graph, which drops the plan the closures were built from: from then
  on the rest of the tick resolves by name (``Graph._push`` / ``Graph._fire``), exactly as
  without a plan. The compiled flow is part of the plan, so the next tick compiles anew.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from harness.errors import GraphError, SrrError
from harness.graph.plan import Evaluation, GraphPlan, Step

if TYPE_CHECKING:
    from harness.graph.engine import Graph, Node

__all__ = ["Run", "compile_flow", "failure"]

#: One step of a compiled flow: runs its node and whatever execution it leads to.
Run = Callable[[Evaluation], None]


def failure(node: Node, err: Exception) -> GraphError:
    """The error of a compute that raised ``err`` (anything but an SrrError)."""
    return GraphError(
        f"{node.path} ({node.canonical_type}): compute failed: {type(err).__name__}: {err}"
    )


def compile_flow(graph: Graph, flow: GraphPlan) -> Run:
    """The tick of ``graph`` while ``flow`` is its plan: every event step, in order."""
    runs: dict[int, Run] = {}

    def run_of(step: Step) -> Run:
        made = runs.get(id(step))
        if made is None:
            made = runs[id(step)] = _compile_step(graph, flow, step, run_of)
        return made

    events = tuple((step.node, run_of(step)) for step in flow.events)

    def tick(evaluation: Evaluation) -> None:
        for node, run in events:
            if graph._flow is flow:
                run(evaluation)
            elif graph._nodes.get(node.name) is node:  # not deleted meanwhile
                graph._fire(node, evaluation)

    return tick


def _compile_step(graph: Graph, flow: GraphPlan, step: Step,
                  run_of: Callable[[Step], Run]) -> Run:
    node = step.node
    impl, db, binding = node.impl, node._db, node._binding
    children = tuple((src_attr, child.node.name, run_of(child))
                     for src_attr, child in step.children)

    def run(evaluation: Evaluation) -> None:
        binding._evaluation = evaluation
        binding.fired = None
        try:
            if not node._initialized:
                impl.initialize(db, evaluation.ctx)
                node._initialized = True
            if not impl.compute(db, evaluation.ctx):
                return
        except SrrError:
            raise
        except Exception as err:
            raise failure(node, err) from err
        if graph._flow is not flow:
            graph._push(node, evaluation)
            return
        if not children:
            return
        fired = binding.fired
        for src_attr, name, child in children:
            if fired and not fired.get(src_attr):  # outputs were selected, not this one
                continue
            if graph._flow is flow:
                child(evaluation)
            else:
                target = graph._nodes.get(name)
                if target is not None:
                    graph._fire(target, evaluation)

    return run
