"""``srr search`` input: the space syntax, the objective, samplers, and the one-line exit-2
errors for bad input (nothing runs: these load the scenario only)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from harness.cli import main
from harness.errors import SrrError
from harness.search.objective import parse_objective
from harness.search.runner import SearchConfig, plan_search
from harness.search.space import parse_dimension, parse_space

ROOT = Path(__file__).resolve().parents[2]
CROSSING = str(ROOT / "scenarios" / "dock_worker_crossing.yaml")


def test_ranges_parse_to_their_kinds() -> None:
    d = parse_dimension("workers.0.speed=0.5..2.5")
    assert (d.kind, d.low, d.high, d.step, d.log) == ("float", 0.5, 2.5, None, False)
    d = parse_dimension("workers.0.start_delay=10..30:2")
    assert (d.kind, d.low, d.high, d.step) == ("int", 10, 30, 2)
    d = parse_dimension("workers.0.start_delay=0..2:0.5")
    assert (d.kind, d.step) == ("float", 0.5)
    d = parse_dimension("x.noise=0.001..0.1:log")
    assert d.log and d.kind == "float"
    d = parse_dimension("systems_under_test.safety_monitor.plugin=['a:B', c]")
    assert d.kind == "categorical" and d.choices == ("a:B", "c")


@pytest.mark.parametrize("text, words", [
    ("workers.0.speed", "PATH=RANGE"),
    ("workers.0.speed=2.5..0.5", "greater than LO"),
    ("workers.0.speed=0.5-2.5", "LO..HI"),
    ("workers.0.speed=a..2", "'a' is not a number"),
    ("workers.0.speed=0..2:0", "STEP must be > 0"),
    # optuna would stop the grid at 64 and never try the top
    ("physics.tick_hz=50..70:7", "HI - LO (20) is not a whole number of steps of 7: the grid "
                                 "would stop at 64 and never try 70; make HI 64 or 71"),
    ("workers.0.speed=0..1:0.3", "the grid would stop at 0.9"),
    ("workers.0.speed=0..2:log", "LO > 0"),
    ("workers.0.speed=[]", "non-empty list"),
    ("workers.0.speed=[1, 1]", "listed twice"),
    ("workers..speed=0..1", "dotted"),
])
def test_bad_ranges_name_the_flag(text: str, words: str) -> None:
    with pytest.raises(SrrError) as err:
        parse_dimension(text)
    assert str(err.value).startswith(f"--space {text}:") and words in str(err.value)


def test_a_path_given_twice_is_refused() -> None:
    with pytest.raises(SrrError, match="given twice"):
        parse_space(["a.b=0..1", "a.b=[1, 2]"])


def test_objective_thresholds() -> None:
    o = parse_objective("safety.min_clearance", below=0.5, above=None)
    assert o.violated(0.4) and not o.violated(0.5) and o.direction == "minimize"
    assert o.margin(0.4) == pytest.approx(-0.1)
    o = parse_objective("safety.over_mute", below=None, above=1.5)
    assert o.violated(2.0) and not o.violated(1.5) and o.direction == "maximize"
    o = parse_objective("spec.no_collision.robustness", below=None, above=None)
    assert (o.below, o.threshold) == (True, 0.0)  # robustness: violated below 0
    with pytest.raises(SrrError, match="--violated-below VALUE or --violated-above"):
        parse_objective("safety.over_mute", below=None, above=None)
    with pytest.raises(SrrError, match="one, not both"):
        parse_objective("safety.over_mute", below=1.0, above=2.0)


def _search(tmp_path: Path, *extra: str) -> list[str]:
    return ["search", CROSSING, "--out", str(tmp_path / "out"), "--budget", "1", *extra]


@pytest.mark.parametrize("extra, line", [
    (["--space", "workers.0.speed=2..1", "--objective", "safety.over_mute",
      "--violated-above", "1"], "srr search: --space workers.0.speed=2..1: HI (1) must be"),
    # a plug-in's parameters are checked at both ends too (they are read in its set-up)
    (["--space", "systems_under_test.safety_monitor.params.reaction_delai=0..1",
      "--objective", "safety.over_mute", "--violated-above", "1"],
     "srr search: --space systems_under_test.safety_monitor.params.reaction_delai=0.0: "
     "systems_under_test[2].params.reaction_delai: unknown field"),
    (["--space", "systems_under_test.safety_monitor.params.reaction_delay=0..4000",
      "--objective", "safety.over_mute", "--violated-above", "1"],
     "srr search: --space systems_under_test.safety_monitor.params.reaction_delay=4000.0: "
     "systems_under_test[2].params.reaction_delay: must be <= 3600"),
    (["--space", "workers.0.speed=0.5..2", "--objective", "safety.over_mute",
      "--violated-above", "1", "--sampler", "annealing"],
     "srr search: --sampler annealing: expected one of tpe, random, qmc, cmaes"),
    (["--space", "workers.0.speed=0.5..2", "--objective", "safety.over_mute"],
     "srr search: --objective safety.over_mute: say when a run violates it"),
    (["--space", "workers.0.sped=0.5..2", "--objective", "safety.over_mute",
      "--violated-above", "1"], "srr search: --space workers.0.sped: "),
    (["--space", "workers.0.speed=-3..2", "--objective", "safety.over_mute",
      "--violated-above", "1"], "srr search: --space workers.0.speed: "),
    (["--objective", "safety.over_mute", "--violated-above", "1"],
     "srr search: --space: give at least one PATH=RANGE"),
    (["--space", "workers.0.speed=0.5..2", "--objective", "safety.over_mute",
      "--violated-above", "1", "--budget", "0"], "srr search: --budget: must be >= 1"),
    # --set on a searched path: each trial's value would replace it
    (["--space", "workers.0.speed=0.5..2", "--set", "workers.0.speed=1", "--objective",
      "safety.over_mute", "--violated-above", "1"],
     "srr search: --set workers.0.speed=1: workers.0.speed is searched (--space "
     "workers.0.speed): each trial's value would replace this one; leave one of the two out"),
    (["--space", "workers.0.speed=0.5..2", "--objective", "safety.over_mute",
      "--violated-above", "1", "--bless", "--reason", "x"],
     "srr search: --bless: only with --add-to-suite SUITE"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                          extra: list[str], line: str) -> None:
    argv = _search(tmp_path, *extra)
    if "--budget" in extra:  # the flag given last wins
        argv = ["search", CROSSING, "--out", str(tmp_path / "out"), *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(line) and "\n" not in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()  # nothing ran, nothing written


def test_warnings_are_of_the_values_the_search_tries() -> None:
    """The scenario's own start_delay (22 s) is not before the end of a 20 s run, but the
    search varies it over 0..26: the nominal value's warning is not said, the top end's is."""
    plan = plan_search(SearchConfig(
        CROSSING, parse_space(["workers.0.start_delay=0..26"]),
        parse_objective("safety.over_mute", below=None, above=1.0), ("duration=20",)))
    assert [w for w in plan.warnings if "start_delay" in w] == [
        "--space workers.0.start_delay=26.0: workers[0].start_delay: 26 s is not before the "
        "end of the run (duration 20 s): worker 'character_0' stands at its first waypoint "
        "the whole run"]


def test_a_metric_group_the_scenario_does_not_score(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """forklift_warehouse scores control only: a safety objective could never be met."""
    argv = ["search", str(ROOT / "scenarios" / "forklift_warehouse.yaml"), "--out",
            str(tmp_path / "out"), "--space", "duration=2..3", "--objective",
            "safety.over_mute", "--violated-above", "1"]
    assert main(argv) == 2
    assert "scores no safety" in capsys.readouterr().err


def test_add_to_suite_must_be_a_suite_file(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    argv = _search(tmp_path, "--space", "workers.0.speed=0.5..2", "--objective",
                   "safety.over_mute", "--violated-above", "1", "--add-to-suite", CROSSING)
    assert main(argv) == 2
    assert "not a suite file" in capsys.readouterr().err


@pytest.mark.parametrize("make, words", [
    (lambda out: out.write_text("x"), "is a file, not a folder"),
    (lambda out: (out.mkdir(), (out / "keep.txt").write_text("x")),
     "holds no search (study.db) to resume"),
    # an emptied study.db beside earlier trials' run directories: no search to resume either
    (lambda out: (out.mkdir(), (out / "keep.txt").write_text("x"),
                  (out / "study.db").write_bytes(b"")),
     "holds no search (study.db is empty) to resume"),
])
def test_out_that_is_not_a_search_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                             make: Any, words: str) -> None:
    out = tmp_path / "out"
    make(out)
    argv = ["search", CROSSING, "--out", str(out), "--space", "workers.0.speed=0.5..2",
            "--objective", "safety.over_mute", "--violated-above", "1"]
    assert main(argv) == 2
    assert words in capsys.readouterr().err
    assert not out.is_dir() or sorted(p.name for p in out.iterdir()
                                      if p.name != "study.db") == ["keep.txt"]
