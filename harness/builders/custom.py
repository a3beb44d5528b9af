"""Your own graph builders: the scenario's ``graphs:`` entries.

::

    graphs:
      - {builder: "my_pkg.my_graph:build", name: Teleop, robot: tb3, params: {speed: 0.2}}

Each enabled entry's function is imported like a system-under-test plug-in (Python path, then
the current directory) and called once per build with a :class:`GraphBuildContext`, after
the built-in graphs, on a stage of its own that holds only what it builds; its graphs then
join the simulation's stage. That makes a builder idempotent whatever it does (a graph it
built before is replaced, never extended twice) and lets the harness refuse a graph path
that is already taken by a built-in graph or an earlier entry.

The predictable path of an entry is ``/World/<name>Graph`` (:attr:`GraphBuildContext.graph_path`,
or :attr:`~GraphBuildContext.graph_config` for ``og.Controller.edit``); a builder may build
other paths too (seed 000 uses ``/ActionGraph``). It reaches the robots through
:class:`RobotPrims`: the articulation root, link, joint and mounted sensor prims by name.

Everything that goes wrong — the module does not import, the function is missing, it raises,
its graph collides — is a :class:`~harness.errors.ScenarioError` naming the scenario file and
``graphs[i].builder`` (or ``graphs[i].name``), so ``srr run`` and ``srr validate`` exit 2
with one line. Its nodes are annotated with the entry (:class:`NodeOrigin` ``node``), so the
wiring checks before the first tick (a prim that does not exist, a bad topic) name
``graphs[i]`` too.
"""

from __future__ import annotations

import types
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any

from harness.builders.base import BuildContext, NodeOrigin
from harness.errors import ScenarioError, reason
from harness.graph import GraphStage
from harness.graph.errors import GraphError
from harness.scenario import GraphSpec, RobotSpec, Scenario
from harness.sut.base import import_project_module

__all__ = ["GraphBuildContext", "RobotPrims", "build_custom", "current_build",
           "load_builder"]

Builder = Callable[["GraphBuildContext"], Any]


def _named(kind: str, robot: str, table: Mapping[str, str], name: str) -> str:
    try:
        return table[name]
    except KeyError:
        known = ", ".join(sorted(table)) or "none"
        raise GraphError(f"robot {robot} has no {kind} {name!r} ({kind}s: {known})") from None


@dataclass(frozen=True)
class RobotPrims:
    """One robot as a builder sees it: prim paths by name, and its ROS names.

    * ``prim``: the robot's prim (``articulation_prim``, e.g. ``/turtlebot3_waffle_pi``);
    * ``articulation_root``: the root link Isaac's ArticulationRootAPI sits on
      (``<prim>/base_footprint`` for the TurtleBot3, ``<prim>/body`` for the forklift), what
      ``IsaacArticulationController.robotPath`` and ``IsaacComputeOdometry.chassisPrim`` take;
    * ``links``: link name → prim (``base_scan`` → ``<prim>/base_scan``);
    * ``joints``: driven joint name → prim, where Isaac's URDF importer puts it
      (``<parent link prim>/<joint>``). srr's nodes take joint *names*
      (``ArticulationController.jointNames``); the path is for code that builds them from it;
    * ``sensors``: mounted ``lidar`` / ``imu`` / ``camera`` → prim (robots[].sensors blocks;
      ``graph: false`` mounts one without its built-in graph);
    * ``namespace`` and ``frame_prefix``: where the robot's relative topics resolve and what
      its frame ids start with (empty for a single robot).
    """

    name: str
    model: str
    prim: str
    articulation_root: str
    links: Mapping[str, str]
    joints: Mapping[str, str]
    sensors: Mapping[str, str]
    namespace: str = ""
    frame_prefix: str = ""

    def link(self, name: str) -> str:
        """Prim of link ``name``; an unknown link raises GraphError listing the links."""
        return _named("link", self.name, self.links, name)

    def joint(self, name: str) -> str:
        """Prim path of joint ``name``; an unknown joint raises GraphError listing them."""
        return _named("joint", self.name, self.joints, name)

    def sensor(self, kind: str) -> str:
        """Prim of the mounted ``lidar``, ``imu`` or ``camera``."""
        return _named("sensor", self.name, self.sensors, kind)

    def frame(self, name: str) -> str:
        """The robot's frame id for ``name`` (its frame prefix in front)."""
        return f"{self.frame_prefix}{name}"

    @classmethod
    def of(cls, world: Any, spec: RobotSpec) -> RobotPrims:
        """The robot ``spec`` as built in ``world``."""
        info = world.robot(spec.name)
        model = world.model
        body_link = {int(world.prim_ref(p).id): p for p in info.links.values()}
        joints = {}
        for name, ref in info.joints.items():
            parent = int(model.body_parentid[model.jnt_bodyid[ref.joint_id]])
            joints[name] = f"{body_link.get(parent, info.prim)}/{name}"
        return cls(name=info.name, model=info.model, prim=info.prim,
                   articulation_root=info.base_prim,
                   links=types.MappingProxyType(dict(info.links)),
                   joints=types.MappingProxyType(joints),
                   sensors=types.MappingProxyType(dict(info.sensors)),
                   namespace=spec.ns, frame_prefix=spec.frame_prefix or "")


@dataclass(frozen=True)
class GraphBuildContext:
    """What a ``graphs:`` builder gets: its entry, the robots, and the scene's prims.

    ``robot`` is the entry's robot (its ``robot:``, or the only enabled robot); ``robots``
    holds every enabled robot by name. ``params`` is the entry's ``params`` mapping.
    """

    name: str
    field: str
    params: Mapping[str, Any]
    robots: Mapping[str, RobotPrims]
    robot_name: str
    scenario: Scenario
    prims: frozenset[str]

    @property
    def graph_path(self) -> str:
        """The entry's predictable graph path, ``/World/<name>Graph``."""
        return f"/World/{self.name}Graph"

    @property
    def graph_config(self) -> dict[str, str]:
        """``og.Controller.edit``'s config for :attr:`graph_path`."""
        return {"graph_path": self.graph_path, "evaluator_name": "execution"}

    @property
    def robot(self) -> RobotPrims:
        """The entry's robot; a scene with several robots needs ``robot:`` on the entry."""
        if not self.robot_name:
            raise GraphError(f"{self.field}: no robot for this builder: name one with "
                             f"robot: (robots: {', '.join(self.robots) or 'none'})")
        return self.robots[self.robot_name]

    @property
    def tick_hz(self) -> int:
        """The playback tick rate (SimulationGate ``step = tick_hz / fps``)."""
        return self.scenario.physics.tick_hz

    def has_prim(self, path: str) -> bool:
        """Whether ``path`` is a prim of the built world."""
        return str(path) in self.prims


_CURRENT: ContextVar[GraphBuildContext | None] = ContextVar("harness_graph_build",
                                                            default=None)


def current_build() -> GraphBuildContext:
    """The context of the builder running now (for the Isaac shims in :mod:`harness.isaac`);
    none running raises GraphError."""
    ctx = _CURRENT.get()
    if ctx is None:
        raise GraphError("no graphs: builder is running (Isaac prim helpers work only while a "
                         "scenario builds its graphs)")
    return ctx


@contextmanager
def _running(ctx: GraphBuildContext) -> Iterator[None]:
    token = _CURRENT.set(ctx)
    try:
        yield
    finally:
        _CURRENT.reset(token)


def load_builder(spec: GraphSpec, file: str, field: str) -> Builder:
    """Import ``spec.builder`` (``"module:function"``) from the Python path or, after it, the
    current directory (as systems under test are); errors name ``file`` and ``field``."""
    module_name, _, attr = spec.builder.partition(":")
    try:
        module = import_project_module(module_name)
    except Exception as err:  # ImportError, or the module raising while it imports
        raise ScenarioError(file, f"{field}.builder", f"cannot import module {module_name!r}: "
                            f"{type(err).__name__}: {reason(err)}") from err
    func = getattr(module, attr, None)
    if func is None:
        raise ScenarioError(file, f"{field}.builder", f"module {module_name!r} has no {attr!r}")
    if not callable(func):
        raise ScenarioError(file, f"{field}.builder",
                            f"{spec.builder} is not a function (a {type(func).__name__})")
    return func  # type: ignore[no-any-return]


def build_custom(bc: BuildContext, taken: dict[str, str]) -> list[str]:
    """Run every enabled ``graphs:`` entry on the current stage; returns the graph paths they
    built. ``taken`` maps the graph paths already built (the built-in ones) to what built
    them, and gains the new ones."""
    stage = GraphStage.current()
    sc = bc.scenario
    robots = types.MappingProxyType({r.name: RobotPrims.of(bc.world, r)
                                     for r in sc.robots if r.enabled})
    prims = frozenset(bc.world.prims())
    paths: list[str] = []
    for i, spec in enumerate(sc.graphs):
        if not spec.enabled:
            continue
        field = f"graphs[{i}]"
        file = sc.file_for(field, bc.source)
        name = spec.name or ""
        ctx = GraphBuildContext(name=name, field=field, params=spec.params, robots=robots,
                                robot_name=spec.robot, scenario=sc, prims=prims)
        if ctx.graph_path in taken:
            raise ScenarioError(file, f"{field}.name", f"graph path {ctx.graph_path} is "
                                f"already taken by {taken[ctx.graph_path]}; rename it")
        build = load_builder(spec, file, field)
        own = GraphStage(registry=stage.registry)
        try:
            with own, _running(ctx):
                build(ctx)
        except Exception as err:  # whatever the builder raised: one line, exit 2
            raise ScenarioError(file, f"{field}.builder", f"{spec.builder} raised "
                                f"{type(err).__name__}: {reason(err)}") from err
        for graph in own.graphs():
            if graph.path in taken:
                raise ScenarioError(file, f"{field}.builder", f"{spec.builder} built "
                                    f"{graph.path}, a path already taken by "
                                    f"{taken[graph.path]}")
        for graph in own.graphs():
            if stage.has_graph(graph.path):  # left by an earlier build of this entry
                stage.delete_graph(graph.path)
            stage.adopt(graph)
            taken[graph.path] = f"{field} ({name})"
            for node in graph.nodes:  # wiring errors name the entry before the node
                bc.origins[node.path] = NodeOrigin(field, node=node.path)
            bc.custom_graphs[graph.path] = field
            paths.append(graph.path)
    return paths
