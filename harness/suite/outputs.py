"""The files a CI system reads from a suite's output folder.

``summary.json`` (format ``srr-suite/1``: every group and run — scenario, parameters, repeat,
verdict, exit code, wall time, run directory — statistics, flakiness, sweeps, history),
``junit.xml`` (one test case per run: failures name the regressed metrics and their deltas,
flaky runs are failures of type ``flaky`` with a ``flaky`` property, crashed or timed-out runs
are errors, runs not started are skipped) and ``index.html`` (the suite page).
"""

from __future__ import annotations

import time
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from harness.atomic import write_json_atomic, write_text_atomic
from harness.report.junit import xml_document
from harness.suite.results import GroupResult, RunOutcome
from harness.summary import SUITE_FORMAT

__all__ = ["FORMAT", "write_junit_suite", "write_outputs"]

FORMAT = SUITE_FORMAT  # what summary.json says it is


def _case(ts: ET.Element, run: RunOutcome, group: GroupResult) -> None:
    name = run.spec.id.removeprefix(run.spec.entry) or f"#{run.spec.repeat}"
    tc = ET.SubElement(ts, "testcase", classname=f"srr.{run.spec.entry}",
                       name=f"{run.spec.entry}{name}", time=f"{run.wall_s:.3f}")
    props = [("verdict", run.verdict), ("repeat", str(run.spec.repeat)),
             *((f"param.{k}", str(v)) for k, v in run.spec.params)]
    if run.run_dir:
        props.append(("run_dir", run.run_dir))
    if group.flaky:
        props.append(("flaky", "true"))
    pe = ET.SubElement(tc, "properties")
    for k, v in props:
        ET.SubElement(pe, "property", name=k, value=v)
    text = "\n".join(run.reasons) or run.verdict
    if run.verdict == "INVALID":
        kind = "timeout" if run.timed_out else "crash" if run.crash else "INVALID"
        ET.SubElement(tc, "error", type=kind, message=f"{run.verdict}: {text}"[:2000]).text = text
    elif run.verdict == "INTERRUPTED":
        ET.SubElement(tc, "skipped", message=text[:2000])
    elif group.flaky:
        detail = "\n".join(group.reasons[:1]) + ("\n" + text if run.verdict != "PASS" else "")
        ET.SubElement(tc, "failure", type="flaky",
                      message=f"FLAKY: {group.reasons[0] if group.reasons else ''}"[:2000]
                      ).text = detail
    elif run.verdict == "RECORDED":
        ET.SubElement(tc, "system-out").text = (
            f"RECORDED ({'; '.join(run.reasons)}); report: {run.report or '—'}")
    elif run.verdict != "PASS":
        ET.SubElement(tc, "failure", type=run.verdict,
                      message=f"{run.verdict}: {'; '.join(run.reasons)}"[:2000]).text = text
    else:
        ET.SubElement(tc, "system-out").text = (
            f"PASS ({sum(e.get('status') in ('ok', 'improved', 'changed') for e in run.comparison)}"
            f" metrics within tolerance); report: {run.report or '—'}")


def write_junit_suite(path: Path, name: str, groups: Sequence[GroupResult]) -> None:
    """One ``<testsuite>`` per suite entry, one ``<testcase>`` per run."""
    by_entry: dict[str, list[tuple[RunOutcome, GroupResult]]] = {}
    for g in groups:
        for r in g.runs:
            by_entry.setdefault(r.spec.entry, []).append((r, g))
    root = ET.Element("testsuites", name=name)
    totals = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0, "time": 0.0}
    for entry, runs in by_entry.items():
        ts = ET.SubElement(root, "testsuite", name=entry)
        for r, g in runs:
            _case(ts, r, g)
        counts = {
            "tests": len(runs),
            "failures": sum(r.verdict not in ("PASS", "RECORDED", "INVALID", "INTERRUPTED") or (
                g.flaky and r.verdict not in ("INVALID", "INTERRUPTED")) for r, g in runs),
            "errors": sum(r.verdict == "INVALID" for r, _ in runs),
            "skipped": sum(r.verdict == "INTERRUPTED" for r, _ in runs),
            "time": sum(r.wall_s for r, _ in runs),
        }
        for k, v in counts.items():
            ts.set(k, f"{v:.3f}" if k == "time" else str(v))
            totals[k] += v
    for k, v in totals.items():
        root.set(k, f"{v:.3f}" if k == "time" else str(int(v)))
    write_text_atomic(path, xml_document(root))


def write_outputs(out_dir: Path, summary: Mapping[str, Any],
                  groups: Sequence[GroupResult]) -> dict[str, Any]:
    """``junit.xml`` and ``index.html`` first, ``summary.json`` last: a folder with a
    ``summary.json`` is a finished suite. The time the first two took goes into the summary's
    ``timeline`` (``pages_s``) when it has one. Returns the summary as written."""
    from harness.report.suite_page import write_suite_page

    t0 = time.monotonic()
    write_junit_suite(out_dir / "junit.xml", str(summary["name"]), groups)
    write_suite_page(out_dir, summary)
    data = dict(summary)
    if isinstance(data.get("timeline"), Mapping):
        data["timeline"] = {**data["timeline"], "pages_s": round(time.monotonic() - t0, 3)}
    write_json_atomic(out_dir / "summary.json", data)
    return data
