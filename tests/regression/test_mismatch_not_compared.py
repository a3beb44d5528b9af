"""A MISMATCH run (a baseline of another configuration) compares nothing, so no metric row
says regressed, improved or ok against it: console, summary, junit and report show the rows
as not compared."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from harness.cli import main
from tests.conftest import SCENARIOS

pytestmark = pytest.mark.slow  # runs a scenario

FW = SCENARIOS / "forklift_warehouse.yaml"


def test_a_mismatch_shows_its_metric_rows_as_not_compared(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    run = tmp_path / "r"
    assert main(["run", str(FW), "--duration", "2", "--out", str(run), "-q"]) == 1
    out = capsys.readouterr().out
    s = json.loads((run / "summary.json").read_text())
    assert s["verdict"] == "MISMATCH"
    # 2 s never reach the goal the 35 s baseline reached: compared, these would regress
    goal = next(e for e in s["comparison"] if e["name"] == "control.goal_reached")
    assert (goal["value"], goal["baseline"]) == (0.0, 1.0)
    assert {e["status"] for e in s["comparison"]} == {"not_compared"}
    assert all(e["delta"] is None for e in s["comparison"])
    table = out.split("verdict:")[0]
    assert "regressed" not in table and "improved" not in table
    assert "metrics beside a baseline of another configuration (not compared)" in out
    assert table.count("not compared") == len(s["comparison"]) + 1  # rows and title
    cases = {c.get("name"): c for c in ET.parse(run / "junit.xml").getroot().iter("testcase")}
    assert cases["control.goal_reached"].find("failure") is None
    assert "not compared" in (cases["control.goal_reached"].findtext("system-out") or "")
    assert cases["verdict"].find("failure") is not None  # the run still fails, as MISMATCH
    html = (run / "report.html").read_text()
    assert "badge b-regressed" not in html and "st-regressed" not in html.split("</style>")[1]
    assert "All metrics beside a baseline of another configuration, not compared" in html
    assert html.count('<span class="badge b-not_compared">not compared</span>') == len(
        s["comparison"])
