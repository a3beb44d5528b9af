"""``srr report``: re-render a finished run directory's ``report.html``, strictly."""

from __future__ import annotations

from pathlib import Path

from harness import runlock
from harness.recording.bagread import ros1_recording
from harness.recording.errors import BagError
from harness.recording.verify import verify_recording
from harness.report.html import write_report
from harness.run.graphs import rebuild_graphs
from harness.scenario import load_scenario
from harness.scoring import scenario_frames
from harness.summary import read_summary

__all__ = ["report"]


def report(run_dir: str | Path, *, video: bool = True) -> Path:
    """Re-render a run directory's ``report.html`` and its camera videos (``srr report``;
    ``video=False``: the page without videos, and an old ``video/`` folder removed). Unlike
    the lenient renderer, which notes what it could not read, this refuses a run directory
    whose summary, scenario or bag does not read back (SrrError, exit 2) and writes nothing
    then."""
    run = Path(run_dir)
    runlock.refuse_if_live(run)
    summary = read_summary(run)
    scenario = load_scenario(run / "scenario.yaml")
    if not (run / "bag" / "metadata.yaml").is_file() and ros1_recording(run / "bag") is None:
        raise BagError(f"{run / 'bag'}: metadata.yaml: missing (not a rosbag2 directory)")
    verify_recording(run, summary)  # the page draws this bag under this summary's verdict
    frames = scenario_frames(scenario, run / "bag")
    return write_report(run, summary=summary, scenario=scenario, frames=frames,
                        rebuild_graphs=rebuild_graphs, video=video)
