"""``srr diff BASELINE.json RUN``: a run against a baseline file, where the run's summary only
says that its recording differs. The baseline's reference recording stands for A's bag (the
first divergence, field by field); the topics it does not keep are compared by the digests
the baseline holds."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from harness.cli import main
from tests.conftest import ModuleTmp

ROOT = Path(__file__).resolve().parents[2]
FW = ROOT / "scenarios" / "forklift_warehouse.yaml"
BASELINE = ROOT / "baselines" / "forklift_warehouse.json"

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def runs(module_tmp: ModuleTmp) -> dict[str, Path]:
    out = module_tmp("diffbase")
    made = {"same": out / "same", "faster": out / "faster"}
    assert main(["run", str(FW), "--out", str(made["same"]), "-q"]) == 0
    main(["run", str(FW), "--out", str(made["faster"]), "-q",
          "--set", "systems_under_test.route_follower.params.speed=1.3"])
    return made


def test_a_run_that_drives_otherwise_diverges_from_the_baseline_on_cmd_vel(
        runs: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["diff", str(BASELINE), str(runs["faster"]), "--json", str(tmp_path / "d.json")])
    out, err = capsys.readouterr()
    assert code == 1
    result = json.loads((tmp_path / "d.json").read_text())
    status = {t["name"]: t["status"] for t in result["topics"]}
    assert status == {"/clock": "identical", "/tf_static": "identical", "/cmd_vel": "differs",
                      "/odom": "differs", "/gt/forklift/tf": "differs", "/tf": "differs"}
    lines = out.splitlines()
    first = next(line for line in lines if line.startswith("first divergence: "))
    assert first.startswith("first divergence: /cmd_vel message #")
    assert "its reference recording keeps 5 of its 6 topics; the others are compared by " \
        "their digests only" in " ".join(err.split())
    # /tf is not in the reference: compared by digest, nothing to point at
    (tf,) = [t for t in result["topics"] if t["name"] == "/tf"]
    assert tf["first"] is None and tf["count_a"] == tf["count_b"] == 2100
    assert tf["messages_differ"] is None  # not counted (— in the table), not 0


def test_a_run_that_records_the_baseline_is_identical_to_it(
        runs: dict[str, Path], capsys: pytest.CaptureFixture[str]) -> None:
    summary = json.loads((runs["same"] / "summary.json").read_text())
    if not summary["baseline"]["digest_matches"]:
        pytest.skip("this machine does not record the shipped baseline's bytes: "
                    f"{summary['baseline'].get('versions_differing')}")
    assert main(["diff", str(BASELINE), str(runs["same"])]) == 0
    assert "verdict: IDENTICAL (6 topics: 6 identical)" in capsys.readouterr().out


def test_a_baseline_file_without_its_reference_or_with_html_is_refused(
        runs: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lone = tmp_path / "forklift_warehouse.json"
    shutil.copy(BASELINE, lone)  # no .mcap beside it
    assert main(["diff", str(lone), str(runs["same"])]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert f"{lone.with_suffix('.mcap')}: missing: this baseline has no reference recording" in err
    assert main(["diff", str(BASELINE), str(runs["same"]), "--html", str(tmp_path / "x.html")]) == 2
    assert "--html: shows two run directories" in capsys.readouterr().err
    assert not (tmp_path / "x.html").exists()
    # B is the run compared: a baseline there is named as such, not as a missing directory
    assert main(["diff", str(runs["same"]), str(BASELINE)]) == 2
    assert f"{BASELINE}: a baseline file can only be A" in capsys.readouterr().err
