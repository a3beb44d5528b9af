"""A real tf2 buffer as an independent judge of a recorded TF tree.

The ``ros-jazzy-*`` wheels have no tf2; Debian's ``python3-tf2`` (ROS 1's binding of the same
C++ ``tf2::BufferCore``) runs under the system Python, so :func:`tf2_accepts` reads a bag's
``/tf`` and ``/tf_static`` with the independent mcap reader, feeds every transform to that
buffer in a subprocess (``tests/tf2_buffer.py``) and returns what tf2 made of them.

Unavailable tf2 skips the caller, unless ``SRR_REQUIRE_ROS2=1`` (CI installs it).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.bagread import decoded

SYSTEM_PYTHON = "/usr/bin/python3"
SCRIPT = Path(__file__).with_name("tf2_buffer.py")


def tf2_available() -> bool:
    if not shutil.which(SYSTEM_PYTHON):
        return False
    probe = subprocess.run([SYSTEM_PYTHON, "-c", "import tf2_py, genpy, geometry_msgs.msg"],
                           capture_output=True, timeout=60, env=_env())
    return probe.returncode == 0


def need_tf2() -> None:
    if tf2_available():
        return
    why = ("no real tf2: install Debian's python3-tf2 (apt-get install python3-tf2) for "
           f"{SYSTEM_PYTHON}")
    if os.environ.get("SRR_REQUIRE_ROS2") == "1":
        pytest.fail(why)
    pytest.skip(why)


def _env() -> dict[str, str]:
    # The system interpreter must not see the project's virtual environment (ROS 2 wheels
    # carry message packages with the same names as ROS 1's).
    return {k: v for k, v in os.environ.items()
            if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}


@dataclass(frozen=True)
class Tf2Result:
    frames: dict[str, dict[str, Any]]  # frame → parent, found, xyz, why
    errors: list[str]  # exceptions tf2 raised while being fed
    warnings: list[str]  # what tf2 printed (TF_REPEATED_DATA, ...)


def recorded_transforms(run_dir: Path) -> list[dict[str, Any]]:
    out = []
    for topic, _, _, msg in decoded(run_dir):
        leaf = topic.rsplit("/", 1)[-1]
        if leaf not in ("tf", "tf_static") or topic.startswith("/gt/"):
            continue
        for t in msg.transforms:
            tr, q = t.transform.translation, t.transform.rotation
            out.append({"parent": t.header.frame_id, "child": t.child_frame_id,
                        "t_ns": t.header.stamp.sec * 1_000_000_000 + t.header.stamp.nanosec,
                        "static": leaf == "tf_static", "topic": topic,
                        "xyz": [tr.x, tr.y, tr.z], "xyzw": [q.x, q.y, q.z, q.w]})
    return out


def tf2_accepts(run_dir: Path, root: str = "world") -> Tf2Result:
    """Feed ``run_dir``'s recorded TF to a real tf2 buffer (skips without tf2)."""
    need_tf2()
    payload = json.dumps({"root": root, "transforms": recorded_transforms(run_dir)})
    done = subprocess.run([SYSTEM_PYTHON, str(SCRIPT)], input=payload, capture_output=True,
                          text=True, timeout=300, env=_env(), check=True)
    data = json.loads(done.stdout)
    warnings = [line for line in done.stderr.splitlines()
                if line.strip() and not line.startswith(" ")]
    return Tf2Result(data["frames"], data["errors"], warnings)
