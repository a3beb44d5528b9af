"""What a run says of its bytes against the baseline's: identical, or which topics differ and
which versions it ran with that the baseline was not blessed with (the console line, the
summary's ``baseline`` entry, the Markdown summary and the report)."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

from harness.cli import main
from harness.run.judge import differing_topics, differing_versions
from harness.run.summary import TopicRow
from harness.summary import recording_note

ROOT = Path(__file__).resolve().parents[2]
FW = ROOT / "scenarios" / "forklift_warehouse.yaml"


def _edited_baseline(tmp_path: Path, topics: dict[str, dict[str, object]],
                     **fields: object) -> Path:
    """A copy of the shipped forklift baseline (and its reference recording) in a folder of
    its own, with these topics' entries and fields replaced and another combined digest."""
    data = json.loads((ROOT / "baselines" / "forklift_warehouse.json").read_text())
    data.update(fields, digest="0" * 64, topics={**data["topics"], **topics})
    bdir = tmp_path / "baselines"
    bdir.mkdir()
    (bdir / "forklift_warehouse.json").write_text(json.dumps(data))
    shutil.copy(ROOT / "baselines" / "forklift_warehouse.mcap", bdir)
    return bdir


def _row(sha: str) -> TopicRow:
    return TopicRow(type="std_msgs/msg/Bool", count=1, sha256=sha)


def test_topics_and_versions_that_differ() -> None:
    base = {"/a": {"sha256": "1"}, "/b": {"sha256": "2"}, "/gone": {"sha256": "3"}}
    run = {"/a": _row("1"), "/b": _row("X"), "/new": _row("4")}
    assert differing_topics(base, run) == ("/b", "/gone", "/new")
    assert differing_topics(base, {"/a": _row("1"), "/b": _row("2"), "/gone": _row("3")}) == ()
    assert differing_versions({"numpy": "2.4.6", "mujoco": "4.0.0", "old": "1"},
                              {"numpy": "2.5.2", "mujoco": "4.0.0", "new": "2"}) == {
        "numpy": {"baseline": "2.4.6", "run": "2.5.2"}}  # one side's alone: unknown


def test_the_note_names_the_topics_and_versions() -> None:
    topics = {t: {} for t in ("/a", "/b", "/c", "/d", "/e", *(f"/t{i}" for i in range(11)))}
    assert recording_note({"topics": topics}) is None  # no baseline
    assert recording_note({"topics": topics, "baseline": {"digest_matches": True}}) == \
        "recording identical to the baseline's"
    note = recording_note({"topics": topics, "baseline": {
        "digest_matches": False, "topics_differing": ["/a", "/b", "/c", "/d", "/e"],
        "versions_differing": {"numpy": {"baseline": "2.4.6", "run": "2.5.2"},
                               "gl": {"baseline": "", "run": "llvmpipe"}}}})
    assert note == ("recording differs from the baseline's in 5 of 16 topics "
                    "(/a, /b, /c, /d, …); versions differ: numpy 2.4.6 → 2.5.2, gl — → llvmpipe")
    # a topic only the baseline recorded differs too, and counts among the topics: it said
    # "in 17 of 16 topics"
    note = recording_note({"topics": topics, "baseline": {
        "digest_matches": False, "topics_differing": ["/a", "/ghost"]}})
    assert note == "recording differs from the baseline's in 2 of 17 topics (/a, /ghost)"
    # a baseline from before per-topic digests: the verdict on the bytes alone
    assert recording_note({"topics": topics, "baseline": {"digest_matches": False}}) == \
        "recording differs from the baseline's"
    # an interrupted run's shorter recording differs in every topic: it says why instead
    assert recording_note({"topics": topics, "interrupted": True, "baseline": {
        "digest_matches": False, "topics_differing": ["/a"]}}) == \
        "recording cut short (interrupted): not the baseline's"
    assert recording_note({"topics": topics, "stopped": "disk_space: ...", "baseline": {
        "digest_matches": False, "topics_differing": ["/a"]}}) == \
        "recording cut short (the run was stopped): not the baseline's"


@pytest.mark.slow
def test_a_run_says_which_topics_differ_from_its_baseline(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    shipped = json.loads((ROOT / "baselines" / "forklift_warehouse.json").read_text())
    bdir = _edited_baseline(tmp_path, {
        "/ghost": {"count": 1, "sha256": "0" * 64, "type": "std_msgs/msg/Bool"},
        "/odom": dict(shipped["topics"]["/odom"], sha256="f" * 64)},
        versions={**shipped["versions"], "numpy": "1.0.0"})

    for name, baselines in (("shipped", ROOT / "baselines"), ("edited", bdir)):
        code = main(["run", str(FW), "--out", str(tmp_path / name), "-q", "--no-video",
                     "--baselines", str(baselines), "--summary-md", str(tmp_path / f"{name}.md")])
        assert code == 0  # the metrics hold either way: the bytes are reported, not judged
    out = capsys.readouterr().out
    edited_run = json.loads((tmp_path / "edited" / "summary.json").read_text())
    b = edited_run["baseline"]
    assert b["digest_matches"] is False and b["topics_differing"] == ["/ghost", "/odom"]
    numpy = edited_run["versions"]["numpy"]
    assert b["versions_differing"] == {"numpy": {"baseline": "1.0.0", "run": numpy}}
    line = ("recording differs from the baseline's in 2 of 7 topics (/ghost, /odom); "
            f"versions differ: numpy 1.0.0 → {numpy}")
    assert line in out.splitlines()
    where = f"  where: srr diff {bdir / 'forklift_warehouse.json'} {tmp_path / 'edited'}"
    assert out.splitlines()[out.splitlines().index(line) + 1] == where
    assert line in (tmp_path / "edited.md").read_text()
    page = (tmp_path / "edited" / "report.html").read_text()
    assert "recording differs from the baseline&#39;s in 2 of 7 topics" in page
    assert (f'<dt>versions differing (baseline → run)</dt><dd class="mono">numpy 1.0.0 → '
            f'{numpy}</dd>') in page
    marks = dict(re.findall(r'<tr data-topic="([^"]+)">.*?<td class="vs-baseline">(\w+)</td>',
                            page, re.S))
    assert marks == {"/clock": "same", "/cmd_vel": "same", "/gt/forklift/tf": "same",
                     "/odom": "differs", "/tf": "same", "/tf_static": "same"}

    # the shipped baseline, recorded on another machine: byte for byte the same recording
    # wherever srr and MuJoCo are the versions it was blessed with
    run = json.loads((tmp_path / "shipped" / "summary.json").read_text())["baseline"]
    other = {k for k in run.get("versions_differing", {}) if k in ("srr", "mujoco")}
    if other:
        pytest.skip(f"the shipped baselines were blessed with other versions of {other}")
    assert run["digest_matches"] is True and "topics_differing" not in run
    assert "recording identical to the baseline's" in out.splitlines()


@pytest.mark.slow
def test_a_run_that_renders_names_its_opengl_renderer(tmp_path: Path) -> None:
    """Camera images are the OpenGL driver's: a run that rendered records which one drew
    them among its versions (a camera-free run has none to record)."""
    from harness.sim.render import gl_renderer_name

    main(["run", str(ROOT / "scenarios" / "dock_empty.yaml"), "--duration", "0.5",
          "--out", str(tmp_path / "dock"), "-q", "--no-video"])
    renderer = json.loads((tmp_path / "dock" / "summary.json").read_text())["versions"][
        "gl_renderer"]
    assert renderer and renderer.isprintable() and renderer == gl_renderer_name()
    main(["run", str(FW), "--duration", "0.5", "--out", str(tmp_path / "fw"), "-q"])
    assert "gl_renderer" not in json.loads((tmp_path / "fw" / "summary.json").read_text())[
        "versions"]


@pytest.mark.slow
def test_a_suite_names_the_groups_whose_recording_is_not_their_baselines(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    shipped = json.loads((ROOT / "baselines" / "forklift_warehouse.json").read_text())
    bdir = _edited_baseline(tmp_path, {"/tf": dict(shipped["topics"]["/tf"], sha256="e" * 64)})
    code = main(["suite", str(FW), "--jobs", "1", "-q", "--out", str(tmp_path / "s"),
                 "--baselines", str(bdir), "--summary-md", str(tmp_path / "s.md")])
    assert code == 0  # the metrics held
    assert ("recording: 1 group(s) recorded other bytes than their baselines (their metrics "
            "judged on their own): forklift_warehouse") in capsys.readouterr().out.splitlines()
    (group,) = json.loads((tmp_path / "s" / "summary.json").read_text())["groups"]
    assert group["against_baseline"]["topics_differing"] == ["/tf"]
    assert "1 group(s) recorded other bytes than their baselines" in \
        (tmp_path / "s.md").read_text()
