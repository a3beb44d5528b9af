"""The bundled nightly suite and its workflow: what CI runs every night must plan, find a
baseline for every group, start costliest first, and install the way the README says."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import yaml

from harness.regression.store import baseline_path
from harness.suite.runner import plan_suite

ROOT = Path(__file__).resolve().parents[2]
NIGHTLY = ROOT / "scenarios" / "suites" / "nightly.yaml"
WORKFLOW = ROOT / ".github" / "workflows" / "nightly.yml"


def test_nightly_suite_plans_with_a_baseline_for_every_group() -> None:
    plan = plan_suite([NIGHTLY])
    groups = {r.group: r for r in plan.runs}
    assert len(groups) == 9 + 5 and len(plan.runs) == 9 * 2 + 5
    sweep = [g for g in groups if g.startswith("crossing_reaction_delay[")]
    assert sweep == [f"crossing_reaction_delay[reaction_delay={v}]"
                     for v in ("0", "0.5", "1", "1.5", "2")]
    for spec in groups.values():
        name = next((o.split("=", 1)[1].strip("'") for o in spec.overrides
                     if o.startswith("baseline=")), spec.scenario)
        assert baseline_path(name, ROOT / "baselines").is_file(), spec.group
    # rendering scenes (the dock) outweigh the camera-less forklift scenes
    cost = {r.scenario: r.cost for r in plan.runs}
    assert cost["dock_worker_crossing"] > cost["forklift_warehouse"]


def test_workflow_installs_as_the_readme_says_and_runs_the_nightly_suite() -> None:
    wf = yaml.safe_load(WORKFLOW.read_text(encoding="utf-8"))
    assert set(wf[True]) == {"schedule", "workflow_dispatch"}  # PyYAML reads `on:` as True
    assert wf[True]["schedule"][0]["cron"]
    steps = wf["jobs"]["suite"]["steps"]
    runs = "\n".join(s.get("run", "") for s in steps)
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    main_job = re.search(r"```bash\n(python3 -m venv .venv && .venv/bin/pip install -q -e \. )"
                         r"&& (.venv/bin/srr run [^\n]+)\n```", readme)
    assert main_job, "README's first set-up command changed shape"
    assert main_job.group(1).strip() in runs
    suite_cmd = next(line for line in runs.splitlines() if "srr suite" in line)
    args = shlex.split(suite_cmd.replace("\\", ""))
    assert (ROOT / args[args.index("suite") + 1]).resolve() == NIGHTLY
    uses = [s.get("uses", "") for s in steps]
    assert any(u.startswith("actions/upload-artifact@") for u in uses)
    assert any("junit" in u for u in uses)
    # the job fails unless the suite exited 0
    assert 'test "$code" = 0' in runs
