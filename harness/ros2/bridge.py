"""The live ROS 2 bridge: a system under test that stands for the external nodes.

Set up (before the first tick): take a ROS_DOMAIN_ID (:mod:`harness.ros2.domain`), start the
external processes (:mod:`harness.ros2.processes`) with ``use_sim_time``, create an rclpy node
in a context of its own and a raw subscription for every declared output, and wait until the
external nodes are there (each output, and ``ready_topic`` when set, has a publisher).

Every tick: each message published on the bus is also published on the ROS 2 graph from its
CDR bytes (a bus tap, at publish time: the graphs' sensor output and ``/clock`` of the tick go
out before the systems under test step). The first tick waits until the external nodes are
there and the ROS 2 graph has settled; a topic's rclpy publisher is made at its first message,
with the QoS the bus then has for it (final by then), and that first message waits (at most
``ros2.timeout``) until discovery has matched the compatible subscribers already on the graph,
so nodes that were ready do not miss the start. In the systems-under-test phase the bridge waits —
lockstep — until every output due at this tick has arrived (``rate_hz``: one message per
period of simulated time; stamped types without a rate: a header stamped at or after the
tick's time), then hands everything received to the bus, where it is recorded and delivered
like any plug-in's output. Past ``ros2.timeout`` seconds of wall-clock waiting (or when an
external process exits) the run stops INVALID naming the output
(:class:`~harness.errors.RunStopped`), never a silently degraded run.

Messages whose type has no rclpy type support in this environment are not bridged; they are
listed once in the run's warnings (``tf2_msgs`` is one with the PyPI wheels: see
docs/howto/ros2.md).
"""

from __future__ import annotations

import contextlib
import importlib
import math
import os
import shutil
import struct
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from harness.blas import users_environ
from harness.bus.bus import Envelope, Qos
from harness.errors import RunStopped, SrrError
from harness.recording.recorder import Recorder, cdr_bytes
from harness.ros2.domain import DomainInUse, DomainLease, lease_domain
from harness.ros2.processes import ExternalProcess, start_processes, stop_processes
from harness.scenario.schema import Ros2OutputSpec, Ros2Spec
from harness.serde.messages import deserialize
from harness.sut.base import SutContext, SystemUnderTest
from harness.sut.errors import PluginError
from harness.validation import close_match

__all__ = ["Ros2Bridge", "message_class", "qos_profile"]

_READY_POLL_S = 0.05
_SETTLE_S = 0.5  # the ROS 2 graph unchanged this long (wall clock) before the first tick


def message_class(msgtype: str) -> Any | None:
    """The rclpy message class of ``pkg/msg/Name``, None when this environment has no type
    support for it."""
    pkg, kind, name = ([*msgtype.split("/"), "", ""])[:3]
    try:
        return getattr(importlib.import_module(f"{pkg}.{kind}"), name)
    except (ImportError, AttributeError, ValueError):
        return None


def _stamp_ns(raw: bytes) -> int:
    """header.stamp of a CDR message whose first field is a std_msgs/Header."""
    fmt = "<iI" if raw[1] == 1 else ">iI"
    sec, nanosec = struct.unpack_from(fmt, raw, 4)
    return int(sec) * 1_000_000_000 + int(nanosec)


def _period(now_ns: int, rate_hz: float) -> int:
    """Index of the period of ``rate_hz`` that tick time ``now_ns`` falls in. Tick times are
    whole nanoseconds rounded down (k * 1e9 // tick_hz), up to 1 ns early."""
    return math.floor((now_ns + 1) * rate_hz / 1e9)


@dataclass
class _Output:
    spec: Ros2OutputSpec
    topic: str
    stamped: bool
    received: list[bytes] = field(default_factory=list)
    period: int = -1  # index of the last period whose message arrived
    latest_stamp_ns: int = -1
    subscription: Any = None

    def due(self, now_ns: int) -> bool:
        if self.spec.rate_hz is not None:
            return _period(now_ns, self.spec.rate_hz) > self.period
        return True

    def arrived(self, now_ns: int) -> bool:
        if self.spec.rate_hz is not None:
            return bool(self.received)
        return self.latest_stamp_ns >= now_ns


def qos_profile(qos: Qos, *, strict: bool = False) -> Any:
    """The rclpy QoSProfile of a bus (or recorded) QoS: keep-last ``depth``. ``strict``: a
    reliable, volatile topic keeps every message until each subscriber acknowledged it
    (keep-all; history is no part of QoS matching, so the same subscribers match): a burst
    longer than ``depth`` can never overwrite a message a slow subscriber has not received."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    keep_all = strict and qos.reliability == "reliable" and qos.durability == "volatile"
    return QoSProfile(  # type: ignore[no-untyped-call]
        history=HistoryPolicy.KEEP_ALL if keep_all else HistoryPolicy.KEEP_LAST,
        depth=max(qos.depth, 1),
        reliability=(ReliabilityPolicy.RELIABLE if qos.reliability == "reliable"
                     else ReliabilityPolicy.BEST_EFFORT),
        durability=(DurabilityPolicy.TRANSIENT_LOCAL if qos.durability == "transient_local"
                    else DurabilityPolicy.VOLATILE))


class Ros2Bridge(SystemUnderTest):
    """Added by ``srr run --ros2`` (``ros2.enabled``); ``params.run_dir`` is where the
    external processes' logs go. With ``params.check_only`` (``srr validate``) it makes
    every check that needs no ROS 2 graph — rclpy, the outputs' types and lockstep rules, the
    external commands — and declares the outputs for the wiring checks, then stops there."""

    def setup(self, ctx: SutContext) -> None:
        self.ctx = ctx
        self.setup_notes: list[str] = []
        self.spec: Ros2Spec = ctx.scenario.ros2
        # errors name the scenario file and the ros2 field, not the bridge's own entry
        self.source = ctx.field.rsplit(": systems_under_test", 1)[0]
        self.run_dir = Path(str(ctx.params.get("run_dir", ".")))
        self.lease: DomainLease | None = None
        self.procs: list[ExternalProcess] = []
        self.pubs: dict[str, Any] = {}
        self.pub_qos: dict[str, Qos] = {}
        self._via_recorder = False
        self._started = False
        self.unbridged: dict[str, str] = {}
        self.outputs: list[_Output] = []
        self._rclpy: Any = None
        try:
            import rclpy
            from rclpy.executors import SingleThreadedExecutor
        except ImportError as err:
            raise PluginError(f"{self.source}: ros2.enabled needs rclpy (pip install -e "
                              f"'.[ros2]', Linux x86-64): {err}") from None
        self._rclpy = rclpy
        for i, proc in enumerate(self.spec.external):
            if shutil.which(proc.cmd[0]) is None:
                raise PluginError(f"{self.source}: ros2.external[{i}].cmd: {proc.cmd[0]!r} "
                                  "is not an executable file or on PATH")
        if ctx.params.get("check_only"):
            for i, out in enumerate(self.spec.outputs):
                self._output_rule(i, out)
                ctx.publisher(out.topic, out.type)
            return
        self.setup_notes = self._tf2_msgs()
        try:
            self.lease = lease_domain(self.spec.domain_id)
        except DomainInUse as err:
            raise PluginError(f"{self.source}: ros2.domain_id: {err}") from None
        # with tf2_msgs on PYTHONPATH for Python nodes; their BLAS threads as the user set them
        env = users_environ()
        env["ROS_DOMAIN_ID"] = str(self.lease.domain_id)
        env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = ("LOCALHOST" if self.spec.localhost_only
                                                else "SUBNET")
        env.pop("ROS_LOCALHOST_ONLY", None)  # deprecated in Jazzy; the range above decides
        os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = env["ROS_AUTOMATIC_DISCOVERY_RANGE"]
        os.environ.pop("ROS_LOCALHOST_ONLY", None)
        from rclpy.context import Context

        self.rcl_context = Context()
        rclpy.init(context=self.rcl_context, domain_id=self.lease.domain_id)
        self.node = rclpy.create_node("srr_bridge", context=self.rcl_context,
                                      start_parameter_services=False)
        self.executor = SingleThreadedExecutor(context=self.rcl_context)
        self.executor.add_node(self.node)
        for i, out in enumerate(self.spec.outputs):
            self._add_output(i, out)
        ctx.bus.add_tap(self._forward)
        self.procs = start_processes(self.spec.external, env, self.run_dir / "ros2")
        self._wait_ready()

    # -- set-up ---------------------------------------------------------------------------
    def _qos(self, topic: str, base: Qos) -> Any:
        over = self.spec.qos.get(topic)
        if over is not None:
            base = Qos(durability=over.durability or base.durability,
                       reliability=over.reliability or base.reliability,
                       depth=over.depth or base.depth)
        return qos_profile(base, strict=True)

    def _output_rule(self, i: int, out: Ros2OutputSpec) -> tuple[Any, bool]:
        """The output's message class and whether it is stamped; a clear error when it has
        no type support or neither a rate nor a header stamp to wait for."""
        where = f"ros2.outputs[{i}]"
        cls = message_class(out.type)
        if cls is None:
            raise PluginError(f"{self.source}: {where}.type: no rclpy type support for "
                              f"{out.type!r} in this environment")
        fields = list(cls.get_fields_and_field_types())
        stamped = bool(fields) and fields[0] == "header"
        if out.rate_hz is None and not stamped:
            raise PluginError(f"{self.source}: {where}.rate_hz: {out.type} has no header "
                              "stamp, so lockstep needs the rate it is published at")
        return cls, stamped

    def _add_output(self, i: int, out: Ros2OutputSpec) -> None:
        cls, stamped = self._output_rule(i, out)
        topic = self.ctx.topic(out.topic)
        self.ctx.publisher(out.topic, out.type)  # declared: the wiring checks see it
        o = _Output(out, topic, stamped)
        def received(raw: bytes, o: _Output = o) -> None:
            self._received(o, raw)

        o.subscription = self.node.create_subscription(
            cls, topic, received, self._qos(topic, Qos(depth=100)), raw=True)
        self.outputs.append(o)

    def _publisher(self, topic: str, msgtype: str, qos: Qos) -> Any | None:
        """The rclpy publisher of ``topic`` with the bus's QoS for it. A topic's bus QoS is
        final once its publisher advertises (a subscriber may declare it first, with the
        default), so a publisher made before that is made again when the QoS changed."""
        if topic in self.pubs:
            if self.pubs[topic] is None or self.pub_qos.get(topic) == qos:
                return self.pubs[topic]
            self.node.destroy_publisher(self.pubs[topic])
        if any(o.topic == topic for o in self.outputs):
            self.pubs[topic] = None  # never echoed back to the nodes that publish it
            return None
        cls = message_class(msgtype)
        if cls is None:
            self.unbridged[topic] = msgtype
            self.pubs[topic] = None
            return None
        pub = self.node.create_publisher(cls, topic, self._qos(topic, qos))
        self.pubs[topic], self.pub_qos[topic] = pub, qos
        if self._started:  # let discovery match the subscribers already there (bounded)
            deadline = time.monotonic() + self.spec.timeout
            while not self._matched(topic) and time.monotonic() < deadline:
                self.executor.spin_once(timeout_sec=_READY_POLL_S)
        return pub

    def _matched(self, topic: str) -> bool:
        """Every subscription the graph knows on ``topic`` with a QoS compatible with our
        publisher's is matched with it (an incompatible one never will be: rclpy warns)."""
        from rclpy.qos import QoSCompatibility, qos_check_compatible

        pub = self.pubs.get(topic)
        if pub is None:
            return True
        subs = self.node.get_subscriptions_info_by_topic(topic)
        wanted = sum(qos_check_compatible(pub.qos_profile, s.qos_profile)[0]
                     != QoSCompatibility.ERROR for s in subs)
        return bool(pub.get_subscription_count() >= wanted)

    def _graph(self) -> frozenset[tuple[str, int, int]]:
        """What discovery knows: every topic with its publisher and subscription counts."""
        names = [name for name, _ in self.node.get_topic_names_and_types()]
        return frozenset((t, self.node.count_publishers(t), self.node.count_subscribers(t))
                         for t in names)

    def _alive_or_stop(self, what: str) -> None:
        for p in self.procs:
            if not p.alive():
                raise RunStopped("ros2_lockstep", f"ros2: external process {p.name} exited "
                                 f"with code {p.proc.returncode} {what} (log: "
                                 f"{p.log_path})")

    def _wait_ready(self) -> None:
        """Until the external nodes are up and discovery matched them with the bridge: each
        ready topic and output has a publisher and the graph has not changed for
        ``_SETTLE_S`` (a node makes its publishers and subscriptions one after the other, and
        discovery announces them so: a subscription not yet known when the bridge first
        publishes its topic would miss the first message)."""
        timeout = max([p.spec.ready_timeout for p in self.procs] or [self.spec.timeout * 3])
        deadline = time.monotonic() + timeout
        ready_topics = [p.spec.ready_topic for p in self.procs if p.spec.ready_topic]
        graph, since = frozenset[tuple[str, int, int]](), time.monotonic()
        while True:
            self.executor.spin_once(timeout_sec=_READY_POLL_S)
            missing = [t for t in ready_topics if self.node.count_publishers(t) == 0]
            missing += [o.topic for o in self.outputs if o.subscription.get_publisher_count() == 0]
            now = self._graph()
            if now != graph:
                graph, since = now, time.monotonic()
            if not missing and time.monotonic() - since >= _SETTLE_S:
                break
            try:
                self._alive_or_stop("before it was ready")
            except RunStopped as err:
                raise SrrError(str(err)) from None
            if time.monotonic() > deadline:
                outputs = {o.topic: o for o in self.outputs}
                waiting = ", ".join(self._not_published(t, outputs.get(t))
                                    for t in sorted(set(missing)))
                others = [n for n in self.node.get_node_names() if n != self.node.get_name()]
                late = "" if others or not self.procs else (
                    "; no external node has joined the ROS graph yet: a node may take seconds "
                    "to start, raise ros2.external[].ready_timeout")
                raise SrrError(f"ros2: the external nodes were not ready within {timeout:g} s "
                               f"(still waiting on {waiting}{late}; domain {self.domain_id}; "
                               f"logs in {self.run_dir / 'ros2'})")
        for o in self.outputs:  # what arrived while waiting is not part of any tick
            o.received.clear()
        self._started = True

    def _publishers(self, topic: str) -> list[Any]:
        """The graph's publishers of ``topic`` (rclpy ``TopicEndpointInfo``), not the
        bridge's."""
        return [p for p in self.node.get_publishers_info_by_topic(topic)
                if p.node_name != self.node.get_name()]

    def _not_published(self, topic: str, o: _Output | None) -> str:
        """``topic`` (the output ``o``, or a ready topic), which has no publisher the bridge
        matched, and what the graph has instead: a publisher of another type or of a QoS
        the output's subscription cannot match, or a published topic of that name in another
        namespace or spelt alike."""
        from rclpy.qos import QoSCompatibility, qos_check_compatible

        published = {name: sorted({p.topic_type for p in pubs}) for name, _ in
                     self.node.get_topic_names_and_types()
                     if (pubs := self._publishers(name))}
        if o is not None and published.get(topic, [o.spec.type]) != [o.spec.type]:
            return (f"{topic} (published as {', '.join(published[topic])}, not the declared "
                    f"{o.spec.type})")
        if o is not None and topic in published:
            for p in self._publishers(topic):
                compat, why = qos_check_compatible(p.qos_profile, o.subscription.qos_profile)
                if compat == QoSCompatibility.ERROR:
                    offered = p.qos_profile
                    fix = {"reliability": offered.reliability.name.lower(),
                           "durability": offered.durability.name.lower()}
                    return (f"{topic} (its publisher's QoS does not match the bridge's "
                            f"subscription: {why.removeprefix('ERROR: ').strip('; ').lower()}; "
                            f"set ros2.qos: {{{topic}: {{reliability: {fix['reliability']}, "
                            f"durability: {fix['durability']}}}}})")
        leaf = topic.rsplit("/", 1)[-1]
        declared = {o.topic for o in self.outputs}  # another output's publisher is its own
        others = [t for t in published if t != topic and t not in declared]
        near = [t for t in others if t.rsplit("/", 1)[-1] == leaf]
        alike = near[0] if len(near) == 1 else close_match(topic, others)
        if alike is None:
            return topic
        return (f"{topic} (nothing publishes it; {alike} ({', '.join(published[alike])}) is "
                "published: misspelt or in another namespace?)")

    def _unfed(self) -> str:
        """The topics the external nodes subscribe to that nothing publishes but that are
        spelt like one the bridge publishes (a misspelt input), as a note for an error."""
        ours = [t for t, pub in self.pubs.items() if pub is not None]
        notes = []
        for name, _ in self.node.get_topic_names_and_types():
            if name in ours or self.node.count_publishers(name) or \
                    not self.node.count_subscribers(name):
                continue
            alike = close_match(name, ours)
            if alike is not None:
                notes.append(f"{name}, which nothing publishes (did you mean {alike}?)")
        return f"; the external nodes subscribe to {', '.join(notes)}" if notes else ""

    @property
    def domain_id(self) -> int:
        return self.lease.domain_id if self.lease is not None else -1

    # -- every tick -----------------------------------------------------------------------
    def attach(self, recorder: Recorder) -> None:
        """Publish the bytes the recorder serializes (at the same moment: the recorder is a
        bus tap too) instead of serializing every message a second time."""
        self._via_recorder = True
        recorder.add_serialized_tap(self._forward_bytes)

    def _forward(self, env: Envelope) -> None:
        if not self._via_recorder:
            self._forward_bytes(env, cdr_bytes(env))

    def _forward_bytes(self, env: Envelope, data: bytes) -> None:
        pub = self._publisher(env.topic, env.msgtype, self.ctx.bus.qos(env.topic))
        if pub is not None:
            pub.publish(data)

    def _received(self, o: _Output, raw: bytes) -> None:
        o.received.append(bytes(raw))
        if o.stamped:
            o.latest_stamp_ns = max(o.latest_stamp_ns, _stamp_ns(raw))

    def step(self, now_ns: int) -> None:
        due = [o for o in self.outputs if o.due(now_ns)]
        deadline = time.monotonic() + self.spec.timeout
        while any(not o.arrived(now_ns) for o in due):
            self.executor.spin_once(timeout_sec=0.01)
            if time.monotonic() > deadline:
                late = [o for o in due if not o.arrived(now_ns)]
                names = ", ".join(f"{o.topic} ({o.spec.type}{_older(o)})" for o in late)
                raise RunStopped("ros2_lockstep", (
                    f"ros2: no {names} from the external nodes within "
                    f"{self.spec.timeout:g} s of wall-clock time at t={now_ns / 1e9:g} s"
                    f"{self._unfed()}"))
            self._alive_or_stop(f"while the run waited at t={now_ns / 1e9:g} s")
        self._drain()
        for o in self.outputs:
            if o.received and o.spec.rate_hz is not None:
                o.period = _period(now_ns, o.spec.rate_hz)
            for raw in o.received:
                self.ctx.bus.publish_raw(o.topic, o.spec.type, raw, _decode,
                                         self.ctx.bus.qos(o.topic))
            o.received.clear()

    def _drain(self) -> None:
        """Take whatever else already arrived (spin until a pass handles nothing)."""
        for _ in range(1000):
            before = sum(len(o.received) for o in self.outputs)
            self.executor.spin_once(timeout_sec=0.0)
            if sum(len(o.received) for o in self.outputs) == before:
                break

    def shutdown(self) -> None:
        if not hasattr(self, "_started"):  # never set up (an error before the systems under
            return  # test were): nothing started, nothing to stop
        self._flush()
        stop_processes(self.procs, self.run_dir / "ros2")
        with contextlib.suppress(Exception):
            self.executor.shutdown()
            self.node.destroy_node()  # type: ignore[no-untyped-call]
            self._rclpy.shutdown(context=self.rcl_context)
        if self.lease is not None:
            self.lease.release()

    def _flush(self) -> None:
        """Before the external processes are stopped: wait (at most ``ros2.timeout`` in all)
        until every subscriber acknowledged every message published, so the last ticks'
        messages, sent after the last output was awaited, reach the nodes too. Not when an
        external process has exited (its subscriptions would be waited for in vain)."""
        if not self._started or any(not p.alive() for p in self.procs):
            return
        from rclpy.duration import Duration

        deadline = time.monotonic() + self.spec.timeout
        for pub in self.pubs.values():
            if pub is not None:
                left = max(0.0, deadline - time.monotonic())
                with contextlib.suppress(Exception):  # a node gone: nothing to wait for
                    pub.wait_for_all_acked(Duration(nanoseconds=int(left * 1e9)))

    @staticmethod
    def _tf2_msgs() -> list[str]:
        """Make tf2_msgs usable (built once into the cache, :mod:`harness.ros2.tf2_msgs`);
        without a compiler the TF topics are not bridged, and the warnings say why."""
        from harness.ros2.errors import Ros2SetupError
        from harness.ros2.tf2_msgs import ensure_tf2_msgs

        try:
            ensure_tf2_msgs(build=True)
        except Ros2SetupError as err:
            return [f"ros2: tf2_msgs is not available, so TF is not bridged: {err} "
                    "(then `srr ros2 setup`)"]
        return []

    def warnings(self) -> list[str]:
        return [*self.setup_notes, *(
            f"ros2: {t} ({m}) is recorded but not published on the ROS 2 graph: no rclpy "
            "type support for it here" for t, m in sorted(self.unbridged.items()))]


def _older(o: _Output) -> str:
    """For a stamped output without a rate whose latest message is older than the tick: its
    stamp, and why one stamped at the tick is due."""
    if o.spec.rate_hz is not None or o.latest_stamp_ns < 0:
        return ""
    return (f"; the latest was stamped {o.latest_stamp_ns / 1e9:g} s, and without rate_hz "
            "one stamped at or after every tick is due")


_decode: Callable[[bytes, str], Any] = deserialize
