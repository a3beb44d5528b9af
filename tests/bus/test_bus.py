"""Messages published as bytes: the object is built only when something reads it, once, and
delivery is as for a published object."""

from __future__ import annotations

from typing import Any

from harness.bus import TRANSIENT_LOCAL, Bus, Envelope
from harness.serde.messages import clock, clock_packer, serialize, split_ns

CLOCK = "rosgraph_msgs/msg/Clock"


def _publish(bus: Bus, ns: int, topic: str = "/clock") -> list[int]:
    """Publish the clock at ``ns`` as bytes; returns a list that counts the builds."""
    builds: list[int] = []

    def build() -> Any:
        builds.append(ns)
        return clock(ns)

    bus.publish_serialized(topic, CLOCK, clock_packer().pack(*split_ns(ns)), build)
    return builds


def test_nobody_reading_builds_nothing_and_taps_get_the_bytes() -> None:
    bus = Bus(lambda: 7)
    raw: list[bytes | None] = []
    bus.add_tap(lambda env: raw.append(env.raw))
    builds = _publish(bus, 1_500_000_000)
    bus.spin()
    assert builds == [] and raw == [serialize(clock(1_500_000_000), CLOCK)]
    assert bus.published_counts() == {"/clock": 1}


def test_subscribers_share_one_object_built_once() -> None:
    bus = Bus(lambda: 0)
    got: list[Any] = []
    bus.subscribe("/clock", CLOCK, got.append)
    bus.subscribe("/clock", CLOCK, got.append)
    builds = _publish(bus, 42)
    bus.spin()
    assert builds == [42] and got[0] is got[1] and got[0] == clock(42)


def test_a_subscription_made_before_the_spin_still_gets_it() -> None:
    """As for ``publish``: delivery looks at the subscribers when the bus spins."""
    bus = Bus(lambda: 0)
    builds = _publish(bus, 3)
    got: list[Any] = []
    bus.subscribe("/clock", CLOCK, got.append)
    bus.spin()
    assert got == [clock(3)] and builds == [3]


def test_a_tap_reading_msg_and_a_late_latched_subscriber() -> None:
    bus = Bus(lambda: 0)
    bus.advertise("/clock_static", CLOCK, TRANSIENT_LOCAL)
    seen: list[Envelope] = []
    bus.add_tap(seen.append)
    builds = _publish(bus, 9, "/clock_static")
    bus.spin()
    assert builds == []
    assert seen[0].msg == clock(9) and builds == [9]  # the tap read it: built now
    late: list[Any] = []
    bus.subscribe("/clock_static", CLOCK, late.append)
    bus.spin()
    assert late == [clock(9)] and late[0] is seen[0].msg and builds == [9]


def test_an_envelope_subscriber_builds_only_what_it_reads() -> None:
    """``subscribe_envelopes``: each message's envelope, in order with the topic's other
    subscribers; a message is built when read, once, shared with object subscribers."""
    bus = Bus(lambda: 0)
    order: list[tuple[str, Any]] = []
    bus.subscribe_envelopes("/clock", CLOCK, lambda env: order.append(("env", env)))
    bus.subscribe("/clock", CLOCK, lambda msg: order.append(("msg", msg)))
    first = _publish(bus, 1)
    bus.spin()
    assert [kind for kind, _ in order] == ["env", "msg"] and first == [1]
    assert order[0][1].msg is order[1][1]  # the envelope's message is the one delivered

    envs: list[Envelope] = []
    alone = Bus(lambda: 0)
    alone.subscribe_envelopes("/clock", CLOCK, envs.append)
    builds = [_publish(alone, ns) for ns in (1, 2, 3)]
    alone.spin()
    assert [env.stamp_ns for env in envs] == [0, 0, 0] and builds == [[], [], []]
    assert envs[-1].msg == clock(3) and builds == [[], [], [3]]  # only the latest, on reading


def test_a_late_envelope_subscriber_of_a_latched_topic_gets_the_envelope() -> None:
    bus = Bus(lambda: 0)
    bus.advertise("/clock_static", CLOCK, TRANSIENT_LOCAL)
    builds = _publish(bus, 9, "/clock_static")
    bus.spin()
    late: list[Envelope] = []
    bus.subscribe_envelopes("/clock_static", CLOCK, late.append)
    bus.spin()
    assert len(late) == 1 and late[0].msg == clock(9) and builds == [9]
