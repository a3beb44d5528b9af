"""Hand-built :class:`Frames` for metric tests: give the tables a test needs, the rest empty."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from harness.frames import Frames

TICK_HZ = 60


def t_ns(k: int | np.ndarray) -> Any:
    """Stamp of tick ``k`` at 60 Hz, computed the way the engine does."""
    return np.asarray(k, dtype=np.int64) * 1_000_000_000 // TICK_HZ


def _empty(cols: dict[str, str]) -> pd.DataFrame:
    return pd.DataFrame({k: pd.Series(dtype=v) for k, v in cols.items()})


EMPTY = {
    "clock": {"t_ns": "int64", "log_ns": "int64"},
    "gt_poses": {"t_ns": "int64", "name": "str", "x": "float64", "y": "float64",
                 "z": "float64", "yaw": "float64"},
    "odom": {"t_ns": "int64", "topic": "str", "frame": "str", "x": "float64", "y": "float64",
             "yaw": "float64", "vx": "float64", "wz": "float64"},
    "cmd_vel": {"t_ns": "int64", "topic": "str", "vx": "float64", "wz": "float64"},
    "tracks": {"frame": "int64", "t_ns": "int64", "topic": "str", "cls": "str",
               "track_id": "int64", "x": "float64", "y": "float64"},
    "track_frames": {"frame": "int64", "t_ns": "int64", "log_ns": "int64", "topic": "str"},
    "muted": {"t_ns": "int64", "value": "bool"},
    "topics": {"name": "str", "type": "str", "count": "int64", "first_ns": "int64",
               "last_ns": "int64", "max_gap_ns": "int64"},
    "tf_static": {"parent": "str", "child": "str", "x": "float64", "y": "float64",
                  "z": "float64", "qx": "float64", "qy": "float64", "qz": "float64",
                  "qw": "float64"},
    "tf": {"t_ns": "int64", "log_ns": "int64", "topic": "str", "tree": "str",
           "static": "bool", "parent": "str", "child": "str", "x": "float64", "y": "float64",
           "z": "float64", "qx": "float64", "qy": "float64", "qz": "float64", "qw": "float64"},
}


def make_frames(**tables: pd.DataFrame) -> Frames:
    full = {k: tables.get(k, _empty(v)) for k, v in EMPTY.items()}
    stamps = [int(t) for df in full.values() if "t_ns" in df and len(df)
              for t in (df["t_ns"].min(), df["t_ns"].max())]
    return Frames(**full, start_ns=min(stamps, default=0), end_ns=max(stamps, default=0),
                  message_count=0)


def gt_rows(name: str, ticks: np.ndarray, x: np.ndarray, y: np.ndarray,
            yaw: np.ndarray | float = 0.0) -> pd.DataFrame:
    n = len(ticks)
    return pd.DataFrame({"t_ns": t_ns(ticks), "name": [name] * n,
                         "x": np.asarray(x, dtype=float), "y": np.asarray(y, dtype=float),
                         "z": np.zeros(n), "yaw": np.broadcast_to(yaw, (n,)).astype(float)})
