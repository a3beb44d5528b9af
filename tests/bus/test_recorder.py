"""The recorder: order-preserving background writes, and write failures as one clear error."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.bus import Bus, Recorder
from harness.bus.messages import clock
from harness.cli import main

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "forklift_warehouse.yaml"


def test_counts_and_digests_follow_publication_order(tmp_path: Path) -> None:
    now = [0]
    bus = Bus(lambda: now[0])
    rec = Recorder(tmp_path / "bag", queue_size=2)  # a tiny queue: the producer must block
    rec.open(bus.qos)
    bus.add_tap(rec)
    for i in range(50):
        now[0] = i * 1000
        bus.publish("/clock", "rosgraph_msgs/msg/Clock", clock(now[0]))
    stats = rec.close()
    assert stats["/clock"].count == 50 and stats["/clock"].first_ns == 0
    assert stats["/clock"].last_ns == 49_000

    again = Recorder(tmp_path / "bag2")
    bus2 = Bus(lambda: now[0])
    again.open(bus2.qos)
    bus2.add_tap(again)
    for i in range(50):
        now[0] = i * 1000
        bus2.publish("/clock", "rosgraph_msgs/msg/Clock", clock(now[0]))
    assert again.close()["/clock"].sha256 == stats["/clock"].sha256


def test_a_failing_disk_is_one_line_and_leaves_no_run(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str],
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    from harness.bus.mcap_writer import McapWriter

    calls = {"n": 0}
    real = McapWriter.flush  # where a closed chunk goes to the file

    def failing(self: McapWriter) -> None:
        calls["n"] += 1
        if calls["n"] > 1:
            raise OSError(28, "No space left on device")
        real(self)

    monkeypatch.setattr(McapWriter, "flush", failing)
    out = tmp_path / "r"
    code = main(["run", str(SCENARIO), "--duration", "3", "--out", str(out), "-q"])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert "No space left on device" in err and "cannot record" in err
    assert not out.exists()  # nothing half-written is left looking valid

