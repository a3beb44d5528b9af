"""One run's pull-request summary: from the typed summary whose verdict and exit code the run
returns (a recovered, INVALID run kept in ``data/``; a real regressed run; ``srr run
--summary-md`` end to end)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from harness import api
from harness.cli import main
from harness.run.markdown import run_markdown
from harness.run.summary import RunSummary

DATA = Path(__file__).parent / "data"
ROOT = Path(__file__).resolve().parents[2]


def _rows(md: str, heading: str) -> list[str]:
    return md.split(f"### {heading}\n\n", 1)[1].split("\n\n", 1)[0].splitlines()[2:]


def test_an_invalid_run_names_its_tripped_gate() -> None:
    s = RunSummary.read(DATA / "recovered")
    md = run_markdown(s, link_base="runs/x")
    assert md.startswith(f"## 💥 srr run `{s.scenario}`: **INVALID** (exit code 3)\n")
    assert "[report](runs/x/report.html)" in md
    (gate,) = _rows(md, "Health gates that tripped (1 of 1)")
    assert gate.startswith("| `recording_complete` | the run was killed while finalizing")
    assert "### Regressed metrics" not in md


def test_regressed_and_missing_metrics_come_first_by_name() -> None:
    s = RunSummary.read(DATA / "run")  # judged beside a baseline of another configuration
    entries = [dict(e) for e in s.comparison]
    by = {e["name"]: e for e in entries}
    by["control.goal_reached"] |= {"status": "regressed", "delta": -1.0}
    by["control.collisions"] |= {"status": "missing", "value": None, "delta": None,
                                 "baseline": 0}
    md = run_markdown(dataclasses.replace(s, comparison=tuple(entries), verdict="REGRESSED"))
    assert md.startswith("## ❌ srr run `forklift_warehouse`: **REGRESSED** (exit code 1)")
    rows = _rows(md, "Regressed metrics")
    assert rows == ["| `control.collisions` | — | 0 | — | ±0 | missing |",
                    "| `control.goal_reached` | 0 bool | 1 | -1 | ±0 | regressed |"]
    assert f"<details><summary>{len(entries) - 2} other metric(s)</summary>" in md


@pytest.mark.slow
def test_srr_run_writes_the_summary_of_the_verdict_it_exits_with(tmp_path: Path) -> None:
    md_file = tmp_path / "pr.md"
    code = main(["run", str(ROOT / "scenarios" / "forklift_warehouse.yaml"), "--duration", "1",
                 "--out", str(tmp_path / "run"), "-q", "--summary-md", str(md_file)])
    s = RunSummary.read(tmp_path / "run")
    assert code == s.exit_code == 1 and s.verdict == "MISMATCH"
    md = md_file.read_text(encoding="utf-8")
    assert md.startswith("## ❌ srr run `forklift_warehouse`: **MISMATCH** (exit code 1)\n")
    assert "[report](run/report.html)" in md and (tmp_path / "run" / "report.html").is_file()
    assert md == run_markdown(s, link_base="run")
    assert api.write_summary_md(api.RunResult(tmp_path / "run", s.verdict, s.exit_code,
                                              s.to_json(), s), tmp_path / "again.md",
                                link_base="run").read_text(encoding="utf-8") == md
