"""Pull-request summaries of a suite: built from the groups the suite judged (the suite's own
grouping, statistics, flakiness and exit code, run here on the outcomes of a regressed group
of three repeats, a flaky pair, a crashed run and a passing one), escaped, ordered and capped;
and the command-line options' checks, made before anything runs."""

from __future__ import annotations

import re
import shutil
from dataclasses import replace
from pathlib import Path
from typing import Any

from harness.cli import main
from harness.report.markdown import cap, cell, code, join_link
from harness.suite.markdown import suite_markdown, write_markdown
from harness.suite.plan import RunSpec
from harness.suite.results import GROUP_ORDER, RunOutcome, group_runs, suite_exit_code
from harness.suite.runner import SuiteResult

ROOT = Path(__file__).resolve().parents[2]
METRIC = "perception.recall"


def _spec(entry: str, repeat: int, repeats: int) -> RunSpec:
    return RunSpec(id=f"{entry}#{repeat}", group=entry, entry=entry, scenario=entry,
                   scenario_file=f"scenarios/{entry}.yaml", overrides=(), params=(),
                   sweep=False, repeat=repeat, repeats=repeats, timeout_s=None,
                   run_dir=f"runs/{entry}/nominal/r{repeat}", renders=False)


def _run(entry: str, repeat: int, repeats: int, verdict: str, *, value: float | None = None,
         status: str = "ok", digest: str | None = "d" * 64, crash: str | None = None,
         reasons: tuple[str, ...] = ()) -> RunOutcome:
    spec = _spec(entry, repeat, repeats)
    metrics = () if value is None else ({"name": METRIC, "value": value, "unit": "ratio",
                                         "direction": "higher", "group": "perception"},)
    comparison = () if value is None else ({"name": METRIC, "value": value, "baseline": 0.95,
                                            "tolerance": 0.05, "delta": value - 0.95,
                                            "status": status, "unit": "ratio"},)
    report = None if crash else f"{spec.run_dir}/report.html"
    return RunOutcome(spec=spec, verdict=verdict, exit_code={"PASS": 0, "INVALID": 3}.get(
        verdict, 1), reasons=reasons, wall_s=1.0, run_dir=None if crash else spec.run_dir,
        report=report, log=f"logs/{entry}_r{repeat}.log", digest=None if crash else digest,
        crash=crash, metrics=metrics, comparison=comparison)


def _suite(tmp_path: Path, outcomes: list[RunOutcome], name: str = "pr") -> SuiteResult:
    """What run_suite keeps of a finished suite: the judged groups, worst first, and their
    exit code."""
    groups = group_runs(outcomes, tmp_path)
    ranked = tuple(sorted(groups, key=lambda g: GROUP_ORDER.index(g.verdict)))
    code_ = suite_exit_code(groups, interrupted=False)
    summary: dict[str, Any] = {"name": name, "wall_s": 12.5, "executor": "local", "jobs": 2,
                               "interrupted": False}
    return SuiteResult(tmp_path, ranked[0].verdict, code_, summary, ranked)


def _mixed(tmp_path: Path) -> SuiteResult:
    bad = "reduced | `range`"  # a pipe and backticks in a reason and in a name
    return _suite(tmp_path, [
        *(_run("short_range", k, 3, "REGRESSED", value=v, status="regressed",
               reasons=(f"{METRIC}: {bad}",)) for k, v in ((1, 0.70), (2, 0.72), (3, 0.74))),
        _run("flaky|pid", 1, 2, "PASS", value=0.96),
        _run("flaky|pid", 2, 2, "FAIL", value=0.96, reasons=("control.goal_reached: no",)),
        _run("segfault", 1, 1, "INVALID",
             crash="killed by signal SIGSEGV (a segmentation fault)",
             reasons=("the worker crashed: killed by signal SIGSEGV (a segmentation fault)",)),
        _run("nominal", 1, 1, "PASS", value=0.96),
    ])


def _table(md: str, heading: str) -> list[list[str]]:
    """The rows of the table under ``### heading``, split on unescaped pipes."""
    section = md.split(f"### {heading}\n\n", 1)[1].split("\n\n", 1)[0].splitlines()
    return [[c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]] for line in section[2:]]


def test_a_suite_with_a_regression_a_flaky_pair_and_a_crash(tmp_path: Path) -> None:
    res = _mixed(tmp_path)
    assert (res.verdict, res.exit_code) == ("INVALID", 3)
    md = suite_markdown(res, link_base="https://ci.example/run/7")
    first = md.splitlines()[0]
    assert first == "## 💥 srr suite `pr`: **INVALID** (exit code 3)"
    assert ("**4 group(s), 7 run(s)** in 12.5 s on local × 2: 1 INVALID · 1 FLAKY · "
            "1 REGRESSED · 1 PASS") in md
    # the groups that did not pass, worst first, with their first reason and reports
    rows = _table(md, "Groups that did not pass")
    assert [(r[0], r[1], r[2]) for r in rows] == [
        ("💥 INVALID", "`segfault`", "1"), ("🎲 FLAKY", "`flaky\\|pid`", "2"),
        ("❌ REGRESSED", "`short_range`", "3")]
    assert rows[2][3] == "\\#1: perception.recall: reduced \\| \\`range\\`"
    assert rows[2][4] == ("[#1](https://ci.example/run/7/runs/short_range/nominal/r1/report.html)"
                          " [#2](https://ci.example/run/7/runs/short_range/nominal/r2/report.html)"
                          " [#3](https://ci.example/run/7/runs/short_range/nominal/r3/report.html)")
    # the regressed metric: mean 0.72 of three repeats, sample std 0.02, t(0.975, 2) = 4.303
    # → 95 % interval 0.72 ± 0.0497; delta from the baseline 0.95
    (reg,) = _table(md, "Regressed metrics")
    assert reg == ["`short_range`", f"`{METRIC}`", "0.72 ratio", "[0.6703, 0.7697]", "0.95",
                   "-0.23", "±0.05", "3", "regressed"]
    (flaky,) = _table(md, "Flaky groups")
    assert flaky[:4] == ["`flaky\\|pid`", "PASS / FAIL", "—", "—"]
    (crash,) = _table(md, "Crashed, timed-out and invalid runs")
    assert crash == ["`segfault#1`", "crashed", "the worker crashed: killed by signal SIGSEGV "
                     "(a segmentation fault)", "[log](https://ci.example/run/7/logs/segfault_r1.log)",
                     "—"]
    assert "<details><summary>1 group(s) passed</summary>" in md
    assert "[index.html](https://ci.example/run/7/index.html)" in md
    # nothing in it breaks a table: every table row has its header's number of cells
    for heading in ("Groups that did not pass", "Regressed metrics", "Flaky groups",
                    "Crashed, timed-out and invalid runs"):
        text = md.split(f"### {heading}\n\n", 1)[1].split("\n\n", 1)[0].splitlines()
        widths = {len(re.split(r"(?<!\\)\|", line)) for line in text}
        assert len(widths) == 1, (heading, text)


def test_the_headline_follows_the_exit_code(tmp_path: Path) -> None:
    ok = _suite(tmp_path, [_run("nominal", 1, 1, "PASS", value=0.96)], name="ok")
    assert ok.exit_code == 0
    md = suite_markdown(ok)
    assert md.startswith("## ✅ srr suite `ok`: **PASS** (exit code 0)\n")
    assert "### " not in md  # nothing to act on
    regressed = _suite(tmp_path, [_run("a", 1, 1, "REGRESSED", value=0.5, status="regressed"),
                                  _run("b", 1, 1, "PASS", value=0.96)], name="r")
    assert regressed.exit_code == 1
    assert suite_markdown(regressed).startswith("## ❌ srr suite `r`: **REGRESSED** (exit code 1)")


def test_the_same_result_gives_the_same_text(tmp_path: Path) -> None:
    assert suite_markdown(_mixed(tmp_path)) == suite_markdown(_mixed(tmp_path))


def test_links_default_to_the_suite_folder_relative_to_the_file(tmp_path: Path) -> None:
    out = tmp_path / "suite"
    out.mkdir()
    res = _suite(out, [_run("a", 1, 1, "PASS", value=0.96)])
    inside = write_markdown(res, out / "pr.md").read_text(encoding="utf-8")
    assert "[report](runs/a/nominal/r1/report.html)" in inside
    beside = write_markdown(res, tmp_path / "pr.md").read_text(encoding="utf-8")
    assert "[report](suite/runs/a/nominal/r1/report.html)" in beside
    odd = tmp_path / "d e#f"  # a folder name is no URL: its '#' is not a fragment
    odd.mkdir()
    res = _suite(odd, [_run("a", 1, 1, "PASS", value=0.96)])
    beside = write_markdown(res, tmp_path / "pr.md").read_text(encoding="utf-8")
    assert "[report](d%20e%23f/runs/a/nominal/r1/report.html)" in beside
    assert join_link("https://github.com/o/r/actions/runs/1#", "index.html") == (
        "https://github.com/o/r/actions/runs/1#index.html")


def test_a_long_summary_is_cut_at_a_line_and_says_so(tmp_path: Path) -> None:
    outcomes = [_run(f"scenario_{k:03d}", 1, 1, "REGRESSED", value=0.5, status="regressed",
                     reasons=("x" * 250,)) for k in range(400)]
    res = _suite(tmp_path, outcomes)
    full = suite_markdown(res, limit=10**8)
    assert len(full.encode()) > 65536
    md = suite_markdown(res)
    # room for a comment action's marker within GitHub's 65,536 characters
    assert 64000 < len(md.encode()) <= 64512 and len(md) <= 64512
    assert full.startswith(md.rsplit("\n*… truncated", 1)[0])
    left = len(full.splitlines()) - len(md.rsplit("\n*… truncated", 1)[0].splitlines()) - 1
    # (the last line, the links to the whole results, is kept)
    assert md.endswith(f"*… truncated: {left} more line(s) left out to stay within 64512 bytes "
                       "(the full results are in the suite's summary.json and reports).*\n"
                       "\nSuite page: [index.html](index.html) · [summary.json](summary.json) "
                       "· [junit.xml](junit.xml)\n")
    assert cap(["a", "b"], 100) == "a\nb\n"
    # cut inside a folded block: the block is closed, so the note and the links show
    folded = cap(["<details><summary>x</summary>", "", *["row"] * 50, "</details>"], 200,
                 last="links")
    assert folded.count("<details>") == folded.count("</details>") == 1
    assert folded.endswith("reports).*\n\nlinks\n") and len(folded.encode()) <= 200


def test_cells_and_code_spans_cannot_break_out() -> None:
    assert cell("a|b `c` <img src=x>\n*d*") == "a\\|b \\`c\\` &lt;img src=x&gt; \\*d\\*"
    assert code("x`y|z") == "``x`y\\|z``"
    assert code("`edge") == "`` `edge ``"
    assert cell("y" * 500, 10) == "y" * 9 + "…"


def test_bad_summary_options_are_one_line_exit_2_before_anything_runs(
        tmp_path: Path, capsys: Any) -> None:
    suite = tmp_path / "missing.yaml"  # never read: the options are checked first
    assert main(["suite", str(suite), "--summary-md", str(tmp_path / "no" / "pr.md")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--summary-md" in err and "does not exist" in err
    assert main(["suite", str(suite), "--summary-link-base", "https://x"]) == 2
    assert "--summary-link-base: only with --summary-md" in capsys.readouterr().err
    assert main(["suite", str(suite), "--summary-md", str(tmp_path / "pr.md"),
                 "--summary-link-base", ""]) == 2  # links that would point nowhere
    assert "--summary-link-base: empty" in capsys.readouterr().err
    assert main(["run", str(suite), "--summary-md", str(tmp_path / "pr.md"),
                 "--repeat", "2"]) == 2
    assert "--summary-md: one run" in capsys.readouterr().err
    assert not (tmp_path / "pr.md").exists()
    for command in ("run", "suite"):  # never over a file of the run's or the suite's own
        out = tmp_path / "out"
        assert main([command, str(suite), "--out", str(out), "--summary-md",
                     str(out / "summary.json")]) == 2
        assert f"--summary-md {out / 'summary.json'}: inside --out {out}" in \
            capsys.readouterr().err


def test_a_summary_over_a_file_the_command_reads_is_refused(tmp_path: Path,
                                                           capsys: Any) -> None:
    """--summary-md naming the suite file, a scenario an entry runs, or `srr run`'s scenario
    (given another way than the entry wrote it) would replace it: one line, exit 2, the file
    as it was."""
    scenario = tmp_path / "forklift.yaml"
    shutil.copytree(ROOT / "scenarios" / "forklift", tmp_path / "forklift")
    scenario.write_text((ROOT / "scenarios" / "forklift_warehouse.yaml").read_text(
        encoding="utf-8"), encoding="utf-8")
    (tmp_path / "suites").mkdir()
    suite = tmp_path / "suites" / "s.yaml"
    suite.write_text("suite: s\nscenarios: [../forklift.yaml]\n", encoding="utf-8")
    before = {p: p.read_bytes() for p in (scenario, suite)}
    for argv, target in ((["suite", str(suite)], suite), (["suite", str(suite)], scenario),
                         (["run", str(tmp_path / "suites" / ".." / "forklift.yaml")],
                          scenario)):
        out = tmp_path / "out"
        assert main([*argv, "--out", str(out), "--summary-md", str(target)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"--summary-md {target}: is " in err, err
        assert "a file this command reads" in err and not out.exists()
    assert {p: p.read_bytes() for p in (scenario, suite)} == before


def test_groups_whose_bytes_are_not_their_baselines_are_listed_folded(tmp_path: Path) -> None:
    """A group whose metrics held but whose recording is not byte for byte its baseline's is
    listed, folded away, with the topics and versions that differ; one whose bytes match,
    a flaky one (its repeats disagree anyway), a MISMATCH (its metrics were not judged) and
    one without a baseline are not."""
    drift = {"digest_matches": False, "topics_differing": ["/cam_rgb", "/cam_depth"],
             "versions_differing": {"gl_renderer": {"baseline": "llvmpipe", "run": "NVIDIA"}}}
    same = {"digest_matches": True, "topics_differing": [], "versions_differing": {}}
    outcomes = [
        replace(_run("camera_scene", 1, 1, "PASS", value=0.96), against_baseline=drift),
        replace(_run("forklift", 1, 1, "PASS", value=0.96), against_baseline=same),
        replace(_run("other_config", 1, 1, "MISMATCH", value=0.96), against_baseline=drift),
        replace(_run("wobbly", 1, 2, "PASS", value=0.96), against_baseline=drift),
        replace(_run("wobbly", 2, 2, "FAIL", value=0.96, digest="e" * 64),
                against_baseline=drift),
        _run("no_baseline", 1, 1, "PASS", value=0.96),
    ]
    res = _suite(tmp_path, outcomes)
    md = suite_markdown(res)
    head = "<details><summary>1 group(s) recorded other bytes than their baselines</summary>"
    assert head in md
    rows = md.split(head, 1)[1].split("</details>", 1)[0].strip().splitlines()[2:]
    assert rows == ["| `camera_scene` | PASS | 2: `/cam_rgb`, `/cam_depth` | gl\\_renderer "
                    "llvmpipe → NVIDIA | [report](runs/camera_scene/nominal/r1/report.html) |"]
    by_id = {g.id: g.to_json() for g in res.groups}
    assert by_id["camera_scene"]["against_baseline"] == drift
    assert by_id["no_baseline"]["against_baseline"] is None
    assert [r.to_json()["recording_matches_baseline"] for r in outcomes] == [
        False, True, False, False, False, None]
    assert "recorded other bytes" not in suite_markdown(_suite(tmp_path, outcomes[1:2]))
