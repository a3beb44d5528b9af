"""Where a scenario's baseline lives is decided from the scenario file alone, the same from
any working directory, for run, bless and replay; every message names the absolute path."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from harness import api
from harness.cli import main
from tests.conftest import ROOT, SCENARIOS

FW = SCENARIOS / "forklift_warehouse.yaml"


def scene_copy(tmp_path: Path) -> Path:
    """The forklift scene in a folder of its own, in a project of its own (the ``.git``
    folder fences the search, so a stray ``baselines/`` above the test's folder is not seen)."""
    (tmp_path / ".git").mkdir()
    scene = tmp_path / "scene"
    scene.mkdir()
    shutil.copy(FW, scene / FW.name)
    shutil.copytree(SCENARIOS / "forklift", scene / "forklift")
    for cwd in ("a", "b"):
        (tmp_path / cwd).mkdir()
    return scene / FW.name


def summary(run: Path) -> dict[str, object]:
    data: dict[str, object] = json.loads((run / "summary.json").read_text())
    return data


@pytest.mark.slow
def test_bless_in_one_directory_and_run_in_another(tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    src = scene_copy(tmp_path)
    beside = tmp_path / "scene" / "baselines" / "forklift_warehouse.json"
    monkeypatch.chdir(tmp_path / "a")
    rel = str(Path("..") / "scene" / src.name)
    assert main(["run", rel, "--duration", "1", "--out", "r1", "-q"]) == 1
    first = summary(tmp_path / "a" / "r1")
    assert f"no baseline at {beside}: bless one" in " ".join(first["reasons"])  # type: ignore[arg-type]
    assert first["baselines_dir"] == str(beside.parent)
    # one second of a route: its goal not reached, blessed on purpose
    assert main(["baseline", "bless", "r1", "--reason", "the first second",
                 "--allow-failing"]) == 0
    assert beside.is_file() and not (tmp_path / "a" / "baselines").exists()

    monkeypatch.chdir(tmp_path / "b")
    main(["run", rel, "--duration", "1", "--out", "r2", "-q"])
    second = summary(tmp_path / "b" / "r2")
    assert second["baseline"]["path"] == str(beside)  # type: ignore[index]
    assert not any("no baseline" in r for r in second["reasons"])  # type: ignore[attr-defined]
    assert {e["status"] for e in second["comparison"]} == {"ok"}  # type: ignore[attr-defined]

    # a replay from a third directory is judged against the same baseline
    monkeypatch.chdir(tmp_path)
    rep = api.replay(tmp_path / "a" / "r1", out=tmp_path / "rep")
    assert rep.summary["baseline"]["path"] == str(beside)


@pytest.mark.slow
def test_the_baselines_field_is_relative_to_the_scenario_file(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    src = scene_copy(tmp_path)
    (tmp_path / "scene" / "baselines").mkdir()  # nearer, but the field says where
    text = src.read_text(encoding="utf-8")
    src.write_text(text + "\nbaselines: ../kept/baselines\n", encoding="utf-8")
    kept = tmp_path / "kept" / "baselines" / "forklift_warehouse.json"
    monkeypatch.chdir(tmp_path / "a")
    res = api.run_scenario(api.load(src, duration=1.0), source=str(src), out=Path("r1"),
                           update_baseline=True, update_reason="kept elsewhere",
                           allow_failing=True)  # one second: its route's goal not reached
    assert kept.is_file() and res.blessed == kept
    assert res.summary["baselines_dir"] == str(kept.parent)
    assert not any((tmp_path / "scene" / "baselines").iterdir())
    resolved = (tmp_path / "a" / "r1" / "scenario.yaml").read_text()  # absolute once resolved
    assert f"baselines: {kept.parent}\n" in resolved
    # --baselines still wins, resolved against the working directory
    monkeypatch.chdir(tmp_path / "b")
    path = api.bless(tmp_path / "a" / "r1", "explicit", baselines=Path("mine"),
                     allow_failing=True)  # a short run: its route's goal not reached
    assert path == tmp_path / "b" / "mine" / "forklift_warehouse.json" and path.is_file()


def test_the_nearest_baselines_folder_up_to_the_project_root(tmp_path: Path) -> None:
    deep = tmp_path / "proj" / "scenarios" / "nested"
    deep.mkdir(parents=True)
    (tmp_path / "baselines").mkdir()  # above the project root: never looked at
    (tmp_path / "proj" / "pyproject.toml").write_text("")
    src = str(deep / "s.yaml")
    assert api.baselines_dir(src) == deep / "baselines"  # none up to the root: beside it
    (tmp_path / "proj" / "baselines").mkdir()
    assert api.baselines_dir(src) == tmp_path / "proj" / "baselines"
    (deep / "baselines").mkdir()
    assert api.baselines_dir(src) == deep / "baselines"
    # the bundled layout: scenarios/ and its subfolders share the repository's baselines/
    for f in (FW, SCENARIOS / "regressions" / "dock_worker_crossing_short_range.yaml"):
        assert api.baselines_dir(str(f)) == ROOT / "baselines"


def test_relative_sources_resolve_the_same_from_any_directory(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(SCENARIOS)
    assert api.baselines_dir("forklift_warehouse.yaml") == ROOT / "baselines"
    monkeypatch.chdir(tmp_path)
    assert api.baselines_dir("<scenario>") == tmp_path / "baselines"  # not from a file


@pytest.mark.slow
def test_blessing_an_invalid_run_is_refused_as_bad_input(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "hall.yaml"
    src.write_text("format_version: 1\nname: hall\nduration: 0.25\nclock: {enabled: true}\n"
                   "world: {size: [30.0, 20.0], shelves: [], dock: {enabled: false}}\n")
    code = main(["run", str(src), "--out", str(tmp_path / "bad"), "-q",
                 "--set", "scoring.health.expected_rates={/clock: 1000}"])
    assert code == 3 and summary(tmp_path / "bad")["verdict"] == "INVALID"
    capsys.readouterr()
    code = main(["baseline", "bless", str(tmp_path / "bad"), "--reason", "no",
                 "--baselines", str(tmp_path / "bl")])
    err = capsys.readouterr().err
    assert code == 2
    line = " ".join(err.split())
    assert line.startswith(f"srr baseline bless: {tmp_path / 'bad'}: not blessed: the run is "
                           "INVALID (health topic_rate:/clock:")
    assert not (tmp_path / "bl").exists()


@pytest.mark.slow
def test_a_suite_blesses_beside_the_scenario_file(tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / ".git").mkdir()
    (tmp_path / "scene").mkdir()
    (tmp_path / "a").mkdir()
    (tmp_path / "scene" / "hall.yaml").write_text(
        "format_version: 1\nname: hall\nduration: 0.25\nclock: {enabled: true}\n"
        "world: {size: [30.0, 20.0], shelves: [], dock: {enabled: false}}\n")
    monkeypatch.chdir(tmp_path / "a")
    assert main(["suite", str(Path("..") / "scene" / "hall.yaml"), "--jobs", "1", "-q",
                 "--out", "suite", "--update-baselines", "--reason", "kept bags",
                 "--summary-md", "pr.md"]) == 1
    blessed = tmp_path / "scene" / "baselines" / "hall.json"
    assert blessed.is_file()
    assert not (tmp_path / "a" / "baselines").exists()
    # the outputs say so (the group, judged before, still reads "no baseline at ...")
    summary = json.loads((tmp_path / "a" / "suite" / "summary.json").read_text())
    assert summary["baselines_blessed"] == {"reason": "kept bags", "written": [str(blessed)],
                                            "unchanged": []}
    md = (tmp_path / "a" / "pr.md").read_text()
    assert "**Baselines blessed** (`--update-baselines`, reason: kept bags): 1 written" in md
    assert "- `hall.json`" in md


def test_a_baselines_path_that_is_a_file_is_refused(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "hall.yaml"
    src.write_text("format_version: 1\nname: hall\nduration: 0.25\n"
                   "world: {size: [30.0, 20.0], shelves: [], dock: {enabled: false}}\n"
                   "baselines: taken\n")
    (tmp_path / "taken").write_text("a file")
    assert main(["run", str(src), "--out", str(tmp_path / "r"), "-q"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert f"{src}: baselines: {tmp_path / 'taken'} is not a folder" in err
    assert not (tmp_path / "r").exists()  # refused before anything was written
    assert main(["run", str(src), "--out", str(tmp_path / "r"), "-q", "--baselines",
                 str(tmp_path / "taken")]) == 2
    assert f"--baselines: {tmp_path / 'taken'} is not a folder" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()
    assert main(["validate", str(src)]) == 2
    assert "baselines: " in capsys.readouterr().err


@pytest.mark.slow
def test_a_suite_rebless_rewrites_only_the_baselines_that_change(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--update-baselines`` over baselines that already hold what the runs recorded leaves
    their files as they are (no new date, reason or run directory to review); a scene that
    changed is blessed again."""
    (tmp_path / ".git").mkdir()
    hall = "format_version: 1\nname: {name}\nduration: {d}\nclock: {{enabled: true}}\n" \
        "world: {{size: [30.0, 20.0], shelves: [], dock: {{enabled: false}}}}\n"
    for name in ("hall", "yard"):
        (tmp_path / f"{name}.yaml").write_text(hall.format(name=name, d=0.25))

    def suite(out: str, reason: str) -> list[str]:
        main(["suite", str(tmp_path / "hall.yaml"), str(tmp_path / "yard.yaml"), "--jobs", "1",
              "-q", "--out", str(tmp_path / out), "--update-baselines", "--reason", reason])
        return capsys.readouterr().out.splitlines()

    suite("s1", "first")
    files = {n: (tmp_path / "baselines" / f"{n}.json").read_bytes() for n in ("hall", "yard")}
    assert all(b'"reason": "first"' in data for data in files.values())
    lines = suite("s2", "again")
    assert not [line for line in lines if line.startswith("blessed ")]
    assert "unchanged: 2 baseline(s) already hold what these runs recorded and scored (left as " \
        "they are): hall.json, yard.json" in lines
    assert {n: (tmp_path / "baselines" / f"{n}.json").read_bytes() for n in files} == files

    (tmp_path / "yard.yaml").write_text(hall.format(name="yard", d=0.5))  # another scene
    lines = suite("s3", "longer")
    assert f"blessed {tmp_path / 'baselines' / 'yard.json'}" in lines
    assert (tmp_path / "baselines" / "hall.json").read_bytes() == files["hall"]
    yard = json.loads((tmp_path / "baselines" / "yard.json").read_text())
    assert yard["reason"] == "longer" and yard["config"]["duration"] == 0.5


def test_a_baselines_field_a_set_gives_is_relative_to_the_scenario_file(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``--set baselines=DIR`` is relative to the scenario file it is set on, as the field
    written there is, not to the working directory (``--baselines`` is)."""
    from harness.run.baselines import baselines_dir

    src = scene_copy(tmp_path)
    monkeypatch.chdir(tmp_path / "a")
    sc = api.load(src, overrides=["baselines=kept"])
    assert baselines_dir(str(src), None, sc) == tmp_path / "scene" / "kept"
