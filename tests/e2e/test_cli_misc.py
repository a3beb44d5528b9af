"""inspect, interruption, and bags that are not bags."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness import api
from harness.cli import main

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "forklift_warehouse.yaml"


@pytest.mark.slow
def test_inspect_lists_topics(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    res = api.run_scenario(api.load(SCENARIO, duration=1.0), out=tmp_path / "r")
    assert main(["inspect", str(res.run_dir / "bag")]) == 0
    out = capsys.readouterr().out
    assert "/odom" in out and "nav_msgs/msg/Odometry" in out and "60" in out
    assert "transient_local" in out


@pytest.mark.parametrize("broken", ["missing", "no-metadata", "truncated"])
@pytest.mark.slow
def test_inspect_refuses_broken_bags(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                     broken: str) -> None:
    bag = tmp_path / "bag"
    if broken != "missing":
        res = api.run_scenario(api.load(SCENARIO, duration=1.0), out=tmp_path / "r")
        bag = res.run_dir / "bag"
        if broken == "no-metadata":
            (bag / "metadata.yaml").unlink()
        else:
            (mcap,) = bag.glob("*.mcap")
            data = mcap.read_bytes()
            mcap.write_bytes(data[: len(data) // 2])
    code = main(["inspect", str(bag)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "Traceback" not in err
    assert str(bag) in err
    if broken == "truncated":  # said in words, with the way out
        assert "the file is cut short or damaged" in err and "srr recover" in err, err


def test_inspect_names_a_file_that_is_no_mcap_or_empty(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for content, said in ((b"hello, this is text\n", "not an MCAP file"),
                          (b"", "the file is empty")):
        junk = tmp_path / "junk.mcap"
        junk.write_bytes(content)
        assert main(["inspect", str(junk)]) == 2
        assert capsys.readouterr().err.strip().endswith(f"cannot read bag: {said}" +
                                                        (" (it does not start with MCAP's "
                                                         "magic bytes)" if content else ""))


@pytest.mark.slow
def test_interrupt_finalizes_bag_and_marks_summary(tmp_path: Path) -> None:
    sc = api.load(SCENARIO, duration=5.0)

    def stop_midway(done: int, total: int) -> None:
        if done == 90:
            raise KeyboardInterrupt

    res = api.run_scenario(sc, out=tmp_path / "r", progress=stop_midway)
    summary = json.loads((res.run_dir / "summary.json").read_text())
    assert summary["interrupted"] is True and summary["verdict"] == "INTERRUPTED"
    assert res.exit_code == 130
    assert summary["topics"]["/clock"]["count"] == 90
    from harness.bag import inspect_bag

    info = inspect_bag(res.run_dir / "bag")  # the bag is finalized and readable
    assert {t.name: t.count for t in info.topics}["/clock"] == 90


def test_out_dir_not_empty_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "keep.txt").write_text("x")
    code = main(["run", str(SCENARIO), "--out", str(tmp_path), "--duration", "0.5", "-q"])
    assert code == 2 and "not empty" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.txt"]


@pytest.mark.slow
def test_a_ctrl_c_that_lands_in_a_ctypes_call_interrupts_the_run(tmp_path: Path) -> None:
    """Ctrl-C raised inside a ``ctypes`` argument conversion reaches the loop as
    ``ArgumentError``, not ``KeyboardInterrupt``: the run still ends INTERRUPTED (exit 130)
    with its recording kept, not as a failed plug-in with its run directory removed."""
    sc = api.load(SCENARIO, duration=3.0, overrides=[
        "systems_under_test.route_follower.plugin=tests.e2e.interrupt_plugins:CtrlCInCtypes"])
    res = api.run_scenario(sc, out=tmp_path / "r")
    summary = json.loads((res.run_dir / "summary.json").read_text())
    assert (res.exit_code, summary["verdict"]) == (130, "INTERRUPTED")
    clock = summary["topics"]["/clock"]["count"]
    assert 55 <= clock <= 62  # stopped in the tick at 1 s (60 Hz), not before
    from harness.bag import inspect_bag

    assert {t.name: t.count for t in inspect_bag(res.run_dir).topics}["/clock"] == clock


def test_a_ctrl_c_that_lands_in_a_ctypes_call_before_the_run_is_an_interrupt(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The same Ctrl-C in a plug-in's set-up, before the first tick: ``srr run`` says it was
    interrupted (exit 130), not that the plug-in failed, and leaves no run directory."""
    out = tmp_path / "r"
    code = main(["run", str(SCENARIO), "--duration", "1", "-q", "--out", str(out), "--set",
                 "systems_under_test.route_follower.plugin="
                 "tests.e2e.interrupt_plugins:CtrlCInCtypesAtSetup"])
    err = capsys.readouterr().err
    assert code == 130 and err.strip().splitlines()[-1] == "srr run: interrupted", err
    assert not out.exists()
