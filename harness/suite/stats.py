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
        # here, not at the top: SciPy's stats take a quarter of srr's import time, and the
        # suite needs them only once its runs are done (srr suite starts faster)
        from scipy import stats as _st

        half = float(_st.t.ppf(0.975, n - 1)) * std / math.sqrt(n)
        ci = (mean - half, mean + half)
    return Stats(n, mean, std, min(xs), max(xs), ci)
