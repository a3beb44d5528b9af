"""A run whose bag was damaged after it finished, as a user's probe damaged one: every command
that reads the bag (``inspect``, ``diff``, ``report``, ``baseline bless``, ``replay``,
``export``) refuses it alike, in one line naming the file and what is wrong, exit 2, writing
nothing, through the one verification they share (:mod:`harness.recording.verify`)."""

from __future__ import annotations

import hashlib
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

from harness import api
from harness.cli import main
from harness.recording.errors import BagError
from harness.recording.mcapread import McapIndex
from harness.replay import Playback
from tests.conftest import SCENARIOS, ModuleTmp

pytestmark = pytest.mark.slow

FW = SCENARIOS / "forklift_warehouse.yaml"
COMMANDS = ["inspect", "diff", "report", "bless", "replay", "export"]


@pytest.fixture(scope="module")
def good(module_tmp: ModuleTmp) -> Path:
    """A finished 2 s run of the forklift warehouse: an MCAP file of two chunks."""
    out = module_tmp("damaged") / "good"
    api.run_scenario(api.load(FW, duration=2), source=str(FW), out=out)
    return out


def _flip(mcap: Path, offset: int, n: int = 4) -> None:
    with mcap.open("r+b") as f:
        f.seek(offset)
        b = f.read(n)
        f.seek(offset)
        f.write(bytes(x ^ 0xFF for x in b))


def damaged(good: Path, tmp: Path, damage: Callable[[Path], None]) -> Path:
    run = tmp / "run"
    shutil.copytree(good, run)
    damage(run / "bag" / "bag.mcap")
    return run


def _tree(run: Path) -> dict[str, str]:
    return {str(p.relative_to(run)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(run.rglob("*")) if p.is_file()}


def refusal(good: Path, run: Path, tmp: Path, command: str,
            capsys: pytest.CaptureFixture[str]) -> str:
    """What ``command`` says of the damaged ``run``: exit 2, one line, nothing written, the
    run left as it was."""
    if command == "export":
        pytest.importorskip("rerun")
    out, baselines, rrd = tmp / "out", tmp / "baselines", tmp / "x.rrd"
    argv = {"inspect": ["inspect", str(run)], "diff": ["diff", str(good), str(run)],
            "report": ["report", str(run), "--no-video"],
            "bless": ["baseline", "bless", str(run), "--reason", "r", "--baselines",
                      str(baselines)],
            "replay": ["replay", str(run), "--out", str(out), "-q"],
            "export": ["export", str(run), "--rerun", str(rrd)]}[command]
    before = _tree(run)
    code = main(argv)
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, (code, err)
    said = " ".join(argv[:2]) if argv[0] == "baseline" else argv[0]  # srr baseline bless:
    assert err.startswith(f"srr {said}: ") and "Traceback" not in err, err
    assert not out.exists() and not baselines.exists() and not rrd.exists()
    assert not list(tmp.glob(".*.partial"))
    assert _tree(run) == before
    return err


def _chunks(mcap: Path) -> list[tuple[int, int]]:
    return [(c.chunk_start_offset, c.chunk_length) for c in sorted(
        McapIndex(mcap).summary.chunk_indexes, key=lambda c: c.chunk_start_offset)]


@pytest.mark.parametrize("command", COMMANDS)
def test_a_chunk_that_fails_its_crc_is_refused_by_every_command(
        good: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str) -> None:
    # 4 bytes flipped inside the second chunk's messages: only its CRC tells
    def damage(mcap: Path) -> None:
        start, length = _chunks(mcap)[1]
        _flip(mcap, start + length // 2)

    run = damaged(good, tmp_path, damage)
    err = refusal(good, run, tmp_path, command, capsys)
    assert str(run) in err and err.endswith(": cannot read bag: Chunk checksum mismatch."), err


def _summary_middle(mcap: Path) -> int:
    data = mcap.read_bytes()
    footer = len(data) - 8 - 29
    start = int.from_bytes(data[footer + 9:footer + 17], "little")
    return (start + footer) // 2


# (a byte or four flipped where no reader looked, what every command says)
INDEX_DAMAGE: dict[str, tuple[Callable[[Path], None], str]] = {
    "summary": (lambda m: _flip(m, _summary_middle(m)),
                "cannot read bag: bag.mcap: the summary section fails its CRC check"),
    "footer": (lambda m: _flip(m, m.stat().st_size - 20),
               "cannot read bag: bag.mcap: the summary section fails its CRC check"),
    "chunk length": (lambda m: _flip(m, _chunks(m)[1][0] + 1, 1),
                     "cannot read bag: bag.mcap: chunk at byte {}: the file's record there "
                     "is not the Chunk of {} bytes its chunk index says"),
}


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("where", list(INDEX_DAMAGE))
def test_a_summary_or_chunk_index_that_disagrees_with_the_file_is_refused_by_every_command(
        good: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], where: str,
        command: str) -> None:
    damage, words = INDEX_DAMAGE[where]
    start, length = _chunks(good / "bag" / "bag.mcap")[1]
    run = damaged(good, tmp_path, damage)
    err = refusal(good, run, tmp_path, command, capsys)
    assert str(run) in err and err.endswith(words.format(start, length)), err


@pytest.mark.parametrize("where", list(INDEX_DAMAGE))
def test_recover_refuses_what_the_readers_refuse(good: Path, tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str],
                                                 where: str) -> None:
    run = damaged(good, tmp_path, INDEX_DAMAGE[where][0])
    before = _tree(run)
    code = main(["recover", str(run)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "corrupt" in err, err
    assert err.endswith("not recovered"), err
    assert _tree(run) == before


def _cut(n: int) -> Callable[[Path], None]:
    return lambda m: os.truncate(m, n)


# (a file no reader can start on, what every command says: neither names `srr recover`,
# which has nothing to rebuild from)
START_DAMAGE: dict[str, tuple[Callable[[Path], None], str]] = {
    "empty": (_cut(0), "the file is empty"),
    "cut in magic": (_cut(5), "the file is cut short inside MCAP's magic bytes (5 bytes)"),
    "cut in header": (_cut(30), "the file is cut short inside its MCAP header (30 bytes)"),
    "not mcap": (lambda m: m.write_text("hello world, this is not mcap\n" * 10),
                 "not an MCAP file (it does not start with MCAP's magic bytes)"),
}


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("case", list(START_DAMAGE))
def test_a_file_cut_in_its_header_or_not_mcap_is_named_alike_by_every_command(
        good: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str,
        command: str) -> None:
    damage, words = START_DAMAGE[case]
    run = damaged(good, tmp_path, damage)
    err = refusal(good, run, tmp_path, command, capsys)
    assert str(run) in err and err.endswith(f"cannot read bag: bag.mcap: {words}"), err
    assert "srr recover" not in err, err


@pytest.mark.parametrize("case", list(START_DAMAGE))
def test_replay_reads_its_recording_through_the_one_reader(
        good: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str) -> None:
    """Playback itself (what a summary without digests leaves to it) and recover say it
    too."""
    damage, words = START_DAMAGE[case]
    run = damaged(good, tmp_path, damage)
    with pytest.raises(BagError) as info:
        list(Playback(run / "bag").by_time())
    assert str(info.value) == f"{run / 'bag' / 'bag.mcap'}: cannot read recording: {words}"
    assert main(["recover", str(run)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.endswith(f"bag.mcap: {words}: nothing to recover"), err


@pytest.mark.parametrize("command", COMMANDS)
def test_metadata_of_the_wrong_types_is_named_by_file_and_field(
        good: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str) -> None:
    def damage(mcap: Path) -> None:
        (mcap.parent / "metadata.yaml").write_text(
            "rosbag2_bagfile_information:\n  version: nine\n  storage_identifier: 5\n"
            "  topics_with_message_count: {}\n")

    run = damaged(good, tmp_path, damage)
    err = refusal(good, run, tmp_path, command, capsys)
    assert err.endswith(f"{run / 'bag' / 'metadata.yaml'}: not a rosbag2 metadata file: "
                        "rosbag2_bagfile_information.version: 'nine' is not an integer"), err
