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

from harness.cli import main
from harness.regression.store import BaselineError, load_baseline

BASELINES = Path(__file__).resolve().parents[2] / "baselines"
SCENARIOS = BASELINES.parent / "scenarios"


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
    (lambda d: d["metrics"][_first(d, "metrics")].update(direction="sideways"),
     lambda d: f"metrics.{_first(d, 'metrics')}.direction",
     "expected one of 'lower', 'higher', 'none', got 'sideways'"),
    (lambda d: d.update(format_version=99),
     lambda d: "format_version", "99 is newer than this srr reads (up to 1); use a newer srr"),
    (lambda d: d.update(format_version="1"),
     lambda d: "format_version", "expected an integer, got '1'"),
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


@pytest.mark.parametrize("spoil", ["direction", "format_version"])
def test_run_and_diff_refuse_a_baseline_in_the_same_words(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], spoil: str) -> None:
    """One check of a baseline file for every command: ``srr run`` accepted a metric's
    ``direction: sideways`` (and ``format_version: 99``) that ``srr diff`` refused, in other
    words and under a path that does not exist (``metrics[0].direction``)."""
    data = json.loads((BASELINES / "forklift_warehouse.json").read_text(encoding="utf-8"))
    if spoil == "direction":
        data["metrics"][_first(data, "metrics")]["direction"] = "sideways"
    else:
        data["format_version"] = 99
    bdir = tmp_path / "b"
    bdir.mkdir()
    path = bdir / "forklift_warehouse.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(BaselineError) as want:
        load_baseline(path)
    for argv in (["run", str(SCENARIOS / "forklift_warehouse.yaml"), "--duration", "0.5",
                  "--baselines", str(bdir), "--out", str(tmp_path / "r"), "-q"],
                 ["diff", str(path), str(tmp_path)]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err == f"srr {argv[0]}: {want.value}\n", err
    assert not (tmp_path / "r").exists()
