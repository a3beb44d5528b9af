"""A baseline keeps a small reference recording of its run: the non-image topics, readable by
an independent MCAP reader and by srr's own frames loader, well under 1 MB."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from harness import api
from harness.frames import load_frames
from tests.conftest import SCENARIOS

BASELINES = SCENARIOS.parent / "baselines"


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(p.stem for p in BASELINES.glob("*.json")))
def test_shipped_baselines_carry_a_small_reference_recording(name: str) -> None:
    data = json.loads((BASELINES / f"{name}.json").read_text())
    ref = BASELINES / data["reference"]["file"]
    assert ref == BASELINES / f"{name}.mcap" and ref.stat().st_size == data["reference"]["bytes"]
    assert ref.stat().st_size < 1_000_000
    counts: dict[str, int] = {}
    with ref.open("rb") as f:  # the independent reader decodes every message
        for schema, channel, _message, msg in make_reader(
                f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            assert schema is not None and msg is not None
            assert "Image" not in schema.name and "PointCloud" not in schema.name
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    assert counts == data["reference"]["topics"]
    # same counts as the blessed run recorded for those topics
    assert all(data["topics"][t]["count"] == n for t, n in counts.items())
    assert any(t.startswith("/gt/") for t in counts) and "/clock" in counts


@pytest.mark.slow
def test_blessing_writes_the_reference_and_frames_read_it_like_the_run(tmp_path: Path) -> None:
    fw = SCENARIOS / "forklift_warehouse.yaml"
    res = api.run_scenario(api.load(fw, duration=3.0), source=str(fw), out=tmp_path / "r")
    path = api.bless(res.run_dir, "reference test", baselines=tmp_path / "b",
                     allow_failing=True)  # its route's goal not reached in three seconds
    ref = path.with_suffix(".mcap")
    assert ref.is_file()
    run, base = load_frames(res.run_dir), load_frames(ref)
    for table in ("gt_poses", "odom", "cmd_vel"):
        a, b = getattr(run, table), getattr(base, table)
        assert len(a) == len(b) > 0
        np.testing.assert_array_equal(a[["x", "y"]].to_numpy() if "x" in a else
                                      a[["vx", "wz"]].to_numpy(),
                                      b[["x", "y"]].to_numpy() if "x" in b else
                                      b[["vx", "wz"]].to_numpy())
    assert (run.start_ns, run.end_ns) == (base.start_ns, base.end_ns)
    again = api.run_scenario(api.load(fw, duration=3.0), source=str(fw), out=tmp_path / "r2",
                             baselines=tmp_path / "b")
    assert again.summary["baseline"]["reference"] == str(ref)
