"""A baseline file is read through the one validator (harness.validation): every bundled
baseline reads back as written, and a malformed one is one line naming the file and the key
inside it that is wrong."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from harness.regression.store import BaselineError, load_baseline

BASELINES = Path(__file__).resolve().parents[2] / "baselines"


def test_every_bundled_baseline_reads_back_as_written() -> None:
    files = sorted(BASELINES.glob("*.json"))
    assert files
    for path in files:
        baseline = load_baseline(path)
        assert baseline is not None
        assert baseline.to_json() == json.loads(path.read_text(encoding="utf-8")), path


def _first(d: dict[str, Any], key: str) -> str:
    return sorted(d[key])[0]


@pytest.mark.parametrize(("spoil", "field", "words"), [
    (lambda d: d["metrics"][_first(d, "metrics")].update(value="high"),
     lambda d: f"metrics.{_first(d, 'metrics')}.value", "expected a number, got 'high'"),
    (lambda d: d["metrics"][_first(d, "metrics")].pop("unit"),
     lambda d: f"metrics.{_first(d, 'metrics')}.unit", "required field is missing"),
    (lambda d: d["versions"].update(mujoco=3),
     lambda d: "versions.mujoco", "expected a string, got 3"),
    (lambda d: d["topics"].update({_first(d, "topics"): 5}),
     lambda d: f"topics.{_first(d, 'topics')}", "expected a mapping, got 5"),
    (lambda d: d.update(seed=True),
     lambda d: "seed", "expected an integer, got True"),
    (lambda d: d.pop("scenario"),
     lambda d: "scenario", "required field is missing"),
])
def test_a_malformed_baseline_names_the_key(
        tmp_path: Path, spoil: Callable[[dict[str, Any]], None],
        field: Callable[[dict[str, Any]], str], words: str) -> None:
    data = json.loads((BASELINES / "forklift_warehouse.json").read_text(encoding="utf-8"))
    where = field(data)
    spoil(data)
    path = tmp_path / "forklift_warehouse.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(BaselineError) as err:
        load_baseline(path)
    assert re.fullmatch(rf"{re.escape(str(path))}: not a valid baseline: "
                        rf"{re.escape(where)}: {re.escape(words)}", str(err.value)), err.value
