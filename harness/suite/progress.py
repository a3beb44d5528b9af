"""What ``srr suite`` shows while it works: on a terminal one live line per running run
(elapsed wall time against its timeout) under a done/total line; in a log (CI) one line per
run as it finishes. Then a table of the groups, worst first."""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

from rich.console import Console, Group
from rich.live import Live
from rich.table import Table
from rich.text import Text

from harness.suite.events import Event
from harness.suite.results import GroupResult

__all__ = ["SuiteProgress", "groups_table"]

_STYLE = {
    "PASS": "green",
    "RECORDED": "green",
    "INVALID": "bold red",
    "FLAKY": "bold magenta",
    "REGRESSED": "bold red",
    "FAIL": "red",
    "MISMATCH": "yellow",
    "UNSCORED": "yellow",
    "INTERRUPTED": "yellow",
}


class SuiteProgress:
    """A :data:`~harness.suite.events.Listener` that draws progress on ``console``."""

    def __init__(self, console: Console, total: int, *, live: bool) -> None:
        self.console = console
        self.total = total
        self.done = 0
        self.running: dict[str, tuple[float, Event]] = {}
        self.live: Live | None = (
            Live(console=console, refresh_per_second=4, transient=True, get_renderable=self._render)
            if live
            else None
        )

    def __enter__(self) -> SuiteProgress:
        if self.live is not None:
            self.live.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        if self.live is not None:
            self.live.stop()

    def _render(self) -> Group:
        now = time.monotonic()
        lines = [
            Text(
                f"suite: {self.done}/{self.total} runs done, {len(self.running)} running",
                style="bold",
            )
        ]
        for rid, (t0, ev) in self.running.items():
            limit = f" / {ev.spec.timeout_s:g} s" if ev.spec.timeout_s else ""
            lines.append(Text(f"  {rid}  {now - t0:6.1f} s{limit}  ({ev.where})"))
        return Group(*lines)

    def __call__(self, ev: Event) -> None:
        if ev.kind == "start":
            self.running[ev.spec.id] = (time.monotonic(), ev)
            return
        self.running.pop(ev.spec.id, None)
        self.done += 1
        o = ev.outcome
        if o is None:
            return
        why = f" — {o.reasons[0]}" if o.reasons and o.verdict != "PASS" else ""
        line = Text(f"[{self.done}/{self.total}] {o.spec.id}: ")
        line.append(o.verdict, style=_STYLE.get(o.verdict, ""))
        line.append(f" in {o.wall_s:.1f} s{why}")
        self.console.print(line, soft_wrap=True)


def groups_table(groups: Sequence[GroupResult], title: str) -> Table:
    t = Table(title=title)
    for col in ("verdict", "scenario / sweep point", "repeats", "wall s", "why"):
        t.add_column(col, justify="right" if col in ("repeats", "wall s") else "left")
    for g in groups:
        wall = sum(r.wall_s for r in g.runs) / len(g.runs)
        t.add_row(
            Text(g.verdict, style=_STYLE.get(g.verdict, "")),
            Text(g.id),
            str(len(g.runs)),
            f"{wall:.1f}",
            Text(g.reasons[0] if g.reasons else ""),
        )
    return t
