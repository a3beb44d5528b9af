"""Read errors of a recording, translated in one place (:mod:`harness.recording.bagread`): what a
reader raises on a damaged file is one ``BagReadError`` line naming the file (exit 2); a
programming error in the reading path is not a damaged file and keeps its traceback. The
libraries' broader exceptions on bad bytes (lz4's ``RuntimeError``, rosbags' ROS 1 reader's
``AssertionError``) are translated, and only where those libraries raise them."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import lz4.frame
import mcap.reader
import pytest
import rosbags.rosbag2
import yaml
from mcap.writer import CompressionType, Writer
from rosbags.rosbag1 import Writer as Rosbag1Writer
from rosbags.typesys import Stores, get_typestore

from harness.bag import inspect_bag
from harness.cli import main
from harness.diff.topics import message_stream
from harness.frames import load_frames
from harness.recording import mcapread
from harness.recording.bagread import mcap_records, open_recording
from harness.recording.errors import BagError, BagReadError
from harness.recording.mcapread import McapIndex
from harness.recording.recover import recover_bag
from harness.regression.reference import write_reference
from harness.replay import Playback
from tests.conftest import ModuleTmp
from tests.metrics.synthbag import SynthSpec, write_synthetic_bag


@pytest.fixture(scope="module")
def bag(module_tmp: ModuleTmp) -> Path:
    """A rosbag2 directory of one finished MCAP file (1 s of a forklift and workers)."""
    path = module_tmp("bagread") / "bag"
    write_synthetic_bag(path, SynthSpec(duration_s=1.0))
    return path


class Bug(TypeError):
    """A programming error planted in the reading path."""


def bug(*_args: Any, **_kwargs: Any) -> Any:
    raise Bug("a bug, not a damaged file")


def _drain_stream(b: Path) -> None:
    _types, stream = message_stream(b)
    for _ in stream:
        pass


def _replay(b: Path) -> None:
    for _ in Playback(b).by_time():
        pass


# (what reads, the library or srr function that the bug is planted in, the reader)
READERS: list[tuple[str, Any, str, Callable[[Path], object]]] = [
    ("scoring and the report (MCAP index)", mcapread.McapIndex, "_chunked", load_frames),
    ("inspect (rosbags)", rosbags.rosbag2.Reader, "messages", inspect_bag),
    ("diff (rosbags)", rosbags.rosbag2.Reader, "messages", _drain_stream),
    ("replay (MCAP index)", mcapread.McapIndex, "_chunked", _replay),
    ("bless's reference recording (mcap)", mcap.reader.SeekingReader, "iter_messages",
     lambda b: write_reference(b, b.parent / "ref.mcap")),
]


@pytest.mark.parametrize(("what", "owner", "name", "read"), READERS,
                         ids=[r[0] for r in READERS])
def test_a_bug_in_the_reading_path_is_not_reported_as_a_damaged_file(
        bag: Path, monkeypatch: pytest.MonkeyPatch, what: str, owner: Any, name: str,
        read: Callable[[Path], object]) -> None:
    read(bag)  # reads whole
    monkeypatch.setattr(owner, name, bug)
    with pytest.raises(Bug):
        read(bag)
    assert not (bag.parent / "ref.mcap.tmp").exists()


def test_the_cli_shows_a_bug_in_the_reading_path_with_its_traceback(
        bag: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(rosbags.rosbag2.Reader, "messages", bug)
    with pytest.raises(Bug):  # not exit 2 with "cannot read bag"
        main(["inspect", str(bag)])


def _chunked_mcap(path: Path, compression: CompressionType) -> None:
    with path.open("wb") as f:
        w = Writer(f, chunk_size=1024, compression=compression)
        w.start(profile="ros2")
        sid = w.register_schema("std_msgs/msg/String", "ros2msg", b"string data")
        cid = w.register_channel("/chatter", "cdr", sid)
        for i in range(200):
            w.add_message(cid, i * 1_000_000, b"\x00\x01\x00\x00" + bytes(40), i * 1_000_000,
                          i)
        w.finish()  # type: ignore[no-untyped-call]  # mcap leaves it unannotated


def _spoil_first_chunk(path: Path) -> None:
    """The first byte of the first chunk's compressed records: its frame's magic number."""
    ci = min(McapIndex(path).summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
    data = bytearray(path.read_bytes())
    data[mcapread._records_start(ci)] ^= 0xFF
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("compression", [CompressionType.LZ4, CompressionType.ZSTD],
                         ids=["lz4", "zstd"])
def test_a_chunk_that_does_not_decompress_is_a_damaged_file(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        compression: CompressionType) -> None:
    bag_dir = tmp_path / "bag"
    bag_dir.mkdir()
    file = bag_dir / "bag.mcap"
    _chunked_mcap(file, compression)
    _spoil_first_chunk(file)
    with (pytest.raises(BagReadError, match=rf"^{file}: cannot read bag: ") as err,
          open_recording(file) as rec):
        list(rec.messages())
    assert err.value.file == str(file)
    with pytest.raises(BagReadError, match=rf"^{file}: cannot read bag: "):
        list(mcap_records(file))
    damaged = file.read_bytes()
    # recover reads chunk by chunk with mcap's stream reader: a damaged finished file is
    # refused in one line (lz4's RuntimeError and zstd's error were tracebacks)
    with pytest.raises(BagError, match="not recovered"):
        recover_bag(bag_dir)
    assert main(["recover", str(bag_dir)]) == 2
    out = capsys.readouterr().err.strip()
    assert len(out.splitlines()) == 1 and out.startswith("srr recover: "), out
    assert file.read_bytes() == damaged


def test_only_lz4s_own_failure_is_translated(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    file = tmp_path / "f.mcap"
    _chunked_mcap(file, CompressionType.LZ4)

    def broken(_data: bytes) -> bytes:
        raise RuntimeError("a bug in srr, not lz4's report of a bad frame")

    monkeypatch.setattr(lz4.frame, "decompress", broken)
    with pytest.raises(RuntimeError, match="a bug in srr"), open_recording(file) as rec:
        list(rec.messages())


def _ros1_bag(path: Path) -> None:
    store = get_typestore(Stores.ROS1_NOETIC)
    string = store.types["std_msgs/msg/String"]
    with Rosbag1Writer(path) as w:
        conn = w.add_connection("/chatter", "std_msgs/msg/String", typestore=store)
        for i in range(5):
            w.write(conn, 1_000 + i, bytes(store.serialize_ros1(string(data=f"hi {i}"),
                                                                "std_msgs/msg/String")))


def test_a_ros1_bag_whose_record_time_disagrees_with_its_index(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """rosbags' ROS 1 reader asserts that a message record's time is its index entry's: on
    such a damaged bag its AssertionError is a damaged file, one line."""
    bag_dir = tmp_path / "bag"
    bag_dir.mkdir()
    file = bag_dir / "bag.bag"
    _ros1_bag(file)
    data = bytearray(file.read_bytes())
    at = data.index(b"\x0d\x00\x00\x00time=")  # the first message record's time field
    data[at + 9] ^= 0x01
    file.write_bytes(bytes(data))
    with (pytest.raises(BagReadError, match="a message record's time is not its index") as err,
          open_recording(file) as rec):
        list(rec.messages())
    assert isinstance(err.value.__cause__, ValueError)
    assert isinstance(err.value.__cause__.__cause__, AssertionError)
    assert main(["inspect", str(file)]) == 2
    out = capsys.readouterr().err.strip()
    assert out == (f"srr inspect: {file}: cannot read bag: a message record's time is not "
                   "its index entry's"), out


@pytest.mark.parametrize("profiles", [
    [[1]],  # a list where a mapping belongs
    [{"durability": "volatile", "reliability": "reliable", "depth": None}],
    [{"reliability": "reliable"}],
    {"durability": "volatile"},
    7,
], ids=["list-of-lists", "depth-null", "no-durability", "mapping", "number"])
def test_replay_refuses_malformed_qos_in_metadata_in_one_line(
        bag: Path, tmp_path: Path, profiles: object) -> None:
    copy = tmp_path / "bag"
    shutil.copytree(bag, copy)
    meta_file = copy / "metadata.yaml"
    meta = yaml.safe_load(meta_file.read_text())
    info = meta["rosbag2_bagfile_information"]
    info["topics_with_message_count"][0]["topic_metadata"]["offered_qos_profiles"] = profiles
    meta_file.write_text(yaml.safe_dump(meta))
    with pytest.raises(BagError, match=rf"^{meta_file}: not a rosbag2 metadata file: "):
        Playback(copy)


@pytest.mark.parametrize("edit", [
    lambda info: info.update(topics_with_message_count=5),
    lambda info: info.update(relative_file_paths="bag.mcap"),
    lambda info: info["topics_with_message_count"].append("a topic"),
    lambda info: info["topics_with_message_count"][0].pop("topic_metadata"),
], ids=["count-not-a-list", "files-not-a-list", "entry-not-a-mapping", "no-topic-metadata"])
def test_replay_refuses_a_malformed_metadata_structure_in_one_line(
        bag: Path, tmp_path: Path, edit: Callable[[dict[str, Any]], None]) -> None:
    copy, meta_file = _with_metadata_edited(bag, tmp_path, edit)
    with pytest.raises(BagError, match=rf"^{meta_file}: not a rosbag2 metadata file: "):
        Playback(copy)


@pytest.mark.parametrize(("edit", "said"), [
    (lambda info: info.update(version="nine"), "version: 'nine' is not an integer"),
    (lambda info: info.update(storage_identifier=5), "storage_identifier: 5 is not a string"),
    (lambda info: info.pop("message_count"), "message_count: missing"),
    (lambda info: info["duration"].update(nanoseconds="long"),
     "duration.nanoseconds: 'long' is not an integer"),
    (lambda info: info["topics_with_message_count"][1].update(message_count=True),
     "topics_with_message_count[1].message_count: True is not an integer"),
    (lambda info: info["topics_with_message_count"][0]["topic_metadata"].update(type=[1]),
     "topics_with_message_count[0].topic_metadata.type: [1] is not a string"),
    (lambda info: info.update(relative_file_paths=[7]), "relative_file_paths[0]: 7 is not a "
     "string"),
], ids=["version", "storage", "no-count", "duration", "topic-count", "topic-type", "path"])
def test_metadata_of_the_wrong_types_names_the_file_and_field(
        bag: Path, tmp_path: Path, edit: Callable[[dict[str, Any]], None], said: str) -> None:
    """Every reader of a rosbag2 directory (rosbags' for inspect, diff and the read-back,
    replay's) says which field of which file, not rosbags' ``Invalid bag metadata: '>' not
    supported between instances of 'str' and 'int'``."""
    copy, meta_file = _with_metadata_edited(bag, tmp_path, edit)
    want = (f"{meta_file}: not a rosbag2 metadata file: rosbag2_bagfile_information.{said}")
    for read in (open_recording, inspect_bag, Playback):
        with pytest.raises(BagReadError) as info:
            read(copy)
        assert str(info.value) == want


def _with_metadata_edited(bag: Path, tmp_path: Path,
                          edit: Callable[[dict[str, Any]], None]) -> tuple[Path, Path]:
    """A copy of ``bag`` whose ``metadata.yaml`` ``edit`` changed: (the copy, its file)."""
    copy = tmp_path / "bag"
    shutil.copytree(bag, copy)
    meta_file = copy / "metadata.yaml"
    meta = yaml.safe_load(meta_file.read_text())
    edit(meta["rosbag2_bagfile_information"])
    meta_file.write_text(yaml.safe_dump(meta))
    return copy, meta_file
