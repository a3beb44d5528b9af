"""Compressed chunks (``recording.compression``: zstd, lz4): the same messages, read back by the
independent reader; smaller files; a compressed bag cut short recovers to its complete chunks."""

from __future__ import annotations

from pathlib import Path

import pytest
from mcap.reader import make_reader

from harness import api
from harness.recording.bagfile import ChunkPolicy
from harness.recording.recover import recover_bag
from tests.recording.test_recover import SPAN_NS, decoded_count, raw, record

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("compression", ["zstd", "lz4"])
def test_compressed_chunks_hold_the_same_messages(tmp_path: Path, compression: str) -> None:
    plain = record(tmp_path / "plain", policy=ChunkPolicy(max_span_ns=SPAN_NS))
    packed = record(tmp_path / "packed", policy=ChunkPolicy(max_span_ns=SPAN_NS,
                                                            compression=compression))
    a, b = tmp_path / "plain" / "plain.mcap", tmp_path / "packed" / "packed.mcap"
    assert raw(b) == raw(a) and decoded_count(b) == len(raw(a))
    assert {t: s.sha256 for t, s in packed.stats().items()} == \
        {t: s.sha256 for t, s in plain.stats().items()}
    with b.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and summary.chunk_indexes
    assert {c.compression for c in summary.chunk_indexes} == {compression}
    assert b.stat().st_size < a.stat().st_size


@pytest.mark.parametrize("compression", ["zstd", "lz4"])
def test_a_compressed_bag_cut_short_keeps_its_complete_chunks(tmp_path: Path,
                                                               compression: str) -> None:
    record(tmp_path / "src", policy=ChunkPolicy(max_span_ns=SPAN_NS, compression=compression))
    src = tmp_path / "src" / "src.mcap"
    data = src.read_bytes()
    with src.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    everything = raw(src)
    for chunk in summary.chunk_indexes[1:4]:
        end = chunk.chunk_start_offset + chunk.chunk_length
        for cut in (end - 1, end):
            bag = tmp_path / f"cut{cut}"
            bag.mkdir()
            (bag / "bag.mcap").write_bytes(data[:cut])
            res = recover_bag(bag)
            complete = [c for c in summary.chunk_indexes
                        if c.chunk_start_offset + c.chunk_length <= cut]
            n = sum(1 for _, t, _ in everything if t <= complete[-1].message_end_time)
            assert res.status == "rebuilt" and res.chunks == len(complete)
            assert raw(bag / "bag.mcap") == everything[:n]


@pytest.mark.slow
def test_a_run_with_zstd_records_the_same_digests_in_a_smaller_bag(tmp_path: Path) -> None:
    scenario = ROOT / "scenarios" / "dock_worker_crossing.yaml"
    sizes, digests = {}, {}
    for c in ("none", "zstd"):
        sc = api.load(scenario, duration=3, overrides=[f"recording.compression={c}"])
        res = api.run_scenario(sc, source=str(scenario), out=tmp_path / c)
        (mcap,) = (res.run_dir / "bag").glob("*.mcap")
        sizes[c], digests[c] = mcap.stat().st_size, res.summary["digest"]
    assert digests["zstd"] == digests["none"]
    assert sizes["zstd"] < sizes["none"] / 4  # camera images and depth compress well
