"""A run directory says who owns it: while a real `srr run` writes it, every command that reads
or changes a run directory refuses it in one line (exit 2) and touches nothing; once the run is
killed with SIGKILL its lock is free and `srr recover` works.

The live run is a real process (a long --duration); the test waits for the state it needs (the
run directory printed, the marker in phase ``recording``, the bag's header on disk), never for a
guessed length of time.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from harness import api, runlock, runmarker
from harness.cli import main
from tests.conftest import ModuleTmp

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "scenarios" / "forklift_warehouse.yaml"


@pytest.fixture(scope="module")
def finished(module_tmp: ModuleTmp) -> Path:
    sc = api.load(SCENARIO, duration=1.0)
    return api.run_scenario(sc, source=str(SCENARIO),
                            out=module_tmp("done") / "r").run_dir


def start_run(out: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "harness.cli", "run", str(SCENARIO), "--duration", "3000",
         "--out", str(out), "-q"], cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)


def wait_until_recording(proc: subprocess.Popen[str], out: Path) -> None:
    """The first line names the run directory (it is owned from then on); then wait for the
    tick loop and the bag's header."""
    assert proc.stdout is not None
    assert proc.stdout.readline().strip() == f"run directory: {out}"
    deadline = time.monotonic() + 120
    while True:
        marker = runmarker.read(out)
        bag = out / "bag" / "bag.mcap"
        if marker is not None and marker["phase"] == "recording" and bag.is_file() \
                and bag.stat().st_size > 0:
            return
        assert proc.poll() is None, "the run ended before it recorded"
        assert time.monotonic() < deadline, "the run never started recording"
        time.sleep(0.01)


@pytest.fixture()
def live(tmp_path: Path) -> Iterator[tuple[Path, subprocess.Popen[str]]]:
    out = tmp_path / "live"
    proc = start_run(out)
    try:
        wait_until_recording(proc, out)
        yield out, proc
    finally:
        proc.kill()
        proc.wait()
        if proc.stdout is not None:
            proc.stdout.close()


def snapshot(run: Path) -> dict[str, bytes]:
    """Every file of the run directory but the growing bag, with its bytes."""
    return {p.relative_to(run).as_posix(): p.read_bytes() for p in sorted(run.rglob("*"))
            if p.is_file() and p.name != "bag.mcap"}


def test_a_live_run_is_refused_by_every_reader_then_recovered_once_killed(
        live: tuple[Path, subprocess.Popen[str]], finished: Path, tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    out, proc = live
    host = socket.gethostname()
    marker = runmarker.read(out)
    assert marker is not None and marker["pid"] == proc.pid and marker["host"] == host
    owner = runlock.live_owner(out)
    assert owner is not None and owner.pid == proc.pid and owner.host == host

    before = snapshot(out)
    bag = out / "bag" / "bag.mcap"
    inode, size = bag.stat().st_ino, bag.stat().st_size
    baselines = tmp_path / "baselines"
    commands = [
        ["recover", str(out)], ["recover", str(out / "bag")], ["recover", str(bag)],
        ["report", str(out)], ["inspect", str(out)], ["inspect", str(out / "bag")],
        ["replay", str(out), "--out", str(tmp_path / "replayed"), "-q"],
        ["diff", str(finished), str(out)], ["diff", str(out), str(finished)],
        ["baseline", "bless", str(out), "--reason", "r", "--baselines", str(baselines)],
        ["run", str(SCENARIO), "--out", str(out), "-q"],
    ]
    for argv in commands:
        assert main(argv) == 2, argv
        captured = capsys.readouterr()
        err = captured.err.strip()
        assert len(err.splitlines()) == 1 and "Traceback" not in err, err
        assert err == (f"srr {_said(argv)}: {out} is "
                       f"being written by pid {proc.pid} on {host}; wait until it ends or "
                       f"stop it (kill {proc.pid}), then try again"), err
        assert captured.out == ""

    assert proc.poll() is None  # it ran all along
    assert snapshot(out) == before  # nothing was written, renamed or removed
    assert bag.stat().st_ino == inode and bag.stat().st_size >= size  # the live file, growing
    assert not (tmp_path / "replayed").exists() and not baselines.exists()

    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert (out / runlock.LOCK).is_file()  # left by the dead process: free
    assert runlock.live_owner(out) is None
    assert main(["recover", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "rebuilt bag.mcap" in printed and "dropped the -" not in printed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["recovered"] and summary["verdict"] == "INVALID"
    assert summary["recovery"]["dropped_bytes"] >= 0
    assert not (out / runmarker.MARKER).exists() and not (out / runlock.LOCK).exists()
    assert main(["report", str(out)]) == 0  # a finished (recovered) run reads again


def test_a_replay_names_its_run_directory_first(finished: Path, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "replayed"
    assert main(["replay", str(finished), "--out", str(out), "-q"]) in (0, 1)  # 1 s: no PASS
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0] == f"run directory: {out}" and lines[-1] == str(out)
    assert not (out / runlock.LOCK).exists() and not (finished / runlock.LOCK).exists()


def _said(argv: list[str]) -> str:
    """The command as srr names it in an error: ``baseline bless``, ``diff``, ..."""
    return " ".join(argv[:2]) if argv[0] == "baseline" else argv[0]
