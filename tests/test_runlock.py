"""The ownership lock of a run directory, held by a real second process: refused while it lives,
free once it is killed (SIGKILL), and never left held or lying around by one that ends well."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from harness import runlock
from harness.errors import RunInUseError

ROOT = Path(__file__).resolve().parents[1]
HOLDER = """
import sys
from pathlib import Path
from harness import runlock
with runlock.owning(Path(sys.argv[1]), "written", fresh=True):
    print("held", flush=True)
    sys.stdin.read()  # until the test closes it (or kills this process)
"""


@pytest.fixture()
def holder(tmp_path: Path) -> Iterator[tuple[Path, subprocess.Popen[str]]]:
    run = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-c", HOLDER, str(run)], cwd=ROOT,
                            env={**os.environ, "PYTHONPATH": str(ROOT)}, text=True,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    assert proc.stdout is not None and proc.stdout.readline() == "held\n"
    try:
        yield run, proc
    finally:
        proc.kill()
        proc.wait()
        for f in (proc.stdin, proc.stdout):
            if f is not None:
                f.close()


def test_a_live_owner_is_named_and_refused(holder: tuple[Path, subprocess.Popen[str]]) -> None:
    run, proc = holder
    owner = runlock.live_owner(run)
    assert owner is not None
    assert (owner.pid, owner.host, owner.activity) == (proc.pid, socket.gethostname(),
                                                       "written")
    with pytest.raises(RunInUseError, match=f"is being written by pid {proc.pid} on "):
        runlock.refuse_if_live(run)
    for fresh in (True, False):  # neither a new run nor a recovery can take it
        with pytest.raises(RunInUseError), runlock.owning(run, "recovered", fresh=fresh):
            pass
    assert sorted(p.name for p in run.iterdir()) == [runlock.LOCK]


def test_the_lock_of_a_killed_process_is_free(holder: tuple[Path, subprocess.Popen[str]]
                                              ) -> None:
    run, proc = holder
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert (run / runlock.LOCK).is_file()  # left behind, but nobody holds it
    assert runlock.live_owner(run) is None
    runlock.refuse_if_live(run)
    with runlock.owning(run, "recovered", fresh=False):
        assert runlock.live_owner(run) is not None  # this process holds it now
    assert not (run / runlock.LOCK).exists()


def test_an_owner_that_ends_removes_its_lock(holder: tuple[Path, subprocess.Popen[str]]
                                             ) -> None:
    run, proc = holder
    assert proc.stdin is not None
    proc.stdin.close()
    assert proc.wait() == 0
    assert list(run.iterdir()) == []
    assert runlock.live_owner(run) is None


def test_no_directory_or_no_lock_file_means_no_owner(tmp_path: Path) -> None:
    assert runlock.live_owner(tmp_path / "nowhere") is None
    assert runlock.live_owner(tmp_path) is None
    (tmp_path / "file").write_text("not a directory")
    runlock.refuse_if_live(tmp_path / "file")



def test_inspect_refuses_a_run_being_written_as_every_command_does(
        holder: tuple[Path, subprocess.Popen[str]], capsys: pytest.CaptureFixture[str]) -> None:
    """``srr inspect`` said ``metadata.yaml: missing (the recording did not finish; srr recover
    rebuilds the bag)`` of a live run, where the others name its owner."""
    from harness.cli import main

    run, proc = holder
    (run / "bag").mkdir()
    (run / "bag" / "bag.mcap").write_bytes(b"\x89MCAP0\r\n")  # being written
    for target in (run, run / "bag", run / "bag" / "bag.mcap"):
        assert main(["inspect", str(target)]) == 2
        err = capsys.readouterr().err.strip()
        assert err == (f"srr inspect: {run} is being written by pid {proc.pid} on "
                       f"{socket.gethostname()}; wait until it ends or stop it "
                       f"(kill {proc.pid}), then try again"), err
