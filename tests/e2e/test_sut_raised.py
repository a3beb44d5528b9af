"""A system under test that raises during a run: the code under test broke. The run stops
there, INVALID (gate ``sut_raised:<name>``), with what it recorded kept and the plug-in's
traceback beside it; never a harness traceback, never a removed run directory."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness.bag import inspect_bag
from harness.cli import main

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "forklift_warehouse.yaml"
PLUGIN = "systems_under_test.route_follower.plugin=tests.e2e.raising_plugins:"


def _run(tmp_path: Path, cls: str, capsys: pytest.CaptureFixture[str]) -> tuple[Path, str]:
    out = tmp_path / cls
    code = main(["run", str(SCENARIO), "--duration", "2", "-q", "--no-video", "--out",
                 str(out), "--set", PLUGIN + cls])
    said = capsys.readouterr()
    assert code == 3 and "Traceback" not in said.err + said.out, said
    summary = json.loads((out / "summary.json").read_text())
    assert summary["verdict"] == "INVALID" and summary["stopped"]
    gates = {g["name"]: g["ok"] for g in summary["health"]}
    assert gates["sut_raised:route_follower"] is False
    return out, " ".join(summary["reasons"])


@pytest.mark.parametrize(("cls", "where", "error"), [
    ("RaisesInStep", "RuntimeError in step at 1 s of simulated time: boom in step",
     "RuntimeError: boom in step"),
    ("RaisesInCallback", "KeyError in its callback on /clock: 'boom in a callback'",
     "KeyError: 'boom in a callback'"),
])
def test_a_plug_in_that_raises_mid_run_stops_it_invalid_with_its_recording(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], cls: str, where: str,
        error: str) -> None:
    out, reasons = _run(tmp_path, cls, capsys)
    assert f"system under test route_follower raised {where}" in reasons, reasons
    assert f"(traceback: {out / 'traceback.txt'})" in reasons
    traceback = (out / "traceback.txt").read_text()
    assert "raising_plugins.py" in traceback and traceback.strip().endswith(error)
    clock = {t.name: t.count for t in inspect_bag(out / "bag").topics}["/clock"]
    assert 55 <= clock <= 62  # recorded up to the tick at 1 s (60 Hz), kept
    assert (out / "report.html").is_file()


def test_a_plug_in_that_raises_in_setup_stops_the_run_before_it_starts(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Set-up runs before the run (the wiring is planned from it): one line naming the
    field and the plug-in's line, exit 2, no run directory; ``srr validate`` says the same."""
    out = tmp_path / "r"
    for argv in (["run", str(SCENARIO), "-q", "--out", str(out)], ["validate", str(SCENARIO)]):
        assert main([*argv, "--set", PLUGIN + "RaisesInSetup"]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "Traceback" not in err, err
        assert err.startswith(f"srr {argv[0]}: {SCENARIO}: systems_under_test[")
        assert "route_follower raised ValueError in setup: boom in setup (" in err
        assert "raising_plugins.py:" in err
    assert not out.exists()


def test_a_suite_run_whose_plug_in_raises_is_invalid_for_that_reason(tmp_path: Path) -> None:
    """In a suite worker the same run ends INVALID with the plug-in's error as its reason,
    not as a worker that died without a summary."""
    from harness.suite.worker import run_job

    job = {"scenario_file": str(SCENARIO), "run_dir": "r1",
           "overrides": ["duration=2", PLUGIN + "RaisesInStep"]}
    ended = run_job(job, tmp_path)
    assert (ended["exit_code"], ended["error"]) == (3, None)
    summary = json.loads((tmp_path / "r1" / "summary.json").read_text())
    assert "route_follower raised RuntimeError in step" in " ".join(summary["reasons"])


def test_a_plug_in_that_cannot_be_imported_or_made_is_one_line(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "srr_bad_syntax.py").write_text("def f(: pass\n")
    (tmp_path / "srr_init_args.py").write_text(
        "from harness.sut.route_follower import RouteFollower\n"
        "class NeedsArgs(RouteFollower):\n"
        "    def __init__(self, x):\n"
        "        self.x = x\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    field = "--set: systems_under_test[0].plugin"  # the flag gave the plug-in
    for plugin, said in (
            ("srr_bad_syntax:X", f"{field}: cannot import module 'srr_bad_syntax': "
                                 "SyntaxError: invalid syntax"),
            ("srr_init_args:NeedsArgs", f"{field}: srr_init_args:NeedsArgs() failed "
                                        "(TypeError: ")):
        assert main(["validate", str(SCENARIO), "--set",
                     f"systems_under_test.route_follower.plugin={plugin}"]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith(f"srr validate: {said}") and "\n" not in err, err
