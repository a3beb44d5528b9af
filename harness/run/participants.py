"""The run's own participants: what serves a run while it goes, beside the systems under test,
through the same lifecycle hooks (:class:`~harness.sut.participant.RunParticipant`).

* :class:`LiveViewParticipant` — the Foxglove live view (``--foxglove``,
  :mod:`harness.live.view`), started before the run directory is written (a port in use stops
  the run there);
* :class:`RtspParticipant` — the scenario's RTSP streams (``rtsp.enabled``,
  :mod:`harness.video.rtsp`), bound and waited for before the run directory is written.

The run pipeline (:mod:`harness.run.record`) calls their hooks after the systems under
test's: ``attach`` once the recorder is open, ``after_tick`` after every tick, ``warnings``
for the summary, and ``shutdown`` once the run is over, however it ends, in the reverse order
of their start. Neither has ``setup`` or ``step``: they take no part in the tick itself.
"""

from __future__ import annotations

from typing import Any

from harness.bus import Bus
from harness.live.view import LiveView
from harness.recording.recorder import Recorder
from harness.sut.participant import Participant

__all__ = ["LiveViewParticipant", "RtspParticipant"]


class LiveViewParticipant(Participant):
    """A started :class:`LiveView` in a run on ``bus``: it gets every message the recorder
    serializes and, after each tick, the simulation time; it may hold the first tick for a
    client and pace the loop."""

    def __init__(self, view: LiveView, bus: Bus) -> None:
        self.view = view
        self.bus = bus

    def attach(self, recorder: Recorder) -> None:
        recorder.add_serialized_tap(self.view.log)
        self.view.advertise({t: i.msgtype for t, i in self.bus.topics().items()}, self.bus.qos)
        self.view.wait_for_client()

    def after_tick(self, now_ns: int) -> None:
        self.view.tick()  # the time of the newest message it served, and pacing

    def shutdown(self) -> None:
        self.view.close()


class RtspParticipant(Participant):
    """The run's RTSP servers (a :class:`~harness.video.rtsp.RtspHub`, fed by the graphs'
    RTSP nodes). The simulation ends the streams as it closes; ``shutdown`` makes sure they
    are ended on every path (closing is idempotent)."""

    def __init__(self, hub: Any) -> None:
        self.hub = hub

    def shutdown(self) -> None:
        self.hub.close()
