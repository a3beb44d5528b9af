"""The pull-request workflow and its quick suite: the suite plans with a baseline for every
group; the workflow's srr command parses as srr parses it and writes the summary that the job
summary and the one sticky comment show; forks (a read-only token) get no comment step."""

from __future__ import annotations

import shlex
from pathlib import Path
from typing import Any

import yaml

from harness.cli import _parser
from harness.regression.store import baseline_path
from harness.suite.runner import plan_suite

ROOT = Path(__file__).resolve().parents[2]
PR_SUITE = ROOT / "scenarios" / "suites" / "pr.yaml"
WORKFLOW = ROOT / ".github" / "workflows" / "pr.yml"


def _job() -> tuple[dict[str, Any], dict[str, Any]]:
    wf = yaml.safe_load(WORKFLOW.read_text(encoding="utf-8"))
    return wf, wf["jobs"]["quick-suite"]


def _step(steps: list[dict[str, Any]], pred: Any) -> dict[str, Any]:
    (found,) = [s for s in steps if pred(s)]
    return found


def test_the_quick_suite_has_a_baseline_for_every_group() -> None:
    plan = plan_suite([PR_SUITE])
    groups = {r.group: r for r in plan.runs}
    assert len(groups) == 4 and len(plan.runs) == 8  # two repeats each: flaky shows
    for spec in groups.values():
        assert baseline_path(spec.scenario, ROOT / "baselines").is_file(), spec.group
    assert any(r.renders for r in plan.runs)  # the cameras are in it


def test_the_workflow_runs_the_quick_suite_and_shows_its_summary() -> None:
    wf, job = _job()
    assert set(wf[True]) == {"pull_request"}  # PyYAML reads `on:` as True
    assert wf["permissions"]["pull-requests"] == "write"
    steps = job["steps"]
    env = job["env"]
    suite = _step(steps, lambda s: ".venv/bin/srr suite" in s.get("run", ""))
    line = next(x for x in suite["run"].splitlines() if "srr suite" in x)
    words = shlex.split(line.replace("\\\n", " "))
    words = [w.replace("$(nproc)", "2") for w in words]
    for name, value in env.items():
        words = [w.replace(f"${name}", str(value)) for w in words]
    assert words[0] == ".venv/bin/srr"
    args = _parser().parse_args(words[1:])  # srr's own parser: the options exist
    assert args.command == "suite"
    assert [(ROOT / p).resolve() for p in args.paths] == [PR_SUITE]
    assert str(args.out) == env["OUT"] and str(args.summary_md) == env["SUMMARY"]
    assert args.summary_link_base.endswith("/actions/runs/${{ github.run_id }}#")
    # the suite's exit code is kept for the last step, which fails the job unless it is 0
    assert 'echo "exit_code=$code" >> "$GITHUB_OUTPUT"' in suite["run"]
    assert 'test "$code" = 0' in steps[-1]["run"]
    # the job summary: the same file, appended to $GITHUB_STEP_SUMMARY, always
    summary = _step(steps, lambda s: "GITHUB_STEP_SUMMARY" in s.get("run", ""))
    assert summary["if"] == "always()"
    assert 'cat "$SUMMARY" >> "$GITHUB_STEP_SUMMARY"' in summary["run"]
    upload = _step(steps, lambda s: s.get("uses", "").startswith("actions/upload-artifact@"))
    assert upload["with"]["path"] == "${{ env.OUT }}" and upload["if"] == "always()"
    # one comment, updated: a maintained action, the same file, never for a fork's token
    comment = _step(steps, lambda s: "sticky-pull-request-comment" in s.get("uses", ""))
    assert comment["uses"].startswith("marocchino/sticky-pull-request-comment@v2")
    assert comment["with"]["path"] == "${{ env.SUMMARY }}" and comment["with"]["header"]
    assert ("github.event.pull_request.head.repo.full_name == github.repository"
            in comment["if"])
    assert f"hashFiles('{env['SUMMARY']}')" in comment["if"]
    # every action is pinned to a major version
    assert all("@v" in s["uses"] for s in steps if "uses" in s)
