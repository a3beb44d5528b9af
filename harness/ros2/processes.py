"""The external processes that run the nodes under test (``ros2.external``).

Each is started in its own process group with the run's ROS 2 environment (domain id,
discovery range), its output in ``<run dir>/ros2/<name>.log``. At the end each group gets
SIGINT (what Ctrl-C sends a ROS 2 node or launch), then SIGTERM, then SIGKILL, ``grace_s``
apart; exit codes and how each ended go to ``<run dir>/ros2/processes.json``."""

from __future__ import annotations

import contextlib
import ctypes
import json
import os
import signal
import subprocess
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from harness.errors import SrrError
from harness.scenario.schema import Ros2ProcessSpec

__all__ = ["ExternalProcess", "start_processes", "stop_processes"]


@dataclass
class ExternalProcess:
    name: str
    spec: Ros2ProcessSpec
    proc: subprocess.Popen[bytes]
    log_path: Path
    log: IO[bytes]
    ended_by: str = ""  # "" (exited by itself), "SIGINT", "SIGTERM" or "SIGKILL"
    events: list[str] = field(default_factory=list)

    def alive(self) -> bool:
        return self.proc.poll() is None


def _ends_with_us() -> Callable[[], None] | None:
    """What the child runs before its command: Linux's ``PR_SET_PDEATHSIG`` with SIGTERM, so
    a node started in a session of its own (Ctrl-C in the terminal does not reach it; srr
    stops it) still ends when srr is killed with SIGKILL and cannot stop it. The libc call is
    looked up here, in the parent: the child only calls it. None where ``prctl`` is
    missing."""
    try:
        prctl = ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return None
    parent = os.getpid()

    def set_up() -> None:
        prctl(1, int(signal.SIGTERM), 0, 0, 0)  # 1: PR_SET_PDEATHSIG
        if os.getppid() != parent:  # srr died before the request took effect
            os.kill(os.getpid(), signal.SIGTERM)

    return set_up


def start_processes(specs: Sequence[Ros2ProcessSpec], env: Mapping[str, str],
                    log_dir: Path) -> list[ExternalProcess]:
    log_dir.mkdir(parents=True, exist_ok=True)
    out: list[ExternalProcess] = []
    for i, spec in enumerate(specs):
        name = spec.name or f"external_{i}"
        cmd = list(spec.cmd)
        if spec.use_sim_time:
            cmd += ["--ros-args", "-p", "use_sim_time:=true"]
        log_path = log_dir / f"{name}.log"
        log = log_path.open("wb")
        try:
            proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=log,
                                    stderr=subprocess.STDOUT, env={**env, **spec.env},
                                    start_new_session=True, preexec_fn=_ends_with_us())
        except OSError as err:
            log.close()
            stop_processes(out, log_dir)
            raise SrrError(f"ros2.external[{i}].cmd: cannot start {cmd[0]!r}: "
                           f"{err.strerror or err}") from None
        out.append(ExternalProcess(name, spec, proc, log_path, log))
    return out


def _wait(p: ExternalProcess, timeout_s: float) -> bool:
    try:
        p.proc.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        return False
    return True


def stop_processes(procs: Sequence[ExternalProcess], log_dir: Path,
                   grace_s: float = 5.0) -> list[dict[str, Any]]:
    """Stop every process (SIGINT, SIGTERM, SIGKILL, ``grace_s`` apart) and record how."""
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL):
        running = [p for p in procs if p.alive()]
        if not running:
            break
        for p in running:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(p.proc.pid, sig)
            p.ended_by = sig.name
        deadline = time.monotonic() + grace_s
        for p in running:
            _wait(p, max(0.0, deadline - time.monotonic()))
    records = []
    for p in procs:
        p.log.close()
        code = p.proc.returncode
        records.append({"name": p.name, "cmd": list(p.spec.cmd), "pid": p.proc.pid,
                        "exit_code": code, "stopped_with": p.ended_by or None,
                        "log": p.log_path.name, "events": p.events})
    if procs:
        (log_dir / "processes.json").write_text(json.dumps(records, indent=2) + "\n",
                                                encoding="utf-8")
    return records
