"""A forked local worker writes to its log through fds 1 and 2, whatever the parent's
``sys.stdout``/``sys.stderr`` are (here pytest's capture, which has no file descriptor:
the child used to fail on it, status 70, with an empty log)."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness import api

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]


def test_forked_worker_under_replaced_streams(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    suite = tmp_path / "suite.yaml"
    suite.write_text(f"scenarios:\n  - path: {ROOT / 'scenarios' / 'forklift_warehouse.yaml'}"
                     "\n    set: {duration: 2}\n")
    res = api.suite([suite], jobs=1, out=tmp_path / "out", fork=True,
                    baselines=tmp_path / "no-baselines")
    [run] = res.summary["runs"]
    assert run["exit_code"] in (0, 1) and run["verdict"] != "INVALID", run["reasons"]
    capsys.readouterr()
