"""Suite files, folders and sweeps → entries and runs; every mistake names file and field."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import pytest

from harness.cli import main
from harness.errors import ScenarioError, SrrError
from harness.suite.plan import plan_runs
from harness.suite.runner import plan_suite
from harness.suite.spec import load_suite
from harness.suite.stats import describe
from harness.suite.sweep import expand, parse_sweep

ROOT = Path(__file__).resolve().parents[2]
FORKLIFT = ROOT / "scenarios" / "forklift_warehouse.yaml"


def _suite(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "suite.yaml"
    p.write_text(text.replace("FORKLIFT", str(FORKLIFT)), encoding="utf-8")
    return p


def test_sweep_values_range_and_grid() -> None:
    params = parse_sweep({"a.b": [1, 2], "seed": {"from": 0.1, "to": 0.5, "step": 0.2}}, "f")
    assert params[1].values == (0.1, 0.3, 0.5)  # binary noise rounded away
    points = expand(params)
    assert [p.label for p in points] == ["b=1,seed=0.1", "b=1,seed=0.3", "b=1,seed=0.5",
                                         "b=2,seed=0.1", "b=2,seed=0.3", "b=2,seed=0.5"]
    assert parse_sweep({"n": {"from": 1, "to": 7, "step": 3}}, "f")[0].values == (1, 4, 7)
    assert points[0].overrides() == ("a.b=1", "seed=0.1")
    assert expand(())[0].label == ""


@pytest.mark.parametrize(("raw", "field", "words"), [
    ({"x": []}, "sweep.x", "no values"),
    ({"x": {"from": 0, "to": 1, "step": 0}}, "sweep.x.step", "> 0"),
    ({"x": {"from": 2, "to": 1, "step": 1}}, "sweep.x.to", ">= from"),
    ({"x": {"from": 0, "to": 1, "stp": 1}}, "sweep.x.stp", "unknown field (did you mean 'step'?)"),
    ({"x": {"from": 0, "to": 1}}, "sweep.x.step", "required field is missing"),
    ({"x": {"from": 0, "to": 1e9, "step": 1}}, "sweep.x.step", "at most"),
    ({"x": [1, 1]}, "sweep.x", "listed twice"),
    ({"x": [[1]]}, "sweep.x[0]", "expected true or false, a number or a string, got [1]"),
    ({"x": [1, float("nan")]}, "sweep.x[1]", "expected a finite number, got nan"),
    ({"x": 3}, "sweep.x", "list of values"),
    ([1], "sweep", "mapping"),
])
def test_sweep_errors_name_the_field(raw: object, field: str, words: str) -> None:
    with pytest.raises(ScenarioError) as err:
        parse_sweep(raw, "s.yaml")
    assert err.value.file == "s.yaml" and err.value.field == field
    assert words in err.value.message


def test_suite_file_precedence_names_and_runs(tmp_path: Path) -> None:
    p = _suite(tmp_path, """
suite: nightly
defaults: {repeat: 2, timeout: 50}
scenarios:
  - FORKLIFT
  - path: FORKLIFT
    name: fast
    repeat: 3
    set: {duration: 4}
    sweep: {systems_under_test.route_follower.params.speed: [1.0, 2.0]}
""")
    spec = load_suite([p])
    assert spec.name == "nightly"
    a, b = spec.entries
    assert (a.name, a.repeat, a.timeout_s) == ("forklift_warehouse", 2, 50.0)
    assert (b.name, b.repeat, b.overrides) == ("fast", 3, ("duration=4",))
    assert load_suite([p], repeat=5).entries[0].repeat == 5  # the CLI beats the defaults
    assert load_suite([p], repeat=5).entries[1].repeat == 3  # the entry beats the CLI
    runs = plan_runs(spec)
    assert len(runs) == 2 + 2 * 3
    r = runs[2]
    assert r.group == "fast[speed=1]"
    assert r.id == r.group + "#1" and r.sweep and not r.renders
    assert r.run_dir == "runs/fast/speed=1/r1"
    assert "baseline='forklift_warehouse@speed=1'" \
        in r.overrides
    assert runs[0].run_dir == "runs/forklift_warehouse/nominal/r1"


@pytest.mark.parametrize(("body", "field", "words"), [
    ("scenarios: []", "scenarios", "no scenarios"),
    ("scenarios: [{path: nowhere.yaml}]", "scenarios[0].path", "no such file"),
    ("scenarios: [{path: FORKLIFT, repeat: 0}]", "scenarios[0].repeat", "must be >= 1, got 0"),
    ("scenarios: [{path: FORKLIFT, timeout: -1}]", "scenarios[0].timeout", "must be > 0, got -1"),
    ("scenarios: [{path: FORKLIFT, colour: red}]", "scenarios[0].colour",
     "unknown field (expected path, name, repeat, timeout, set, sweep)"),
    ("scenarios: [FORKLIFT, 5]", "scenarios[1]", "expected a string or a mapping, got 5"),
    ("scenarios: [{path: FORKLIFT, set: [1]}]", "scenarios[0].set[0]",
     "expected a string, got 1"),
    ("scenarios: [{path: FORKLIFT, name: 'a/b'}]", "scenarios[0].name", "letters"),
    ("scenarios: [FORKLIFT, FORKLIFT]", "scenarios[1]: name", "already used"),
    ("defaults: {repeats: 2}\nscenarios: [FORKLIFT]", "defaults.repeats",
     "unknown field (did you mean 'repeat'?)"),
    ("scenarios: [{path: FORKLIFT, sweep: {robots.nobody.speed: [1]}}]",
     "scenarios[0].sweep (speed=1): robots.nobody", "no list"),
    ("scenarios: [FORKLIFT, {path: FORKLIFT, name: b, sweep: {robots.nobody.speed: [1]}}]",
     "scenarios[1].sweep (speed=1): robots.nobody", "no list"),
    ("scenarios: [{path: FORKLIFT, set: {duration: -3}}]", "duration", ""),
    # a value set: gives on a swept path would never be used
    ("scenarios: [{path: FORKLIFT, set: {duration: 2}, sweep: {duration: [3, 4]}}]",
     "scenarios[0].set: duration is swept (scenarios[0].sweep: duration)", "leave one"),
    ("scenarios: [{path: FORKLIFT, set: {robots.nobody.speed: 1}}]",
     "scenarios[0].set: robots.nobody", "no list"),
])
def test_suite_file_errors(tmp_path: Path, body: str, field: str, words: str) -> None:
    p = _suite(tmp_path, body)
    with pytest.raises(SrrError) as err:
        plan_suite([p])  # what `srr suite` checks before anything runs
    assert field in str(err.value) and words in str(err.value)
    assert "--set" not in str(err.value)  # the suite file is named, not the command line
    assert "\n" not in str(err.value)


def _with_includes(tmp_path: Path) -> None:
    shutil.copytree(ROOT / "scenarios" / "forklift", tmp_path / "forklift")


def test_folder_takes_scenarios_only(tmp_path: Path) -> None:
    _with_includes(tmp_path)
    (tmp_path / "a.yaml").write_text(FORKLIFT.read_text(encoding="utf-8"), encoding="utf-8")
    (tmp_path / "fragment.yaml").write_text("robots: []\n", encoding="utf-8")
    (tmp_path / "suite.yaml").write_text(f"scenarios: [{FORKLIFT}]\n", encoding="utf-8")
    spec = load_suite([tmp_path])
    assert [e.name for e in spec.entries] == ["forklift_warehouse"]
    (tmp_path / "empty").mkdir()
    with pytest.raises(SrrError, match="no scenario files"):
        load_suite([tmp_path / "empty"])


def test_scenario_declares_its_own_sweep(tmp_path: Path) -> None:
    _with_includes(tmp_path)
    sc = tmp_path / "sw.yaml"
    sc.write_text(FORKLIFT.read_text(encoding="utf-8")
                  + "\nsweep:\n  seed: {from: 1, to: 3, step: 1}\n", encoding="utf-8")
    runs = plan_runs(load_suite([sc]))
    assert [r.group for r in runs] == [f"forklift_warehouse[seed={i}]" for i in (1, 2, 3)]
    sc.write_text(FORKLIFT.read_text(encoding="utf-8") + "\nsweep: {seed: [1, -2]}\n",
                  encoding="utf-8")
    with pytest.raises(ScenarioError) as err:
        plan_runs(load_suite([sc]))
    assert str(sc) in str(err.value) and "seed=-2" in str(err.value)


def test_stats_known_values() -> None:
    d = describe([1.0, 2.0, 3.0])
    assert d is not None
    assert (d.n, d.mean, d.std, d.min, d.max) == (3, 2.0, 1.0, 1.0, 3.0)
    assert d.ci95 is not None
    assert math.isclose(d.ci95[1] - 2.0, 4.302652729911275 / math.sqrt(3), rel_tol=1e-9)
    one = describe([5.0])
    assert one is not None and one.std == 0.0 and one.ci95 is None
    assert describe([]) is None


@pytest.mark.parametrize("n", [2, 3, 7, 30, 200])
def test_stats_ci_is_scipy_students_t_interval(n: int) -> None:
    """The 95 % interval is Student's t interval, bit for bit what scipy.stats gives (the
    quantile comes from scipy.special, which imports in a sixth of the time)."""
    from scipy import stats

    xs = [float((i * 7919) % 101) / 10.0 for i in range(n)]
    d = describe(xs)
    assert d is not None and d.ci95 is not None
    lo, hi = stats.t.interval(0.95, n - 1, loc=d.mean, scale=d.std / math.sqrt(n))
    half = float(stats.t.ppf(0.975, n - 1)) * d.std / math.sqrt(n)
    assert d.ci95 == (d.mean - half, d.mean + half)
    assert math.isclose(d.ci95[0], lo, rel_tol=1e-12) and math.isclose(d.ci95[1], hi,
                                                                      rel_tol=1e-12)


def test_srr_validate_checks_a_suite_file_and_a_folder_without_running(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """``srr validate`` on a suite file (or a folder of scenarios) checks what ``srr suite``
    checks before its first run, every entry and sweep point, and runs nothing."""
    from harness.cli import main

    monkeypatch.chdir(tmp_path)

    nightly = ROOT / "scenarios" / "suites" / "nightly.yaml"
    assert main(["validate", str(nightly)]) == 0
    out = capsys.readouterr().out
    assert f"{nightly}: ok — suite nightly: 10 scenario entries, 14 groups, 23 runs" in out
    (tmp_path / "hall.yaml").write_text(
        "format_version: 1\nname: hall\nduration: 0.25\n"
        "world: {size: [30.0, 20.0], shelves: [], dock: {enabled: false}}\n")
    assert main(["validate", str(tmp_path)]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == f"{tmp_path}: ok — 1 file(s)"
    bad = tmp_path / "suite.yaml"
    bad.write_text("suite: s\nscenarios:\n  - {path: hall.yaml, sweep: {duration: [0.25, -1]}}\n")
    assert main(["validate", str(bad)]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert err.startswith("srr validate: ") and "duration" in err and "Traceback" not in err
    assert main(["validate", str(nightly), "--set", "duration=3"]) == 2
    assert "is a suite; a suite changes its scenarios with `set:`" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["hall.yaml", "suite.yaml"]  # no output


def test_srr_validate_checks_every_file_of_a_folder(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``srr validate FOLDER`` checks every scenario and suite file in it, each as ``srr
    validate FILE`` would, and says which failed: one line each, a summary, exit 2. It
    stopped at the first bad file, so a second one went unseen."""
    from harness.cli import main

    hall = ("format_version: 1\nname: {name}\nduration: {duration}\n"
            "world: {{size: [30.0, 20.0], shelves: [], dock: {{enabled: false}}}}\n")
    (tmp_path / "a_bad.yaml").write_text(hall.format(name="a", duration=-1))
    (tmp_path / "b_hall.yaml").write_text(hall.format(name="hall", duration=0.25))
    (tmp_path / "c_broken.yml").write_text("name: [unclosed\n")
    (tmp_path / "d_suite.yaml").write_text("suite: s\nscenarios:\n  - {path: b_hall.yaml}\n")
    (tmp_path / "e_fragment.yaml").write_text("robots: []\n")  # included by scenarios
    (tmp_path / "f_bad_suite.yaml").write_text("scenarios:\n  - {path: nowhere.yaml}\n")
    assert main(["validate", str(tmp_path)]) == 2
    out, err = capsys.readouterr()
    bad = err.splitlines()
    assert len(bad) == 3, err
    assert bad[0].startswith(f"srr validate: {tmp_path / 'a_bad.yaml'}: duration: "), bad
    assert bad[1].startswith(f"srr validate: {tmp_path / 'c_broken.yml'}: YAML syntax error"), bad
    assert bad[2].startswith("srr validate: ") and "nowhere.yaml" in bad[2], bad
    assert f"{tmp_path / 'b_hall.yaml'}: ok — hall" in out
    assert f"{tmp_path / 'd_suite.yaml'}: ok — suite s: 1 scenario entries" in out
    assert out.splitlines()[-1] == f"{tmp_path}: 3 of 5 file(s) failed"
    for name in ("a_bad.yaml", "c_broken.yml", "f_bad_suite.yaml"):
        (tmp_path / name).unlink()
    (tmp_path / "g_twin.yaml").write_text(hall.format(name="hall", duration=0.5))
    assert main(["validate", str(tmp_path)]) == 2  # each is fine, the folder is not
    out, err = capsys.readouterr()
    assert "'hall' is already used by" in err and len(err.splitlines()) == 1, err
    assert out.splitlines()[-1] == f"{tmp_path}: 1 of 3 file(s) failed"
    (tmp_path / "g_twin.yaml").unlink()
    assert main(["validate", str(tmp_path)]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == f"{tmp_path}: ok — 2 file(s)"


def test_every_sweep_point_sets_its_systems_under_test_up_before_the_suite(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A plug-in parameter is read in set-up: a bad value at any sweep point (not only the
    first) stops ``srr validate`` and ``srr suite`` before a run, naming the point."""
    from harness.cli import main

    _with_includes(tmp_path)
    speed = "systems_under_test.route_follower.params.speed"
    suite = tmp_path / "suite.yaml"
    suite.write_text(f"scenarios:\n  - path: {FORKLIFT}\n    sweep: {{{speed}: [0.2, -1]}}\n",
                     encoding="utf-8")
    with pytest.raises(SrrError) as info:
        plan_suite([suite])
    assert str(info.value).startswith(
        f"{suite}: scenarios[0] [speed=-1]: systems_under_test[0].params.speed: must be > 0")
    own = tmp_path / "sw.yaml"  # the scenario's own sweep, validated on its own
    own.write_text(FORKLIFT.read_text(encoding="utf-8") + f"\nsweep: {{{speed}: [0.2, -1]}}\n",
                   encoding="utf-8")
    assert main(["validate", str(own)]) == 2
    assert f"{own} [speed=-1]: systems_under_test[0].params.speed: " in capsys.readouterr().err


@pytest.mark.parametrize(("value", "said"), [
    ("{duraton: 2}", "duraton: unknown field (did you mean 'duration'?)"),
    ("{duration: -2}", "duration: must be > 0, got -2"),
])
def test_a_bad_set_value_is_the_suite_files(tmp_path: Path, value: str, said: str) -> None:
    """A value an entry's ``set:`` gave is named in the suite file, not in the scenario file
    the loader found it wrong in."""
    _with_includes(tmp_path)
    suite = tmp_path / "suite.yaml"
    suite.write_text(f"scenarios:\n  - path: {FORKLIFT}\n    set: {value}\n", encoding="utf-8")
    with pytest.raises(ScenarioError) as err:
        load_suite([suite])
    assert str(err.value) == f"{suite}: scenarios[0].set: {said}"


@pytest.mark.parametrize("order", [[-12, -6], [-6, -12]])
def test_every_sweep_point_that_moves_a_robot_is_checked_in_its_scene(
        tmp_path: Path, order: list[int]) -> None:
    """A sweep over a robot's spawn: the point in a shelf is refused before anything runs,
    whichever place it has (only the first point's world was built: later ones became INVALID
    runs), and the error names the suite file's entry and the point, not ``--set``."""
    forklift = Path(__file__).resolve().parents[2] / "scenarios" / "forklift_warehouse.yaml"
    suite = tmp_path / "mix.yaml"
    suite.write_text(f"""
suite: mix
scenarios:
  - path: {forklift}
    set: {{duration: 2, robots.0.spawn.position: [-12, -6, 0]}}
    sweep: {{robots.0.spawn.position.0: {order}}}
""", encoding="utf-8")
    with pytest.raises(SrrError) as info:
        plan_suite([suite])
    said = str(info.value)
    assert said.startswith(f"{suite}: scenarios[0] [position.0=-6]: robots[0].spawn.position: "
                           "robot forklift at (-6, -6, 0) starts inside shelf 2"), said
    assert "--set" not in said


def test_a_folder_says_how_many_files_fail_and_whose_include_is_bad(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``srr suite FOLDER`` names the first bad file and counts the others (it stopped at
    the first); ``srr validate FOLDER`` names the scenario whose include is bad, not only
    the include."""
    from harness.cli import main

    (tmp_path / "a.yaml").write_text("format_version: 1\nname: a\nrobots: [\n")
    (tmp_path / "b.yaml").write_text("format_version: 1\nname: b\nrobots: 5\n")
    (tmp_path / "inc.yml").write_text("duration: -1\n")  # a fragment: no name
    (tmp_path / "c.yaml").write_text("format_version: 1\nname: c\ninclude: [inc.yml]\n")
    with pytest.raises(SrrError) as info:
        load_suite([tmp_path])
    said = str(info.value)
    assert said.startswith(f"{tmp_path / 'a.yaml'}: ") and said.endswith(
        f"(and 2 more file(s) of {tmp_path} that do not load: `srr validate {tmp_path}` "
        "says each)"), said
    assert main(["validate", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f"srr validate: {tmp_path / 'c.yaml'}: " in err and "inc.yml" in err, err


DOCK_CROSSING = ROOT / "scenarios" / "dock_worker_crossing.yaml"


def test_a_later_sweep_point_s_warnings_are_said_with_its_label(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Only the first point was validated in full: a warning that only a later point gives
    (a worker that starts after the run ends) was not said before the run; it is now, naming
    the entry and the point, in the suite and in the scenario's own sweep."""
    suite = tmp_path / "sw.yaml"
    suite.write_text(f"suite: sw\nscenarios:\n  - path: {DOCK_CROSSING}\n"
                     "    sweep: {workers.0.start_delay: [22, 40]}\n", encoding="utf-8")
    said = ("workers[0].start_delay: 40 s is not before the end of the run (duration 36 s): "
            "worker 'character_0' stands at its first waypoint the whole run")
    assert plan_suite([suite]).warnings == (f"{suite}: scenarios[0] [start_delay=40]: {said}",)
    own = tmp_path / "dock_worker_crossing.yaml"
    shutil.copytree(ROOT / "scenarios" / "dock", tmp_path / "dock")
    own.write_text(DOCK_CROSSING.read_text(encoding="utf-8")
                   + "\nsweep: {workers.0.start_delay: [22, 40]}\n", encoding="utf-8")
    assert main(["validate", str(own)]) == 0
    err = capsys.readouterr().err
    assert f"srr validate: warning: {own} [start_delay=40]: {said}" in err
    assert "start_delay=22" not in err


def test_a_later_sweep_point_s_waypoint_in_a_shelf_is_refused_before_any_run(
        tmp_path: Path) -> None:
    suite = tmp_path / "sw.yaml"
    suite.write_text(f"suite: sw\nscenarios:\n  - path: {DOCK_CROSSING}\n"
                     "    sweep: {workers.0.route.0.0: [12, -6]}\n", encoding="utf-8")
    with pytest.raises(SrrError) as info:
        plan_suite([suite])
    assert str(info.value).startswith(f"{suite}: scenarios[0] [route.0.0=-6]: ")
    assert "workers[0].route[0]: (-6, -5.5) is inside the shelf at (-6, -6)" in str(info.value)


@pytest.mark.slow
def test_planning_a_suite_loads_each_scenario_configuration_once(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Learning an entry's name, planning its runs, checking it and finding its baseline
    file each used to load its scenario again (four loads of each, half of the planning)."""
    import json

    import harness.scenario.loader as loader

    loaded: list[str] = []
    made = loader.scenario_from_mapping

    def counted(data: dict[str, object], shown: str, *rest: object) -> object:
        loaded.append(shown + json.dumps(data, sort_keys=True, default=str))
        return made(data, shown, *rest)  # type: ignore[arg-type]

    monkeypatch.setattr(loader, "scenario_from_mapping", counted)
    plan = plan_suite([ROOT / "scenarios" / "suites" / "nightly.yaml"])
    assert len(plan.runs) == 23 and len(loaded) >= 14  # every entry and sweep point
    twice = sorted({k[:80] for k in loaded if loaded.count(k) > 1})
    assert not twice, twice
