"""``srr`` command line: a thin layer over :mod:`harness.api`.

Exit codes: 0 pass (``diff``: equal within tolerance); 1 fail, regression, non-deterministic
repeat (``diff``: the runs differ); 2 bad input (one line naming the file and the field,
never a traceback); 3 invalid run; 130 interrupted.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import sys
import warnings
from collections.abc import Callable, Iterator, Sequence
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

# Only what the parser needs is imported here: ``srr --help`` and argument errors load no
# simulation, bus or rendering code. Each command imports the API when it runs.
from harness import __version__
from harness.blas import one_blas_thread
from harness.errors import SrrError, printable, shorten
from harness.glbackend import gl_failure
from harness.interrupt import INTERRUPTED_EXIT, StopRequests
from harness.live.config import DEFAULT_PORT
from harness.outdir import file_above
from harness.summary import recording_note, replay_note

if TYPE_CHECKING:
    from rich.console import Console

    from harness import api
    from harness.diff import DiffResult
    from harness.live.config import LiveConfig
    from harness.suite.diff import SuiteDiff

__all__ = ["main"]


@cache
def _stderr() -> Console:
    from rich.console import Console

    return Console(stderr=True, highlight=False, soft_wrap=True, emoji=False)


@cache
def _stdout() -> Console:
    from rich.console import Console

    # Piped output (CI logs) gets wide tables instead of rich's 80-column default.
    return Console(highlight=False, soft_wrap=True, emoji=False,  # ':x:' is text, not ❌
                   width=None if sys.stdout.isatty() else 160)


class _Parser(argparse.ArgumentParser):
    """argparse that reports bad arguments as one line and exit code 2."""

    def error(self, message: str) -> NoReturn:
        name = self.prog.split()[-1]  # the subcommand's, or "srr" itself
        where = "srr" if name == "srr" else f"srr {name}"
        _stderr().print(f"{where}: error: {shorten(message)}", markup=False)
        raise SystemExit(2)


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="srr", description="Record-and-replay regression harness (MuJoCo).")
    p.add_argument("--version", action="version", version=f"srr {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    run = sub.add_parser("run", help="run a scenario, record it and score it")
    run.add_argument("scenario", type=Path)
    run.add_argument("--out", type=Path, default=None, help="run directory "
                     "(default reports/<scenario>/<run id>)")
    run.add_argument("--seed", type=int, default=None)
    run.add_argument("--duration", type=float, default=None, help="simulated seconds")
    gt = run.add_mutually_exclusive_group()
    gt.add_argument("--srr-gt", dest="srr_gt", action="store_const", const=True, default=None,
                    help="build the ground-truth graph (/gt/*)")
    gt.add_argument("--no-srr-gt", dest="srr_gt", action="store_const", const=False)
    run.add_argument("--set", dest="overrides", action="append", default=[],
                     metavar="KEY=VALUE", help="override a scenario field (dotted path; list "
                     "items by index or name), e.g. robots.forklift.spawn.position=[0,0,0]")
    run.add_argument("--repeat", type=int, default=1, help="run N times and compare digests")
    run.add_argument("--compression", choices=("none", "zstd", "lz4"), default=None,
                     help="compress the bag's chunks (= --set recording.compression=...)")
    run.add_argument("--ros2", action="store_true", help="also publish every topic on a live "
                     "ROS 2 graph and take ros2.outputs from external nodes in lockstep "
                     "(= --set ros2.enabled=true)")
    run.add_argument("--rtsp", action="store_true", help="serve every camera with a port "
                     "as an h264 RTSP stream while the run goes (= --set rtsp.enabled=true)")
    run.add_argument("--update-baseline", action="store_true",
                     help="bless this run as the scenario's baseline")
    run.add_argument("--reason", default=None,
                     help="why, recorded in the baseline (with --update-baseline)")
    run.add_argument("--allow-failing", action="store_true",
                     help="with --update-baseline: bless the run even if it fails an absolute "
                     "criterion (see srr baseline bless --allow-failing)")
    run.add_argument("--baselines", type=Path, default=None,
                     help="baselines folder (default: the project's baselines/)")
    run.add_argument("--min-free-mb", type=float, default=None, metavar="MB",
                     help="free disk space to keep: refuse to start below the estimated bag "
                     "size plus this, stop the run below it (recording.min_free_mb)")
    run.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    run.add_argument("--no-video", dest="video", action="store_false",
                     help="leave the camera videos and clips out of report.html (the recording "
                     "is the same; `srr report RUN_DIR` adds them later)")
    _summary_md_options(run)
    _add_live_args(run)

    rp = sub.add_parser("replay", help="play a recorded run back into its systems under test "
                        "(or replacements), open loop, and score it")
    rp.add_argument("run_dir", type=Path)
    rp.add_argument("--sut", dest="suts", action="append", default=[],
                    metavar="NAME=module:Class", help="replace a system under test's plug-in")
    rp.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                    help="override a field of the systems under test, the scoring or the ros2 "
                    "block")
    rp.add_argument("--out", type=Path, default=None,
                    help="run directory (default reports/<scenario>/<run id>-replay)")
    rp.add_argument("--baselines", type=Path, default=None,
                    help="baselines folder (default: the project's baselines/)")
    rp.add_argument("--ros2", action="store_true", help="play the recording into a live "
                    "ROS 2 graph and take ros2.outputs from the external nodes of ros2.external "
                    "in lockstep (= --set ros2.enabled=true)")
    rp.add_argument("--ros2-external", dest="externals", action="append", default=[],
                    metavar="NAME='CMD ...'", help="run this command for the external process "
                    "NAME of ros2.external (a new build of your node)")
    rp.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    _add_live_args(rp)

    val = sub.add_parser("validate", help="check a scenario file without running it (or a "
                         "suite file: every entry and sweep point; or every scenario and suite "
                         "file of a folder)")
    val.add_argument("scenario", type=Path)
    val.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scenario field, as srr run --set")

    sch = sub.add_parser("schema", help="print the JSON Schema of scenario or suite files "
                         "(for editors)")
    sch.add_argument("kind", nargs="?", choices=("scenario", "suite"), default="scenario")
    sch.add_argument("--out", type=Path, help="write it to this file instead")

    gr = sub.add_parser("graph", help="print the scenario's action graphs")
    gr.add_argument("scenario", type=Path)
    gr.add_argument("--format", choices=("mermaid", "json"), default="mermaid")
    gr.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                    help="override a scenario field, as srr run --set")

    ins = sub.add_parser("inspect", help="list the topics of a recorded bag")
    ins.add_argument("bag", type=Path)

    rec = sub.add_parser("recover", help="make a killed run's bag (and run directory) valid")
    rec.add_argument("bag", type=Path, help="a run directory or its bag/")

    rep = sub.add_parser("report", help="(re-)render a run directory's report.html")
    rep.add_argument("run_dir", type=Path)
    rep.add_argument("--no-video", dest="video", action="store_false",
                     help="no camera videos in the page (and remove the run's video/ folder)")

    su = sub.add_parser("suite", help="run many scenarios (sweeps, repeats) in parallel or on "
                        "Ray; write summary.json, junit.xml and index.html")
    su.add_argument("paths", nargs="+", type=Path, metavar="PATH",
                    help="scenario files, folders of them, or suite files (suite.yaml)")
    su.add_argument("--jobs", "-j", type=int, default=None,
                    help="runs at once (local: default one per CPU; ray: default the cluster's "
                    "CPUs)")
    su.add_argument("--executor", choices=("local", "ray"), default="local")
    su.add_argument("--address", default=None,
                    help="an existing Ray cluster (auto, HOST:6379, ray://HOST:10001); "
                    "default: start a local one")
    su.add_argument("--repeat", type=int, default=None,
                    help="repeats per scenario or sweep point (a suite file's entry may say)")
    su.add_argument("--out", type=Path, default=None,
                    help="output folder (default reports/suite/<start time>)")
    su.add_argument("--resume", action="store_true",
                    help="run only what an earlier, unfinished pass of this suite in --out "
                    "left undone (runs never started, interrupted, timed out, crashed or made "
                    "by another srr, scenario or baseline); the runs that ended are kept and "
                    "judged with the new ones. A missing or empty --out starts afresh")
    su.add_argument("--timeout", type=float, default=None, metavar="SEC",
                    help="wall-clock limit per run; a run past it is stopped and INVALID")
    su.add_argument("--history", type=Path, default=None, metavar="DIR",
                    help="earlier suite outputs: the page shows each metric's trend")
    su.add_argument("--baselines", type=Path, default=None,
                    help="baselines folder (default: the project's baselines/)")
    su.add_argument("--gpu-share", type=float, default=0.5,
                    help="GPU fraction a rendering run asks Ray for (default 0.5)")
    su.add_argument("--update-baselines", action="store_true",
                    help="bless the first repeat of every valid, non-flaky group whose "
                         "baseline it changes (recording, metrics, configuration, versions); "
                         "baselines that already hold the same are left as they are")
    su.add_argument("--reason", default=None, help="why (with --update-baselines)")
    su.add_argument("--allow-failing", action="store_true",
                    help="with --update-baselines: also bless runs that fail an absolute "
                    "criterion (see srr baseline bless --allow-failing)")
    su.add_argument("--quiet", "-q", action="store_true",
                    help="no live status display (a line per finished run and the summary "
                         "still print)")
    _summary_md_options(su)

    _search_parser(sub)

    dif = sub.add_parser("diff", help="compare two runs (recorded topics, first divergence, "
                         "metrics side by side) or two suite output folders (run by run)")
    dif.add_argument("run_a", type=Path, help="baseline run directory, a baseline file "
                     "(baselines/NAME.json: its reference recording; the topics it does not "
                     "keep, by digest), or a suite output folder (srr suite --out; B is one "
                     "too, its runs matched by their ids)")
    dif.add_argument("run_b", type=Path, help="candidate run directory, or suite output folder")
    dif.add_argument("--tolerance", dest="tolerances", action="append", default=[],
                     metavar="TOPIC_GLOB[:FIELD_GLOB]=ABS[,REL]",
                     help="numeric differences within max(ABS, REL*|A|) count as equal, e.g. "
                     "'/odom:pose.pose.position.*=0.01,0.05' (repeatable; no field glob: "
                     "every field of the topic)")
    dif.add_argument("--html", type=Path, default=None, help="write a one-page view of both runs "
                     "(of two suites: the page, and each differing pair's in FILE.pairs/)")
    dif.add_argument("--no-video", dest="video", action="store_false",
                     help="--html without the runs' camera videos")
    dif.add_argument("--json", type=Path, default=None, help="write the result as JSON")

    exp = sub.add_parser("export", help="write a finished run for another viewer (Rerun)")
    exp.add_argument("run_dir", type=Path)
    exp.add_argument("--rerun", type=Path, required=True, metavar="FILE.rrd",
                     help="a Rerun recording on the sim_time timeline (needs the rerun extra)")

    base = sub.add_parser("baseline", help="manage baselines")
    base_sub = base.add_subparsers(dest="baseline_command", required=True, parser_class=_Parser)
    bl = base_sub.add_parser("bless", help="make a finished run its scenario's baseline")
    bl.add_argument("run_dir", type=Path)
    bl.add_argument("--reason", required=True, help="why this run becomes the baseline")
    bl.add_argument("--baselines", type=Path, default=None,
                    help="baselines folder (default: the project's baselines/)")
    bl.add_argument("--allow-failing", action="store_true",
                    help="bless a run that fails an absolute criterion (a required spec, the "
                    "safety match rate's FAIL band, a route goal not reached): later runs "
                    "are then held to it")

    ros2 = sub.add_parser("ros2", help="set up the ros2 extra (rclpy from the ROS 2 wheels)")
    ros2_sub = ros2.add_subparsers(dest="ros2_command", required=True, parser_class=_Parser)
    setup = ros2_sub.add_parser("setup", help="build tf2_msgs (/tf, /tf_static), which the "
                                "wheels lack, once into the cache")
    setup.add_argument("--cache", type=Path, default=None,
                       help="cache folder (default $SRR_ROS2_CACHE, else ~/.cache/srr/ros2)")
    return p


def _summary_md_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--summary-md", type=Path, default=None, metavar="FILE",
                   help="write a GitHub-flavoured Markdown summary (a pull request's comment "
                   "or $GITHUB_STEP_SUMMARY)")
    p.add_argument("--summary-link-base", default=None, metavar="URL",
                   help="prefix of the summary's report links (default: the output folder "
                   "relative to FILE)")


def _check_summary_md(args: argparse.Namespace) -> None:
    if args.summary_link_base is not None and args.summary_md is None:
        raise SrrError("--summary-link-base: only with --summary-md FILE")
    if args.summary_link_base is not None and not args.summary_link_base.strip():
        raise SrrError("--summary-link-base: empty; give the URL the reports are served under "
                       "(or leave the option out: links relative to FILE's folder)")
    out = getattr(args, "out", None)
    if args.summary_md is not None and out is not None and \
            Path(out).resolve() in Path(args.summary_md).resolve().parents:
        raise SrrError(f"--summary-md {args.summary_md}: inside --out {out}, whose files srr "
                       "writes (summary.json, report.html, ...); write it beside that folder")
    _writable("--summary-md", args.summary_md)
    _not_an_input(args, [*(getattr(args, "paths", None) or []),
                         *([args.scenario] if getattr(args, "scenario", None) else [])])


def _not_an_input(args: argparse.Namespace, inputs: Sequence[str | Path]) -> None:
    """Refuse a ``--summary-md`` FILE that is one of the files the command reads (a suite
    or scenario file): writing the summary would replace it."""
    if args.summary_md is None:
        return
    target = Path(args.summary_md).resolve()
    for given in inputs:
        if Path(given).resolve() == target:
            raise SrrError(f"--summary-md {args.summary_md}: is {given}, a file this command "
                           "reads; the summary would replace it: give another file name")


def _write_summary_md(args: argparse.Namespace, result: Any) -> None:
    from harness import api

    if args.summary_md is not None:
        path = api.write_summary_md(result, args.summary_md, link_base=args.summary_link_base)
        _stdout().print(f"summary: {path}", markup=False)


def _progress(quiet: bool) -> Any:
    if quiet or (not _stderr().is_terminal and not sys.stderr.isatty()):
        return None
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    return Progress(TextColumn("[bold]{task.description}"), BarColumn(),
                    TextColumn("{task.fields[sim]}"), TimeRemainingColumn(),
                    console=_stderr(), transient=True)


def _add_live_args(cmd: argparse.ArgumentParser) -> None:
    """``--foxglove`` and its options (``srr run``, ``srr replay``)."""
    fox = cmd.add_argument_group("live view", "serve the run over the Foxglove WebSocket "
                                 "protocol while it goes (needs the live extra)")
    fox.add_argument("--foxglove", action="store_true",
                     help="serve the run live: Foxglove → Open connection → Foxglove WebSocket "
                     "→ ws://localhost:8765")
    fox.add_argument("--foxglove-port", type=int, default=None, metavar="PORT",
                     help=f"port to listen on (default {DEFAULT_PORT}; 0: any free port)")
    fox.add_argument("--foxglove-host", default=None, metavar="HOST",
                     help="address to listen on (default 127.0.0.1, this machine only; "
                     "0.0.0.0 exposes the run to the network)")
    fox.add_argument("--foxglove-wait", type=float, default=None, metavar="SEC",
                     help="hold the first tick until a client subscribes, at most SEC seconds")
    fox.add_argument("--rate", type=float, default=None, metavar="FACTOR",
                     help="run at most FACTOR × real time (1: real time), to watch it; the "
                     "recording is the same")


def _cmd_replay(args: argparse.Namespace) -> int:
    from harness import api

    live = _live_config(args)
    bar = _progress(args.quiet)
    task: Any = None

    def tick(done: int, total: int) -> None:
        if bar is not None and (done % 15 == 0 or done == total):
            bar.update(task, completed=done, total=total)

    if bar is not None:
        bar.start()
        task = bar.add_task(f"replay {args.run_dir.name}", total=None, sim="")
    try:
        res = api.replay(args.run_dir, suts=args.suts, overrides=args.overrides,
                         out=args.out, progress=tick, baselines=args.baselines,
                         started=_started(bar), ros2=args.ros2,
                         externals=args.externals, live=live,
                         notice=lambda text: _stderr().print(f"srr replay: {text}",
                                                             markup=False))
    finally:
        if bar is not None:
            bar.stop()
    _print_run(res, "replay")
    return res.exit_code


def _started(bar: Any) -> Callable[[Path], None]:
    """What prints the run directory as soon as it exists (with or without ``-q``): the one to
    give ``srr recover`` should the run be killed. On stdout, so an error on stderr stays one
    line; above the progress bar, on its console, while one is shown (a line printed on
    stdout would land inside the bar's line on the terminal)."""
    def say(run_dir: Path) -> None:
        (_stdout() if bar is None else bar.console).print(f"run directory: {run_dir}",
                                                          markup=False)
    return say


def _live_config(args: argparse.Namespace) -> LiveConfig | None:
    """``--foxglove`` and its options as a :class:`LiveConfig` (None without ``--foxglove``)."""
    from harness.live.config import LiveConfig

    given = [flag for flag, value in (("--foxglove-port", args.foxglove_port),
                                      ("--foxglove-host", args.foxglove_host),
                                      ("--foxglove-wait", args.foxglove_wait),
                                      ("--rate", args.rate)) if value is not None]
    if not args.foxglove:
        if given:
            raise SrrError(f"{given[0]}: only with --foxglove (the live view)")
        return None
    if getattr(args, "repeat", 1) != 1:
        raise SrrError("--foxglove: watch one run, not a --repeat series")
    return LiveConfig(host=args.foxglove_host if args.foxglove_host is not None
                      else LiveConfig.host,
                      port=args.foxglove_port if args.foxglove_port is not None
                      else DEFAULT_PORT,
                      wait_s=args.foxglove_wait, rate=args.rate)


def _cmd_run(args: argparse.Namespace) -> int:
    from rich.table import Table

    from harness import api

    live = _live_config(args)
    overrides = list(args.overrides)
    if args.min_free_mb is not None:
        overrides.append(f"recording.min_free_mb={args.min_free_mb!r}")
    if args.ros2:
        overrides.append("ros2.enabled=true")
    if args.rtsp:
        overrides.append("rtsp.enabled=true")
    if args.compression is not None:
        overrides.append(f"recording.compression={args.compression}")
    _check_summary_md(args)
    if args.summary_md is not None and args.repeat != 1:
        raise SrrError("--summary-md: one run, not a --repeat series (srr suite --repeat N "
                       "summarizes repeats)")
    scenario = api.load(args.scenario, seed=args.seed, duration=args.duration,
                        srr_gt=args.srr_gt, overrides=overrides)
    if args.update_baseline and args.repeat != 1:
        raise SrrError("--update-baseline: bless one run, not a --repeat series")
    if args.reason is not None and not args.update_baseline:
        raise SrrError("--reason: only with --update-baseline (it is recorded in the baseline)")
    if args.allow_failing and not args.update_baseline:
        raise SrrError("--allow-failing: only with --update-baseline")
    bar = _progress(args.quiet)
    task: Any = None

    def tick(done: int, total: int) -> None:
        if bar is not None and (done % 15 == 0 or done == total):
            bar.update(task, completed=done, total=total,
                       sim=f"{done / scenario.physics.tick_hz:6.1f} s sim")

    if bar is not None:
        bar.start()
        task = bar.add_task(scenario.name, total=scenario.n_ticks, sim="")
    try:
        if args.repeat != 1:
            rep = api.run_repeat(scenario, args.repeat, source=str(args.scenario),
                                 out=args.out, progress=tick, baselines=args.baselines,
                                 started=_started(bar))
        else:
            res = api.run_scenario(scenario, source=str(args.scenario), out=args.out,
                                   progress=tick, baselines=args.baselines,
                                   update_baseline=args.update_baseline,
                                   allow_failing=args.allow_failing,
                                   update_reason=args.reason or "updated with "
                                   "--update-baseline", live=live,
                                   notice=lambda text: _stderr().print(
                                       f"srr run: {text}", markup=False),
                                   started=_started(bar), video=args.video)
    finally:
        if bar is not None:
            bar.stop()
    if args.repeat != 1:
        table = Table(title=f"determinism over {args.repeat} runs")
        table.add_column("run")
        table.add_column("verdict")
        table.add_column("digest")
        for r in rep.runs:
            table.add_row(str(r.run_dir), r.verdict, r.summary["digest"][:16])
        _stdout().print(table)
        finished = len(rep.finished)
        if rep.interrupted:
            _stdout().print(f"interrupted in run {len(rep.runs)} of {args.repeat}: its "
                            "recording is left out of the comparison", markup=False)
        if finished < 2:
            _stdout().print(f"finished runs: {finished}, no digests to compare", markup=False)
        elif rep.identical:
            _stdout().print(f"identical per-topic digests across {finished} runs")
        else:
            _stdout().print("digests DIFFER on: " + ", ".join(rep.differing_topics))
        _stdout().print(str(rep.out_dir))
        return rep.exit_code
    _print_run(res)
    if res.blessed is not None:
        _stdout().print(f"blessed {res.run_dir} as {res.blessed.resolve()}", markup=False)
    if res.not_blessed is not None:
        _stderr().print(f"srr run: {res.not_blessed}", markup=False)
    _write_summary_md(args, res)
    return res.exit_code


def _fmt(v: Any) -> str:
    return "—" if v is None else f"{v:.4g}"


def _fmt_unit(v: Any, unit: str) -> str:
    """A value with its unit; — alone for none (not `— m`)."""
    return "—" if v is None else f"{v:.4g} {unit}".rstrip()


def _print_run(res: api.RunResult, command: str = "run") -> None:
    from rich.table import Table

    s = res.summary
    what = "open-loop replay, " if s.get("replay_of") else ""
    out = s.get("output") or {}
    ros1 = (f", recorded as ROS 1 ({'.bag' if out.get('format') == 'bag' else 'MCAP'})"
            if out.get("ros") == 1 else "")
    table = Table(title=f"{s['scenario']}: {what}{s['simulated_s']:.1f} s simulated, "
                  f"seed {s['seed']}{ros1}")
    for col in ("topic", "type", "count", "rate Hz"):
        table.add_column(col, justify="right" if col in ("count", "rate Hz") else "left")
    for name, t in s["topics"].items():
        table.add_row(name, t["type"], str(t["count"]), f"{t['rate_hz']:.1f}")
    _stdout().print(table)
    if s["comparison"]:
        unjudged = all(e["status"] == "not_compared" for e in s["comparison"])
        mt = Table(title="metrics beside a baseline of another configuration (not compared)"
                   if unjudged else "metrics against the baseline (regressions first)")
        for col in ("metric", "value", "baseline", "delta", "tolerance", "status"):
            mt.add_column(col)
        for e in s["comparison"]:
            style = {"regressed": "bold red", "missing": "bold red",
                     "improved": "green", "not_compared": "dim"}.get(e["status"], "")
            mt.add_row(e["name"], _fmt_unit(e["value"], e["unit"]), _fmt(e["baseline"]),
                       _fmt(e["delta"]), f"±{e['tolerance']:.3g}",
                       e["status"].replace("_", " "), style=style)
        _stdout().print(mt)
    elif s["metrics"]:
        mt = Table(title="metrics (no baseline)")
        for col in ("metric", "value", "unit"):
            mt.add_column(col)
        for m in s["metrics"]:
            mt.add_row(m["name"], _fmt(m["value"]), m["unit"])
        _stdout().print(mt)
    for w in s.get("warnings", []):
        _stderr().print(f"srr {command}: warning: {w}", markup=False)
    bad = [h for h in s["health"] if not h["ok"]]
    _stdout().print(f"health: {len(s['health']) - len(bad)}/{len(s['health'])} gates ok",
                    markup=False)
    replay = replay_note(s)
    if replay is not None:
        _stdout().print(f"this run is an {replay}", markup=False)
    recording = recording_note(s)
    if recording is not None:
        _stdout().print(recording, markup=False)
        b = s.get("baseline") or {}
        cut_short = s.get("interrupted") or s.get("stopped")
        if not b.get("digest_matches") and b.get("reference") and not cut_short:
            _stdout().print(f"  where: srr diff {b['path']} {res.run_dir}", markup=False)
    _stdout().print(f"verdict: {res.verdict}", markup=False)
    for reason in s.get("reasons", []):
        _stdout().print(f"  - {reason}", markup=False)
    _stdout().print(str(res.run_dir), markup=False)


def _cmd_baseline(args: argparse.Namespace) -> int:
    from harness import api

    path = api.bless(args.run_dir, args.reason, baselines=args.baselines,
                     allow_failing=args.allow_failing)
    _stdout().print(f"blessed {args.run_dir} as {path}", markup=False)
    return 0


def _cmd_ros2(args: argparse.Namespace) -> int:
    from harness.ros2.tf2_msgs import install_tf2_msgs

    install = install_tf2_msgs(args.cache)
    how = "built" if install.built_now else "already built"
    _stdout().print(f"tf2_msgs: {how} ({install.build_seconds:.1f} s, "
                    f"{install.size_bytes / 1e6:.1f} MB): {install.prefix}", markup=False)
    return 0


def _cmd_validate(args: argparse.Namespace) -> int:
    from harness.suite.spec import is_suite_path

    path: Path = args.scenario
    if path.is_dir():
        return _validate_folder(path, args.overrides)
    if is_suite_path(path):
        return _validate_suite(path, args.overrides)
    return _validate_scenario(path, args.overrides)


def _validate_scenario(path: Path, overrides: Sequence[str]) -> int:
    from harness import api

    sc = api.load(path, overrides=overrides)
    warnings = api.validate(sc, source=str(path))
    if sc.sweep and not overrides:  # its own sweep: every point, as srr suite would (each
        # warning then says its entry, and a later point's its label)
        warnings = api.plan_suite([path]).warnings
    for w in warnings:
        _stderr().print(f"srr validate: warning: {w}", markup=False)
    robots = ", ".join(
        f"{r.name} ({r.model_name}{', namespace /' + r.ns.strip('/') if r.ns else ''})"
        for r in sc.robots if r.enabled) or "none"
    _stdout().print(f"{path}: ok — {sc.name}, {sc.duration:g} s, seed {sc.seed}, "
                    f"robots: {robots}" + (f", {len(warnings)} warning(s)" if warnings else ""),
                    markup=False)
    return 0


def _validate_suite(path: Path, overrides: Sequence[str]) -> int:
    """``srr validate SUITE.yaml``: what ``srr suite`` checks before its first run, every
    entry and sweep point, and nothing run."""
    from harness import api

    if overrides:
        raise SrrError(f"--set: {path} is a suite; a suite changes its scenarios "
                       "with `set:` in its entries")
    plan = api.plan_suite([path])
    for w in plan.warnings:
        _stderr().print(f"srr validate: warning: {w}", markup=False)
    groups = len({r.group for r in plan.runs})
    _stdout().print(f"{path}: ok — suite {plan.spec.name}: {len(plan.spec.entries)} scenario "
                    f"entries, {groups} groups, {len(plan.runs)} runs"
                    + (f", {len(plan.warnings)} warning(s)" if plan.warnings else ""),
                    markup=False)
    return 0


def _validate_folder(folder: Path, overrides: Sequence[str]) -> int:
    """``srr validate FOLDER``: every scenario and suite file in it checked as ``srr validate
    FILE`` checks it, one line per file (``srr validate: ERROR`` for a bad one), then that
    its scenarios' names are unique, as ``srr suite FOLDER`` needs, and a summary line. Exit
    2 when any file failed."""
    from harness.suite.spec import folder_files, is_suite_path, load_suite

    if overrides:
        raise SrrError(f"--set: {folder} is a folder; validate one scenario file to change it "
                       "with --set")
    files = folder_files(folder)
    failed = 0
    for path in files:
        try:
            (_validate_suite if is_suite_path(path) else _validate_scenario)(path, ())
        except SrrError as err:
            failed += 1
            said = _one_line(err)  # an include's error names the include: say whose it is
            said = said if said.startswith(str(path)) else f"{path}: {said}"
            _stderr().print(f"srr validate: {said}", markup=False)
    if not failed:
        try:  # what only the folder as a whole can get wrong: two scenarios of one name
            load_suite([folder])
        except SrrError as err:
            failed += 1
            _stderr().print(f"srr validate: {_one_line(err)}", markup=False)
    if failed:
        _stdout().print(f"{folder}: {failed} of {len(files)} file(s) failed", markup=False)
        return 2
    _stdout().print(f"{folder}: ok — {len(files)} file(s)", markup=False)
    return 0


def _one_line(err: BaseException) -> str:
    """An error's message on one line, as :func:`main` prints it."""
    return shorten(" ".join(part.strip() for part in str(err).splitlines() if part.strip()))


def _cmd_schema(args: argparse.Namespace) -> int:
    from harness import api
    from harness.atomic import write_text_atomic
    from harness.schemagen import dumps

    _writable("--out", args.out)
    text = dumps(api.json_schema(args.kind))
    if args.out is None:
        sys.stdout.write(text)
    else:
        write_text_atomic(args.out, text)
        _stdout().print(f"{args.kind} schema: {args.out}", markup=False)
    return 0


def _cmd_graph(args: argparse.Namespace) -> int:
    from harness import api

    sc = api.load(args.scenario, overrides=args.overrides)
    sys.stdout.write(api.graph_text(sc, args.format, source=str(args.scenario)) + "\n")
    return 0


def _cmd_inspect(args: argparse.Namespace) -> int:
    from rich.table import Table

    from harness.bag import inspect_bag

    info = inspect_bag(args.bag)
    table = Table(title=f"{info.path} ({info.storage}, {info.message_count} messages, "
                  f"{(info.end_ns - info.start_ns) / 1e9:.2f} s)")
    for col in ("topic", "type", "count", "durability"):
        table.add_column(col)
    for t in info.topics:
        table.add_row(t.name, t.msgtype, str(t.count), t.durability)
    _stdout().print(table)
    return 0


def _cmd_recover(args: argparse.Namespace) -> int:
    from rich.table import Table

    from harness import api

    res = api.recover(args.bag)
    bag = res.bag
    kept = sum(t.count for t in bag.topics.values())
    if bag.status == "valid" and not res.changed:
        _stdout().print(f"{bag.mcap}: valid ({kept} messages in {bag.chunks} chunks): "
                        "nothing to recover", markup=False)
        return 0
    table = Table(title=f"{bag.bag_dir}: kept per topic")
    for col in ("topic", "type", "kept", "durability"):
        table.add_column(col, justify="right" if col == "kept" else "left")
    for t in bag.topics.values():
        table.add_row(t.topic, t.msgtype, str(t.count), t.durability)
    _stdout().print(table)
    if bag.status == "rebuilt":
        last = max((t.last_ns or 0 for t in bag.topics.values()), default=0)
        dropped = (f"; dropped the {bag.dropped_bytes} bytes after them (an incomplete chunk)"
                   if bag.dropped_bytes else "")
        _stdout().print(f"rebuilt {bag.mcap.name} from {bag.chunks} complete chunks "
                        f"({kept} messages, the last at {last / 1e9:.3f} s){dropped}; the "
                        f"original is kept as {bag.damaged.name if bag.damaged else '?'}",
                        markup=False)
    elif bag.status == "metadata":
        _stdout().print(f"{bag.mcap.name} was complete ({kept} messages); rewrote "
                        "metadata.yaml", markup=False)
    else:
        _stdout().print(f"{bag.mcap.name} was complete ({kept} messages)", markup=False)
    if res.summary is not None and res.run_dir is not None:
        _stdout().print(f"{res.run_dir / 'summary.json'}: recovered, verdict "
                        f"{res.summary['verdict']} ({res.cause}; not scored)", markup=False)
        for name, kept_as in res.replaced.items():
            _stdout().print(f"the {name} it replaces is kept as {kept_as.name}", markup=False)
        if "report.html" in res.replaced:
            _stdout().print(f"`srr report {res.run_dir}` renders the recovered run's report",
                            markup=False)
    elif res.run_dir is not None:
        holds = (" and its bag holds every message its summary counts" if res.kept
                 and bag.status == "rebuilt" else "")
        _stdout().print(f"{res.run_dir}: the run had finished{holds}; its summary is kept",
                        markup=False)
    return 0


def _cmd_export(args: argparse.Namespace) -> int:
    from harness import api

    res = api.export_rerun(args.run_dir, args.rerun)
    _stdout().print(f"{res.path}: {len(res.rows)} entities, {sum(res.rows.values())} rows on "
                    f"sim_time, {res.bytes / 1e6:.1f} MB", markup=False)
    if res.skipped:
        _stdout().print("not exported (no Rerun type for them): " + ", ".join(
            f"{t} ({m})" for t, m in res.skipped.items()), markup=False)
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    from harness import api

    path = api.report(args.run_dir, video=args.video)
    _stdout().print(str(path), markup=False)
    return 0


def _writable(option: str, path: Path | None) -> None:
    if path is not None and not path.parent.is_dir():
        above = file_above(path)
        if above is not None:
            raise SrrError(f"{option} {path}: {above} is a file, not a folder")
        raise SrrError(f"{option} {path}: directory {path.parent} does not exist")
    if path is not None and path.is_dir():
        raise SrrError(f"{option} {path}: is a directory, expected a file name")


_STATUS_STYLE = {"differs": "bold red", "only_in_a": "bold red", "only_in_b": "bold red",
                 "within_tolerance": "yellow", "regressed": "bold red", "missing": "bold red",
                 "improved": "green"}


def _count(n: int | None) -> str:
    """A count for a table; None (not counted: a topic compared by its digest only) is —."""
    return "—" if n is None else str(n)


def _print_diff(r: DiffResult) -> None:
    from rich.table import Table

    for label, run in (("A", r.a), ("B", r.b)):
        sim = f"{run.simulated_s:.1f} s" if run.simulated_s is not None else "?"
        _stdout().print(f"{label}: {run.path}  ({run.scenario}, seed {run.seed}, {sim}, "
                        f"{run.verdict})", markup=False)
    for note in r.replay_notes:
        _stdout().print(note, markup=False)
    if r.changes:
        _stdout().print("what changed (A → B):", markup=False)
        for line in r.changes:
            _stdout().print(f"  {line}", markup=False)
    table = Table(title="recorded topics (messages paired by index)")
    for col in ("topic", "type", "A", "B", "status", "differ", "first divergence"):
        table.add_column(col, justify="right" if col in ("A", "B", "differ") else "left")
    for t in r.topics:
        d = t.first_beyond or t.first
        where = "" if d is None else f"#{d.index} @{d.t_ns / 1e9:.3f} s {d.path}"
        table.add_row(t.name, t.msgtype.replace("/msg/", "/"), str(t.count_a), str(t.count_b),
                      t.status, _count(t.messages_differ), where,
                      style=_STATUS_STYLE.get(t.status, ""))
    _stdout().print(table)
    fields = [(t, f) for t in r.topics for f in t.fields]
    if fields:
        ft = Table(title="numeric differences |B − A| over the messages that differ")
        for col in ("topic", "field", "values", "differ", "beyond", "max |Δ|", "RMS", "at",
                    "tolerance"):
            ft.add_column(col, justify="right" if col in ("values", "differ", "beyond",
                                                          "max |Δ|", "RMS", "at") else "left")
        shown = [(t, f) for t in r.topics for f in t.fields[:3]][:30]  # worst first per topic
        for t, f in shown:
            ft.add_row(t.name, f.path, str(f.values), str(f.differ), str(f.beyond),
                       f"{f.max_abs:.4g}",
                       f"{f.rms:.4g}", f"#{f.at_index} @{f.at_ns / 1e9:.3f} s",
                       f.tolerance.describe() if f.tolerance else "none",
                       style="" if f.within else "red")
        _stdout().print(ft)
        if len(fields) > len(shown):
            _stdout().print(f"  … {len(fields) - len(shown)} more field(s) differ "
                            "(--json or --html for all)", markup=False)
    moved = [m for m in r.metrics if m.status != "ok"]
    if moved:
        mt = Table(title="metrics that moved (A = baseline; informative, not part of the exit "
                   "code)")
        for col in ("metric", "A", "B", "delta", "tolerance", "status", "better"):
            mt.add_column(col)
        for m in moved:
            mt.add_row(m.name, _fmt_unit(m.value_a, m.unit), _fmt_unit(m.value_b, m.unit),
                       _fmt(m.delta), f"±{m.tolerance:.3g}", m.status, m.better or "—",
                       style=_STATUS_STYLE.get(m.status, ""))
        _stdout().print(mt)
    if r.metrics:
        _stdout().print(f"metrics: {len(r.metrics) - len(moved)}/{len(r.metrics)} within "
                        "tolerance", markup=False)
    for note in r.notes:
        _stderr().print(f"srr diff: note: {note}", markup=False)
    first = r.first_divergence
    if first is not None:
        _stdout().print(f"first divergence: {first.describe()}", markup=False)
    labels = {"identical": "identical", "within_tolerance": "within tolerance",
              "differs": "different", "only_in_a": "only in A", "only_in_b": "only in B"}
    counts = {label: sum(t.status == s for t in r.topics) for s, label in labels.items()}
    parts = [f"{n} {label}" for label, n in counts.items() if n]
    _stdout().print(f"verdict: {r.verdict.replace('_', ' ')} ({len(r.topics)} topics: "
                    f"{', '.join(parts)})",
                    markup=False)


def _print_suite_diff(r: SuiteDiff) -> None:
    from harness.suite.diff import runs_named

    out = _stdout()
    for label, s in (("A", r.a), ("B", r.b)):
        out.print(f"{label}: {s.path}  (suite {s.name}, {s.runs} runs, {s.verdict}, started "
                  f"{s.started_at or '?'})", markup=False)
    if r.changes:
        out.print("what changed (A → B):", markup=False)
        for line, ids in r.changes:
            out.print(f"  {line}  ({runs_named(ids, len(r.pairs))})", markup=False)
    if r.groups:
        out.print("group verdicts that changed:", markup=False)
        for g in r.groups:
            out.print(f"  {g.id}: {g.verdict_a} → {g.verdict_b}", markup=False)
    for side, runs in (("A", r.only_in_a), ("B", r.only_in_b)):
        if runs:
            out.print(f"runs only in {side} ({len(runs)}):", markup=False)
            for u in runs:
                out.print(f"  {u.id}: {u.verdict}", markup=False)
    changed = r.changed
    if changed:
        out.print(f"runs that differ ({len(changed)} of {len(r.pairs)} matched):", markup=False)
        for p in changed:
            out.print(f"  {p.id}: {p.describe()}", style="" if p.equal else "bold red",
                      markup=False)
    for note in r.notes:
        _stderr().print(f"srr diff: note: {note}", markup=False)
    first = next((p for p in changed if p.run_a is not None and p.run_b is not None), None)
    if first is not None:
        out.print(f"details of a pair: srr diff {first.run_a} {first.run_b}", markup=False)
    out.print(f"verdict: {r.verdict.replace('_', ' ')} ({r.counts()})", markup=False)


def _diff_suites(args: argparse.Namespace, suites: tuple[bool, bool]) -> int:
    from harness import api

    if not all(suites):
        suite, other = (args.run_a, args.run_b) if suites[0] else (args.run_b, args.run_a)
        what = "not a suite folder" if Path(other).exists() else "no such directory"
        raise SrrError(f"{other}: {what}; {suite} is one: srr diff compares two suite "
                       "folders, or two runs")
    result = api.diff_suites(args.run_a, args.run_b, tolerances=args.tolerances)
    _print_suite_diff(result)
    return _diff_outputs(args, result, api.write_suite_diff)


def _diff_outputs(args: argparse.Namespace, result: Any, write_page: Any) -> int:
    """``--json`` and ``--html`` of a diff of two runs or two suites (``write_page``: the
    API's page writer), said as they are written; the diff's exit code."""
    from harness.atomic import write_json_atomic

    if args.json is not None:
        write_json_atomic(args.json, result.to_dict())
        _stdout().print(f"json: {args.json}", markup=False)
    if args.html is not None:
        page = write_page(result, args.html, video=args.video)
        _stdout().print(f"html: {page}", markup=False)
    return int(result.exit_code)


def _cmd_diff(args: argparse.Namespace) -> int:
    from harness import api
    from harness.diff.core import is_baseline_file
    from harness.suite.diff import is_suite_dir

    _writable("--html", args.html)
    _writable("--json", args.json)
    for p in (Path(args.run_a), Path(args.run_b)):
        if p.name == "summary.json" and is_suite_dir(p.parent):
            raise SrrError(f"{p}: the summary of the suite {p.parent}: give the suite folder")
    suites = (is_suite_dir(args.run_a), is_suite_dir(args.run_b))
    if any(suites):
        return _diff_suites(args, suites)
    if args.html is not None and is_baseline_file(Path(args.run_a)):
        raise SrrError(f"--html: shows two run directories; {args.run_a} is a baseline file "
                       "(the run's report.html overlays it, under 'Against the baseline')")
    result = api.diff_runs(args.run_a, args.run_b, tolerances=args.tolerances)
    _print_diff(result)
    return _diff_outputs(args, result, api.write_diff)


def _cmd_suite(args: argparse.Namespace) -> int:
    from harness.suite.host import stop_early

    try:
        return _suite(args)
    finally:
        stop_early()


def _suite(args: argparse.Namespace) -> int:
    from harness import api
    from harness.suite.host import start_early, warm_early
    from harness.suite.progress import SuiteProgress, groups_table

    local = args.executor == "local"
    if local:  # its hosts start while this one plans (and make their OpenGL contexts then)
        import os

        start_early(args.jobs if args.jobs is not None else os.cpu_count() or 1)

    if args.update_baselines and not args.reason:
        raise SrrError("--update-baselines: say why with --reason TEXT")
    if args.reason is not None and not args.update_baselines:
        raise SrrError("--reason: only with --update-baselines (it is recorded in the "
                       "baselines blessed)")
    if args.allow_failing and not args.update_baselines:
        raise SrrError("--allow-failing: only with --update-baselines")
    if args.resume and args.out is None:
        raise SrrError("--resume: name the folder of the suite to resume with --out")
    _check_summary_md(args)
    live = not args.quiet and _stdout().is_terminal
    holder: dict[str, Any] = {}

    def listen(ev: Any) -> None:
        holder["progress"](ev)

    plan = api.plan_suite(args.paths, repeat=args.repeat, timeout_s=args.timeout,
                          on_render=warm_early if local else None)
    _not_an_input(args, [e.scenario_file for e in plan.spec.entries])
    for w in plan.warnings:
        _stderr().print(f"srr suite: warning: {w}", markup=False)
    resumed = api.resume_suite(plan, args.out) if args.resume else None
    if resumed is not None:
        for note in resumed.notes:
            _stderr().print(f"srr suite: resume: {note}", markup=False)
        _stdout().print(f"resuming {args.out}: {len(resumed.kept)} run(s) kept, "
                        f"{len(resumed.again)} to run", markup=False)
    todo = len(plan.runs) if resumed is None else len(resumed.again)
    with SuiteProgress(_stdout(), todo, live=live) as progress:
        holder["progress"] = progress
        res = api.run_planned_suite(
            plan, executor=args.executor, jobs=args.jobs, address=args.address,
            out=args.out, history=args.history, baselines=args.baselines,
            gpu_share=args.gpu_share,
            bless_reason=args.reason if args.update_baselines else None, listen=listen,
            fork=True,  # this process only plans: workers fork from it when safe
            allow_failing=args.allow_failing, resume=resumed)
    s = res.summary
    unstarted = sum(not r.started for g in res.groups for r in g.runs)
    runs = (f"{len(s['runs']) - unstarted} of {len(s['runs'])} runs" if unstarted
            else f"{len(s['runs'])} runs")
    _stdout().print(groups_table(res.groups, f"suite {s['name']}: {runs} on "
                                   f"{s['executor']} × {s['jobs']} in {s['wall_s']:.1f} s"))
    for w in (s.get("history") or {}).get("warnings", []):
        _stderr().print(f"srr suite: warning: {w}", markup=False)
    for path in res.blessed:
        _stdout().print(f"blessed {path}", markup=False)
    for why in res.not_blessed:
        _stderr().print(f"srr suite: {why}", markup=False)
    if res.unchanged:
        _stdout().print(f"unchanged: {len(res.unchanged)} baseline(s) already hold what these "
                        "runs recorded and scored (left as they are): "
                        + ", ".join(p.name for p in res.unchanged), markup=False)
    other = [g.id for g in res.groups if g.recorded_other_bytes]
    if other:
        _stdout().print(f"recording: {len(other)} group(s) recorded other bytes than their "
                        "baselines (their metrics judged on their own): " + ", ".join(other),
                        markup=False)
    _stdout().print(f"verdict: {res.verdict}", markup=False)
    _stdout().print(f"{res.out_dir / 'index.html'}", markup=False)
    _write_summary_md(args, res)
    return int(res.exit_code)


def _search_parser(sub: Any) -> None:
    se = sub.add_parser("search", help="search scenario parameters for a run that violates "
                        "an objective (falsification); counterexamples become scenarios")
    se.add_argument("scenario", type=Path, help="the scenario file to search around")
    se.add_argument("--space", action="append", default=[], metavar="PATH=RANGE",
                    help="a --set path and its range: LO..HI, LO..HI:log, LO..HI:STEP, "
                    "[A, B, ...] (repeatable)")
    se.add_argument("--objective", required=True, metavar="METRIC",
                    help="a metric of the run's summary.json, e.g. safety.under_mute")
    se.add_argument("--violated-below", type=float, default=None, metavar="VALUE",
                    help="a run violates the objective when the metric is below VALUE "
                    "(default 0 for spec.NAME.robustness)")
    se.add_argument("--violated-above", type=float, default=None, metavar="VALUE",
                    help="a run violates the objective when the metric is above VALUE")
    se.add_argument("--budget", type=int, default=20, help="trials in all (default 20)")
    se.add_argument("--sampler", default="tpe", help="tpe (default), random, qmc or cmaes")
    se.add_argument("--seed", type=int, default=0, help="the sampler's seed (default 0)")
    se.add_argument("--stop-at-first", action="store_true",
                    help="stop after the batch that found the first violation")
    se.add_argument("--set", dest="overrides", action="append", default=[],
                    metavar="KEY=VALUE", help="a fixed scenario override (repeatable)")
    se.add_argument("--name", default=None, help="the search's name (default: the scenario's)")
    se.add_argument("--out", type=Path, default=None,
                    help="output folder (default reports/search/<name>); re-running the same "
                    "command resumes the search kept there")
    se.add_argument("--jobs", "-j", type=int, default=None,
                    help="trials at once (local: default one per CPU; ray: the cluster's CPUs)")
    se.add_argument("--executor", choices=("local", "ray"), default="local")
    se.add_argument("--address", default=None, help="an existing Ray cluster")
    se.add_argument("--timeout", type=float, default=None, metavar="SEC",
                    help="wall-clock limit per run; a run past it is stopped and INVALID")
    se.add_argument("--counterexamples", type=int, default=3, metavar="N",
                    help="write the N worst violating trials as scenario files (default 3)")
    se.add_argument("--prune", action="store_true",
                    help="delete the recording (bag/) of every trial that does not violate the "
                    "objective; its summary.json and report.html stay")
    se.add_argument("--add-to-suite", type=Path, default=None, metavar="SUITE",
                    help="append the counterexamples to this suite file")
    se.add_argument("--bless", action="store_true",
                    help="run each added counterexample once and make it its baseline")
    se.add_argument("--reason", default=None, help="why (with --bless)")
    se.add_argument("--baselines", type=Path, default=None,
                    help="baselines folder (default: the project's baselines/)")
    se.add_argument("--quiet", "-q", action="store_true", help="no line per trial")


def _cmd_search(args: argparse.Namespace) -> int:
    from harness import api

    if args.bless and not args.reason:
        raise SrrError("--bless: say why with --reason TEXT")
    if args.reason is not None and not args.bless:
        raise SrrError("--reason: only with --bless (it is recorded in the baselines blessed)")
    quiet = args.quiet

    def on_trial(rec: Any) -> None:
        if not quiet:
            value = "—" if rec.value is None else f"{rec.value:g}"
            _stdout().print(f"{rec.id} {rec.status:<8} {args.objective} = {value}  "
                            + ", ".join(f"{k}={v}" for k, v in rec.params.items()),
                            markup=False)

    res = api.search(
        args.scenario, space=args.space, objective=args.objective,
        violated_below=args.violated_below, violated_above=args.violated_above,
        overrides=args.overrides, sampler=args.sampler, seed=args.seed,
        budget=args.budget, stop_at_first=args.stop_at_first, executor=args.executor,
        jobs=args.jobs, address=args.address, out=args.out, timeout_s=args.timeout,
        name=args.name, counterexamples=args.counterexamples, prune=args.prune,
        add_to_suite=args.add_to_suite, bless_reason=args.reason if args.bless else None,
        baselines=args.baselines, on_trial=on_trial, fork=True)
    for w in res.warnings:
        _stderr().print(f"srr search: warning: {w}", markup=False)
    c = res.summary["counts"]
    _stdout().print(f"search {res.summary['name']}: {c['trials']} trials ({res.ran} now), "
                    f"{c['violated']} violated, {c['invalid']} invalid"
                    + (f", {c['no_value']} where {res.summary['objective']['metric']} had no "
                       "value" if c.get("no_value") else "")
                    + (f", {c['killed']} killed" if c.get("killed") else ""), markup=False)
    for path in res.counterexamples:
        _stdout().print(f"counterexample {path}", markup=False)
    add = res.addition
    if add is not None:
        for n in add.added:
            _stdout().print(f"added {n} to {add.suite}", markup=False)
        for n in add.not_reproduced:
            _stderr().print(f"srr search: warning: {n} did not violate the objective again "
                            "when re-run; not added", markup=False)
        for path in add.blessed:
            _stdout().print(f"blessed {path}", markup=False)
    _stdout().print(f"verdict: {res.verdict}", markup=False)
    _stdout().print(f"{res.out_dir / 'index.html'}", markup=False)
    return int(res.exit_code)


COMMANDS = {"run": _cmd_run, "suite": _cmd_suite, "replay": _cmd_replay, "validate": _cmd_validate,
            "graph": _cmd_graph, "inspect": _cmd_inspect, "baseline": _cmd_baseline,
            "report": _cmd_report, "recover": _cmd_recover, "diff": _cmd_diff,
            "ros2": _cmd_ros2, "schema": _cmd_schema, "export": _cmd_export,
            "search": _cmd_search}


def main(argv: Sequence[str] | None = None) -> int:
    one_blas_thread()  # before any command imports NumPy
    args = _parser().parse_args(argv)
    # Ctrl-C and SIGTERM raise KeyboardInterrupt, and are noted: one that code turned into
    # another error where it landed (an import of a C extension, a ctypes call) still reads
    # as the interrupt it was, not as that error with a traceback.
    stop = StopRequests(at_once=True)
    try:
        with stop.installed(), _warnings_said(_command_name(args)):
            return COMMANDS[args.command](args)
    except KeyboardInterrupt as err:  # its text, if any, says what was left where
        return _interrupted(_command_name(args), str(err))
    except Exception as err:
        if stop.requested:  # an interrupt that became this error where it landed
            return _interrupted(_command_name(args))
        if not isinstance(err, SrrError):
            err = gl_failure(err) or err  # MUJOCO_GL's library missing: what to install
            if not isinstance(err, SrrError):
                raise
        _stderr().print(f"srr {_command_name(args)}: {_one_line(err)}", markup=False)
        return err.exit_code


class _SaidHandler(logging.Handler):
    """srr's own log records (``harness.*``, WARNING and above: MuJoCo's runtime warnings on
    ``harness.sim``) said as the command's warnings are."""

    def __init__(self, command: str) -> None:
        super().__init__(logging.WARNING)
        self.command = command

    def emit(self, record: logging.LogRecord) -> None:
        _stderr().print(f"srr {self.command}: warning: {printable(record.getMessage())}",
                        markup=False)


@contextlib.contextmanager
def _warnings_said(command: str) -> Iterator[None]:
    """While a command runs, a library's Python warning (MuJoCo's compiler: "Inertia matrix is
    too close to singular") and srr's log records are each one line, ``srr CMD: warning:
    ...``, as the command's own warnings are, not a file, a line number and a source line."""
    def show(message: Warning | str, category: type[Warning], filename: str, lineno: int,
             file: Any = None, line: str | None = None) -> None:
        _stderr().print(f"srr {command}: warning: {printable(str(message))}", markup=False)

    handler, log, shown = _SaidHandler(command), logging.getLogger("harness"), \
        warnings.showwarning
    warnings.showwarning = show
    log.addHandler(handler)
    try:
        yield
    finally:
        warnings.showwarning = shown
        log.removeHandler(handler)


def _command_name(args: argparse.Namespace) -> str:
    """The command as typed, with its subcommand where it has one (``baseline bless``)."""
    sub = getattr(args, f"{args.command}_command", None)
    return f"{args.command} {sub}" if sub else str(args.command)


def _interrupted(command: str, note: str = "") -> int:
    _stderr().print(f"srr {command}: interrupted" + (f"; {note}" if note else ""), markup=False)
    return INTERRUPTED_EXIT


def entry() -> None:
    sys.exit(main())


if __name__ == "__main__":
    entry()
