"""A scenario that records on purpose (``scoring: {record_only: true}``) exits 0 with its own
verdict, RECORDED, when every health gate holds; never PASS, and a scenario that scores
nothing without saying so stays UNSCORED (exit 1)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from harness.cli import main

HALL = ("format_version: 1\nname: hall_recording\nduration: 0.25\nclock: {enabled: true}\n"
        "world: {size: [30.0, 20.0], shelves: [], dock: {enabled: false}}\n")


@pytest.fixture
def scene(tmp_path: Path) -> Path:
    src = tmp_path / "hall.yaml"
    src.write_text(HALL + "scoring: {record_only: true}\n", encoding="utf-8")
    return src


@pytest.mark.slow
def test_a_recording_only_scene_exits_0_with_its_own_verdict(
        scene: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", str(scene), "--out", str(tmp_path / "r"), "-q"]) == 0
    assert "verdict: RECORDED" in capsys.readouterr().out
    s = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert (s["verdict"], s["exit_code"], s["metrics"], s["comparison"]) == (
        "RECORDED", 0, [], [])
    assert s["health"] and all(h["ok"] for h in s["health"])
    assert "recorded on purpose" in s["reasons"][0]
    suite = ET.parse(tmp_path / "r" / "junit.xml").getroot()
    assert suite.get("failures") == "0"
    verdict = [c for c in suite.iter("testcase") if c.get("name") == "verdict"]
    assert len(verdict) == 1 and "RECORDED" in (verdict[0].findtext("system-out") or "")
    html = (tmp_path / "r" / "report.html").read_text()
    assert 'data-verdict="RECORDED"' in html and "Recorded on purpose" in html


@pytest.mark.slow
def test_a_tripped_health_gate_still_fails_a_recording_only_scene(
        scene: Path, tmp_path: Path) -> None:
    code = main(["run", str(scene), "--out", str(tmp_path / "r"), "-q",
                 "--set", "scoring.health.expected_rates={/clock: 1000}"])
    assert code == 3
    assert json.loads((tmp_path / "r" / "summary.json").read_text())["verdict"] == "INVALID"


@pytest.mark.slow
def test_unscored_without_saying_so_stays_exit_1(tmp_path: Path) -> None:
    src = tmp_path / "hall.yaml"
    src.write_text(HALL, encoding="utf-8")
    assert main(["run", str(src), "--out", str(tmp_path / "r"), "-q"]) == 1
    assert json.loads((tmp_path / "r" / "summary.json").read_text())["verdict"] == "UNSCORED"


def test_record_only_with_a_scoring_block_is_refused(
        scene: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["validate", str(scene), "--set", "scoring.perception={marker_topics: [/t]}",
                 "--set", "srr_gt=true"])
    err = " ".join(capsys.readouterr().err.split())
    assert code == 2
    assert f"{scene}: scoring.record_only: a record-only scenario scores nothing, and " \
           "scoring.perception is enabled" in err


@pytest.mark.slow
def test_a_suite_of_recording_only_scenes_exits_0(scene: Path, tmp_path: Path) -> None:
    code = main(["suite", str(scene), "--jobs", "1", "--out", str(tmp_path / "suite"), "-q"])
    assert code == 0
    s = json.loads((tmp_path / "suite" / "summary.json").read_text())
    assert s["verdict"] == "RECORDED" and s["counts"] == {"RECORDED": 1}
    root = ET.parse(tmp_path / "suite" / "junit.xml").getroot()
    assert root.get("failures") == "0"
