"""Statistics of a metric over repeats: mean, sample standard deviation, min/max and a 95 %
confidence interval of the mean (Student's t; none for fewer than two values)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["Stats", "describe"]


@dataclass(frozen=True)
class Stats:
    n: int
    mean: float
    std: float
    min: float
    max: float
    ci95: tuple[float, float] | None


def describe(values: Sequence[float]) -> Stats | None:
    """None for no values."""
    xs = [float(v) for v in values]
    n = len(xs)
    if n == 0:
        return None
    mean = math.fsum(xs) / n
    std = math.sqrt(math.fsum((x - mean) ** 2 for x in xs) / (n - 1)) if n > 1 else 0.0
    ci: tuple[float, float] | None = None
    if n > 1:
        # Student's t quantile from scipy.special (what scipy.stats.t.ppf calls, the same
        # value): importing scipy.stats takes 0.4 s, special 0.07 s, and the suite judges its
        # groups after the last run, on its serial path; imported here, not at the top, so
        # srr suite starts without it
        from scipy.special import stdtrit

        half = float(stdtrit(n - 1, 0.975)) * std / math.sqrt(n)
        ci = (mean - half, mean + half)
    return Stats(n, mean, std, min(xs), max(xs), ci)
