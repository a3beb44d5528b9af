"""Plain geometry for zones: point-in-polygon and the side of a tripwire. No shapely needed;
metrics and systems under test share these so they agree on the edges."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from harness.geometry import side_of_line  # shared with the scenario checks

__all__ = ["point_in_polygon", "points_in_polygon", "side_of_line"]


def points_in_polygon(points: np.ndarray, polygon: np.ndarray | Sequence[Sequence[float]]
                      ) -> np.ndarray:
    """Even-odd rule for (N, 2) points against a closed polygon given as (M, 2) vertices."""
    poly = np.asarray(polygon, dtype=np.float64)
    x, y = points[:, 0], points[:, 1]
    inside = np.zeros(len(points), dtype=bool)
    j = len(poly) - 1
    for i in range(len(poly)):
        xi, yi = poly[i]
        xj, yj = poly[j]
        crosses = (yi > y) != (yj > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_at = (xj - xi) * (y - yi) / (yj - yi) + xi
        inside ^= crosses & (x < x_at)
        j = i
    return inside


def point_in_polygon(x: float, y: float, polygon: Sequence[Sequence[float]]) -> bool:
    return bool(points_in_polygon(np.array([[x, y]]), polygon)[0])
