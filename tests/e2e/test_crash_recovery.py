"""SIGKILL a real `srr run` at three moments, then `srr recover`: the bag is read whole by the
independent reader and holds every complete chunk (at most the last one is lost).

A run is deterministic, so an uninterrupted reference run of the same scenario writes the
same MCAP bytes: a killed run's file must be a byte prefix of the reference file, and the
recovered bag must hold exactly the reference's messages of the chunks that were on disk.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path

import pytest
from mcap.reader import make_reader

from harness import api, runmarker
from harness.bag import inspect_bag
from harness.cli import main
from harness.recording.recorder import digest_update
from tests.conftest import ModuleTmp

from .bagread import decoded, mcap_file

ROOT = Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "scenarios" / "forklift_warehouse.yaml"
DURATION = 12.0
OVERRIDES = ["recording.chunk_s=0.25"]  # 48 chunks: fine-grained enough to see what is lost

Raw = list[tuple[str, int, bytes]]


def raw(path: Path) -> Raw:
    with path.open("rb") as f:
        return [(c.topic, m.log_time, m.data) for _, c, m in make_reader(f).iter_messages()]


@pytest.fixture(scope="module")
def reference(module_tmp: ModuleTmp) -> Path:
    sc = api.load(SCENARIO, duration=DURATION, overrides=OVERRIDES)
    res = api.run_scenario(sc, source=str(SCENARIO), out=module_tmp("ref") / "r")
    assert not (res.run_dir / runmarker.MARKER).exists()  # a finished run has no marker
    return res.run_dir


def run_and_kill(out: Path, moment: Callable[[Path], bool]) -> None:
    """Start `srr run` in a process, SIGKILL it as soon as ``moment(out)`` holds."""
    cmd = [sys.executable, "-m", "harness.cli", "run", str(SCENARIO), "--duration",
           str(DURATION), *(a for o in OVERRIDES for a in ("--set", o)), "--out", str(out),
           "-q"]
    proc = subprocess.Popen(cmd, cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    try:
        while not moment(out):
            assert proc.poll() is None, "the run ended before the moment to kill it came"
            assert time.monotonic() < deadline, "the moment to kill the run never came"
            time.sleep(0.001)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == -signal.SIGKILL


def bag_size(out: Path) -> int:
    try:
        return (out / "bag" / "bag.mcap").stat().st_size
    except FileNotFoundError:
        return 0


def phase(out: Path) -> str | None:
    marker = runmarker.read(out) if out.is_dir() else None
    return None if marker is None else str(marker["phase"])


def early(out: Path) -> bool:
    return bag_size(out) > 0  # the file exists and holds its header (flushed on open)


def mid_run(ref_size: int) -> Callable[[Path], bool]:
    return lambda out: phase(out) == "recording" and bag_size(out) >= 0.4 * ref_size


def finalizing(out: Path) -> bool:
    return phase(out) == "finalizing"  # the tick loop is over; closing, scoring, summary


@pytest.mark.parametrize("moment", ["early", "mid-run", "finalizing"])
@pytest.mark.slow
def test_kill_then_recover(reference: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
                           moment: str) -> None:
    ref_file = mcap_file(reference)
    ref_bytes = ref_file.read_bytes()
    ref_msgs = raw(ref_file)
    with ref_file.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    chunks = summary.chunk_indexes
    assert len(chunks) == 48

    out = tmp_path / "run"
    run_and_kill(out, {"early": early, "mid-run": mid_run(len(ref_bytes)),
                       "finalizing": finalizing}[moment])
    killed_phase = phase(out)
    assert killed_phase == ("finalizing" if moment == "finalizing" else "recording")
    assert not (out / "summary.json").exists()  # a killed run does not look finished
    on_disk = (out / "bag" / "bag.mcap").read_bytes()
    assert ref_bytes.startswith(on_disk)  # what was written is the reference's prefix
    complete = [c for c in chunks if c.chunk_start_offset + c.chunk_length <= len(on_disk)]
    if moment == "mid-run":
        assert 0.35 * len(chunks) <= len(complete) < len(chunks)
    if not complete:  # killed before its first chunk was written: nothing was recorded
        assert moment == "early"
        assert main(["recover", str(out)]) == 2
        assert "nothing was recorded" in capsys.readouterr().err
        assert (out / "bag" / "bag.mcap").read_bytes() == on_disk
        assert not (out / "summary.json").exists() and runmarker.read(out) is not None
        return

    assert main(["recover", str(out)]) == 0
    printed = capsys.readouterr().out

    bag = out / "bag"
    got = raw(mcap_file(out))
    n = sum(1 for _, t, _ in ref_msgs if complete and t <= complete[-1].message_end_time)
    assert got == ref_msgs[: len(got)]  # the reference's messages, in order
    assert len(got) >= n  # every complete chunk was kept
    assert sum(1 for _ in decoded(out)) == len(got)  # the independent reader reads it whole
    assert inspect_bag(out).message_count == len(got)  # and so does rosbags
    counts = Counter(t for t, _, _ in got)
    if moment == "finalizing":
        # Everything was published: at most the last chunk may be missing.
        last = chunks[-1]
        in_last = Counter(t for t, ts, _ in ref_msgs if ts >= last.message_start_time)
        for topic, total in Counter(t for t, _, _ in ref_msgs).items():
            assert counts[topic] >= total - in_last[topic], topic
    if len(on_disk) < len(ref_bytes):
        assert (bag / "bag.mcap.damaged").read_bytes() == on_disk
        assert "rebuilt bag.mcap" in printed and "bag.mcap.damaged" in printed
    else:  # killed after the bag was closed: the file is left as it was
        assert mcap_file(out).read_bytes() == ref_bytes
        assert not (bag / "bag.mcap.damaged").exists()
    for topic, count in counts.items():
        assert f"{topic} " in printed and f" {count} " in printed

    s = json.loads((out / "summary.json").read_text())
    assert not (out / runmarker.MARKER).exists()
    if s.get("recovered"):
        assert s["verdict"] == "INVALID" and s["exit_code"] == 3
        assert s["recovery"]["phase"] == killed_phase
        assert "recovered with srr recover" in s["reasons"][0]
        assert {t: v["count"] for t, v in s["topics"].items()} == dict(counts)
        for topic, v in s["topics"].items():  # the digest of exactly what was kept
            h = hashlib.sha256()
            for t, stamp, payload in got:
                if t == topic:
                    digest_update(h, stamp, payload)
            assert v["sha256"] == h.hexdigest()
        assert "<failure" in (out / "junit.xml").read_text()
    else:  # killed in the instant between the summary and the marker's removal
        assert moment == "finalizing" and s["verdict"] == "PASS"

    assert main(["recover", str(out / "bag")]) == 0  # a second recover has nothing to do
    assert "nothing to recover" in capsys.readouterr().out
    if moment == "mid-run":  # the recovered run renders its report, INVALID
        assert main(["report", str(out)]) == 0
        assert "INVALID" in (out / "report.html").read_text()


@pytest.mark.slow
def test_chunk_settings_of_the_scenario_reach_the_recorder(tmp_path: Path) -> None:
    sc = api.load(SCENARIO, duration=2.0,
                  overrides=["recording.chunk_mb=0.02", "recording.chunk_s=60"])
    res = api.run_scenario(sc, source=str(SCENARIO), out=tmp_path / "r")
    with mcap_file(res.run_dir).open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    sizes = [c.uncompressed_size for c in summary.chunk_indexes]
    assert len(sizes) >= 6 and max(sizes) < 20_000 + 1_000  # ~140 kB in chunks of 20 kB


def test_inspect_on_a_killed_bag_points_to_recover(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "bag.mcap").write_bytes(b"\x89MCAP0\r\n")
    assert main(["inspect", str(bag)]) == 2
    assert "srr recover" in capsys.readouterr().err


def test_commands_on_a_killed_run_directory_point_to_recover(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A killed run's directory (its marker, a cut bag, no summary): every command that reads
    it says so and names ``srr recover``, rather than "not a run directory"."""
    run = tmp_path / "run"
    (run / "bag").mkdir(parents=True)
    (run / "bag" / "bag.mcap").write_bytes(b"\x89MCAP0\r\n")
    runmarker.mark(run, "recording", command="srr run x.yaml")
    for argv in (["inspect", str(run)], ["report", str(run)], ["diff", str(run), str(run)],
                 ["replay", str(run)], ["baseline", "bless", str(run), "--reason", "x"]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert "srr recover" in err and err.count("\n") == 1, (argv, err)
        assert "killed while recording" in err or "did not finish" in err, (argv, err)
    (run / runmarker.MARKER).write_text('{"phase": "reco')  # a marker that does not read
    assert main(["report", str(run)]) == 2
    assert "(killed while running)" in capsys.readouterr().err  # not "while unknown"
    runmarker.clear(run)  # no marker: nothing says the run was killed
    assert main(["report", str(run)]) == 2
    assert "not a finished run directory" in capsys.readouterr().err


def test_commands_given_a_finished_run_s_bag_name_its_run_directory(
        finished_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    run = _copy(finished_run, tmp_path)
    for argv in (["report", str(run / "bag")], ["export", str(run / "bag"), "--rerun",
                                                 str(tmp_path / "x.rrd")]):
        assert main(argv) == 2, argv
        assert capsys.readouterr().err.endswith(
            f"{run / 'bag' / 'summary.json'}: missing: {run / 'bag'} is the bag of the run "
            f"directory {run}: give that\n"), argv


def _run_interrupted_in(monkeypatch: pytest.MonkeyPatch, module: object, name: str,
                        out: Path) -> Path:
    """``srr run`` (1 s) into ``out`` with a Ctrl-C raised by ``module.name``: exit 130."""

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(module, name, interrupted)
    assert main(["run", str(SCENARIO), "--duration", "1", "-q", "--out", str(out)]) == 130
    return out


def test_a_ctrl_c_while_finalizing_keeps_the_recording_for_recover(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """A second Ctrl-C after the bag is closed (here: while the run is scored) never costs the
    recording: the directory stays as a killed run's, phase ``finalizing``, and ``srr
    recover`` makes it a finished run directory with every message."""
    from harness.run import record

    out = _run_interrupted_in(monkeypatch, record, "_score", tmp_path / "run")
    assert capsys.readouterr().err.strip().endswith(
        f"srr run: interrupted; the recording is in {out}; `srr recover {out}` makes it a "
        "finished run directory")
    assert runmarker.read(out)["phase"] == "finalizing"  # type: ignore[index]
    assert inspect_bag(out / "bag").message_count > 0  # the bag was closed whole
    monkeypatch.undo()
    assert main(["recover", str(out)]) == 0
    assert json.loads((out / "summary.json").read_text())["recovered"]


def test_a_ctrl_c_while_the_report_renders_leaves_a_complete_run(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """Ctrl-C after ``summary.json``, while the report renders: the run is complete (no
    marker, its summary), no half-written report, and the message says how to render it."""
    from harness.report import html

    out = _run_interrupted_in(monkeypatch, html, "write_report", tmp_path / "run")
    assert capsys.readouterr().err.strip().endswith(
        f"srr run: interrupted; the run is complete in {out} but has no report; "
        f"`srr report {out}` renders it")
    assert runmarker.read(out) is None and not (out / "report.html").exists()
    assert json.loads((out / "summary.json").read_text())["verdict"] != "INTERRUPTED"
    monkeypatch.undo()
    assert main(["report", str(out)]) == 0 and (out / "report.html").is_file()


@pytest.fixture(scope="module")
def finished_run(module_tmp: ModuleTmp) -> Path:
    """A finished 2 s run (two chunks) with its summary and report."""
    sc = api.load(SCENARIO, duration=2.0)
    return api.run_scenario(sc, source=str(SCENARIO),
                            out=module_tmp("finished") / "r").run_dir


def _copy(run: Path, tmp_path: Path) -> Path:
    out = tmp_path / "run"
    shutil.copytree(run, out)
    return out


@pytest.mark.parametrize("damage", ["missing", "unreadable", "wrong types", "one wrong type"])
def test_recover_on_a_finished_run_with_a_damaged_metadata_yaml_keeps_its_summary(
        finished_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        damage: str) -> None:
    """Only ``metadata.yaml`` is rewritten: the MCAP file is whole and holds what the
    summary counts, so the verdict and metrics stay (they became INVALID "killed")."""
    run = _copy(finished_run, tmp_path)
    meta = run / "bag" / "metadata.yaml"
    good_meta = meta.read_text()
    if damage == "missing":
        meta.unlink()
    elif damage == "unreadable":
        meta.write_text("rosbag2_bagfile_information: [\n")
    elif damage == "one wrong type":  # the counts agree; every reader refuses the version
        meta.write_text(good_meta.replace("version: 9", "version: nine", 1))
        assert meta.read_text() != good_meta
    else:
        meta.write_text("rosbag2_bagfile_information:\n  version: nine\n  storage_identifier: 5\n"
                        "  topics_with_message_count: {}\n")
    before = {p.name: p.read_bytes() for p in run.iterdir() if p.is_file()}
    assert main(["recover", str(run)]) == 0
    out = capsys.readouterr().out
    assert "rewrote metadata.yaml" in out
    assert out.strip().endswith(f"{run}: the run had finished; its summary is kept")
    assert meta.read_text() == good_meta
    assert {p.name: p.read_bytes() for p in run.iterdir() if p.is_file()} == before
    assert sorted(p.name for p in (run / "bag").iterdir()) == ["bag.mcap", "metadata.yaml"]


def test_recover_on_a_finished_run_whose_bag_was_cut_keeps_the_replaced_summary(
        finished_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The bag lost messages: the summary (its scores) no longer holds for it and is
    replaced by a recovered one, but kept beside it, and the report that showed it is set
    aside too (the page never contradicts the summary)."""
    run = _copy(finished_run, tmp_path)
    mcap = run / "bag" / "bag.mcap"
    old_summary = (run / "summary.json").read_bytes()
    old_report = (run / "report.html").read_bytes()
    os.truncate(mcap, mcap.stat().st_size * 2 // 3)
    assert main(["recover", str(run)]) == 0
    out = capsys.readouterr().out
    assert (f"{run / 'summary.json'}: recovered, verdict INVALID (its bag was damaged after "
            "the run finished; not scored)") in out
    assert "the summary.json it replaces is kept as summary.json.replaced" in out
    assert "the report.html it replaces is kept as report.html.replaced" in out
    assert f"`srr report {run}` renders the recovered run's report" in out
    assert (run / "summary.json.replaced").read_bytes() == old_summary
    assert (run / "report.html.replaced").read_bytes() == old_report
    assert not (run / "report.html").exists()
    s = json.loads((run / "summary.json").read_text())
    assert s["recovered"] and s["verdict"] == "INVALID"
    detail = s["health"][0]["detail"]
    assert detail.startswith("the run had finished, but its bag was cut short or damaged")
    assert "killed" not in detail and "summary.json.replaced" in detail
    assert main(["report", str(run)]) == 0
    assert "INVALID" in (run / "report.html").read_text()
    capsys.readouterr()
    assert main(["recover", str(run)]) == 0  # the recovered summary holds for its bag
    assert "nothing to recover" in capsys.readouterr().out
    assert json.loads((run / "summary.json").read_text()) == s


def test_recover_never_overwrites_a_replaced_summary(
        finished_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    run = _copy(finished_run, tmp_path)
    (run / "summary.json.replaced").write_text("an earlier one")
    old_summary = (run / "summary.json").read_bytes()
    mcap = run / "bag" / "bag.mcap"
    os.truncate(mcap, mcap.stat().st_size * 2 // 3)
    assert main(["recover", str(run)]) == 0
    assert "kept as summary.json.replaced.2" in capsys.readouterr().out
    assert (run / "summary.json.replaced").read_text() == "an earlier one"
    assert (run / "summary.json.replaced.2").read_bytes() == old_summary


def test_recover_on_a_finished_run_whose_bag_lost_only_its_footer_keeps_its_summary(
        finished_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Cut inside its footer, the file is rebuilt with every chunk: every message the summary
    counts is still there (same digests), so its verdict and scores stand."""
    run = _copy(finished_run, tmp_path)
    mcap = run / "bag" / "bag.mcap"
    old_summary = (run / "summary.json").read_bytes()
    os.truncate(mcap, mcap.stat().st_size - 10)
    assert main(["recover", str(run)]) == 0
    out = capsys.readouterr().out
    assert "rebuilt bag.mcap from 2 complete chunks" in out
    assert out.strip().endswith(f"{run}: the run had finished and its bag holds every message "
                                "its summary counts; its summary is kept")
    assert (run / "summary.json").read_bytes() == old_summary
    assert not (run / "summary.json.replaced").exists() and (run / "report.html").is_file()


def test_recover_refuses_a_whole_bag_that_is_not_what_the_summary_counts(
        finished_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    run = _copy(finished_run, tmp_path)
    (run / "bag" / "metadata.yaml").unlink()
    s = json.loads((run / "summary.json").read_text())
    s["topics"]["/odom"]["count"] += 1
    (run / "summary.json").write_text(json.dumps(s))
    before = {p.name: p.read_bytes() for p in run.rglob("*") if p.is_file()}
    assert main(["recover", str(run)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "/odom: does not match summary.json" in err, err
    assert {p.name: p.read_bytes() for p in run.rglob("*") if p.is_file()} == before


def test_recover_refuses_a_run_killed_before_its_first_chunk(
        finished_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Killed before its first chunk was written, the bag holds the MCAP header only: nothing
    was recorded, and recover says so (it wrote an empty bag and a summary, exit 0)."""
    run = _copy(finished_run, tmp_path)
    for name in ("summary.json", "junit.xml", "report.html", "bag/metadata.yaml"):
        (run / name).unlink()
    mcap = run / "bag" / "bag.mcap"
    with mcap.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    os.truncate(mcap, summary.chunk_indexes[0].chunk_start_offset)
    runmarker.mark(run, "recording", command="srr run x.yaml")
    before = {p: p.read_bytes() for p in run.rglob("*") if p.is_file()}
    assert main(["recover", str(run)]) == 2
    err = capsys.readouterr().err
    assert err == (f"srr recover: {run}: nothing was recorded: the run was killed before its "
                   f"first chunk was written (bag.mcap: {mcap.stat().st_size} bytes, no "
                   "complete chunk); nothing to recover, the run directory can be deleted\n")
    assert {p: p.read_bytes() for p in run.rglob("*") if p.is_file()} == before


def test_recover_with_an_unreadable_marker_says_the_run_was_killed_while_running(
        finished_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A killed run whose ``incomplete.json`` does not read (its phase unknown): recovered,
    and the line says so in words ("killed while unknown" it said)."""
    run = _copy(finished_run, tmp_path)
    for name in ("summary.json", "report.html", "junit.xml"):
        (run / name).unlink()
    mcap = run / "bag" / "bag.mcap"
    os.truncate(mcap, mcap.stat().st_size * 2 // 3)
    (run / runmarker.MARKER).write_text('{"phase": "reco')
    assert main(["recover", str(run)]) == 0
    out = capsys.readouterr().out
    assert (f"{run / 'summary.json'}: recovered, verdict INVALID (killed while running; not "
            "scored)") in out, out
    assert not (run / runmarker.MARKER).exists()


def test_recover_on_a_killed_run_without_its_scenario_yaml_says_the_run_stays_unfinished(
        finished_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Its bag is rebuilt, but no summary can be written without the scenario: exit 2 with
    one line that says so (it exited 0 and left the run unfinished without a word)."""
    run = _copy(finished_run, tmp_path)
    for name in ("summary.json", "report.html", "junit.xml", "scenario.yaml"):
        (run / name).unlink()
    mcap = run / "bag" / "bag.mcap"
    os.truncate(mcap, mcap.stat().st_size * 2 // 3)
    runmarker.mark(run, "recording")
    assert main(["recover", str(run)]) == 2
    err = capsys.readouterr().err
    assert err == (f"srr recover: {run}: the bag is rebuilt from its complete chunks ({mcap}), "
                   "but the run directory has no scenario.yaml, so its summary cannot be "
                   f"written: the run stays unfinished ({runmarker.MARKER} kept); put the "
                   "run's scenario.yaml back and run srr recover again\n")
    assert (run / runmarker.MARKER).is_file() and not (run / "summary.json").exists()
