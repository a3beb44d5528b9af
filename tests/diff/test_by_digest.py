"""``srr diff BASELINE.json RUN``: the topics the baseline's reference recording does not
keep are compared by digest, with no messages to pair: their ``differ`` count is not 0 (which
read as "differs, but 0 messages differ") but not counted at all — ``—`` in the table,
``null`` in ``--json`` — and the note that says why stays."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from harness.cli import _print_diff
from harness.diff.core import _by_digest
from harness.diff.result import DiffResult, RunInfo, TopicDiff

TF = "tf2_msgs/msg/TFMessage"


def _only_in_b(name: str, count: int, sha: str) -> TopicDiff:
    """What diff_bags gives for a topic the reference recording (A's bag) does not hold."""
    return TopicDiff(name=name, type_a=None, type_b=TF, count_a=0, count_b=count,
                     sha256_a=None, sha256_b=sha, status="only_in_b", messages_differ=0,
                     first=None, first_beyond=None, fields=(), mismatches=(), time_shifts=0,
                     worst=None, tolerances=())


def test_topics_compared_by_digest_count_no_messages(
        capsys: pytest.CaptureFixture[str]) -> None:
    recorded = {"/tf": {"type": TF, "count": 20, "sha256": "aa"},
                "/tf_same": {"type": TF, "count": 20, "sha256": "bb"},
                "/gone": {"type": TF, "count": 5, "sha256": "cc"}}
    topics = _by_digest([_only_in_b("/tf", 20, "zz"), _only_in_b("/tf_same", 20, "bb")],
                        recorded, frozenset())
    by_name = {t.name: t for t in topics}
    assert [(n, t.status, t.messages_differ) for n, t in by_name.items()] == [
        ("/gone", "only_in_a", None), ("/tf", "differs", None),
        ("/tf_same", "identical", None)]
    run = RunInfo(Path("run"), "s", 1, "PASS", 1.0, "d")
    _print_diff(DiffResult(run, run, topics, (), (), ()))
    rows = {line.split()[1]: line for line in capsys.readouterr().out.splitlines()
            if re.match(r"\W*/(tf|gone)", line)}
    assert re.search(r"\bdiffers\W+—\W", rows["/tf"]), rows
    assert re.search(r"\bidentical\W+—\W", rows["/tf_same"]), rows
    assert " 0 " not in rows["/tf"].split("differs")[1], rows
