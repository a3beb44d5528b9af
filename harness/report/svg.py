"""A small SVG writer for the report: linear scales, tick choice, decimation, elements.

Everything is plain strings, so the report stays one self-contained file with no plotting
library and no script. Coordinates are rounded to 0.1 px to keep the file small.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from html import escape

import numpy as np

__all__ = ["Scale", "Svg", "decimate", "fmt_num", "nice_ticks", "tick_label"]


def fmt_num(v: float) -> str:
    """A coordinate: at most one decimal, no trailing zeros."""
    s = f"{v:.1f}"
    return s[:-2] if s.endswith(".0") else s


def nice_ticks(lo: float, hi: float, n: int = 6) -> list[float]:
    """Round tick values (1, 2, 2.5, 5 × 10^k steps) covering [lo, hi], about ``n`` of them."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return []
    if hi <= lo:
        return [lo]
    raw = (hi - lo) / max(n, 1)
    mag = 10.0 ** math.floor(math.log10(raw))
    step = next((m * mag for m in (1.0, 2.0, 2.5, 5.0, 10.0) if m * mag >= raw), 10.0 * mag)
    first = math.ceil(lo / step - 1e-9) * step
    out = []
    v = first
    while v <= hi + step * 1e-9:
        out.append(0.0 if abs(v) < step * 1e-9 else round(v, 10))
        v += step
    return out


def tick_label(v: float, ticks: Sequence[float]) -> str:
    """``v`` with as many decimals as the tick step needs (0.25 steps get two)."""
    step = abs(ticks[1] - ticks[0]) if len(ticks) > 1 else 1.0
    decimals = max(0, -math.floor(math.log10(step))) if step > 0 else 0
    while decimals < 6 and abs(step * 10**decimals - round(step * 10**decimals)) > 1e-6:
        decimals += 1
    text = f"{v:.{decimals}f}"
    return "0" if text.strip("-0.") == "" else text


class Scale:
    """Linear map from a data interval onto a pixel interval (``r0`` may exceed ``r1``)."""

    def __init__(self, d0: float, d1: float, r0: float, r1: float) -> None:
        if not (math.isfinite(d0) and math.isfinite(d1)) or d1 == d0:
            d0, d1 = (d0 - 0.5, d0 + 0.5) if math.isfinite(d0) else (0.0, 1.0)
        self.d0, self.d1, self.r0, self.r1 = float(d0), float(d1), float(r0), float(r1)
        self.k = (self.r1 - self.r0) / (self.d1 - self.d0)

    def __call__(self, v: float) -> float:
        return self.r0 + (float(v) - self.d0) * self.k

    def array(self, v: np.ndarray) -> np.ndarray:
        return self.r0 + (np.asarray(v, dtype=np.float64) - self.d0) * self.k


def decimate(x: np.ndarray, y: np.ndarray, buckets: int) -> tuple[np.ndarray, np.ndarray]:
    """At most ~4 points per bucket (first, min, max, last), keeping peaks; ``x`` sorted."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    n = x.size
    if n <= 4 * buckets or buckets < 1:
        return x, y
    edges = np.linspace(x[0], x[-1], buckets + 1)
    which = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, buckets - 1)
    starts = np.flatnonzero(np.concatenate(([True], which[1:] != which[:-1])))
    ends = np.concatenate((starts[1:], [n])) - 1
    keep = np.zeros(n, dtype=bool)
    keep[starts] = True
    keep[ends] = True
    finite = np.where(np.isfinite(y), y, np.nan)
    for s, e in zip(starts, ends, strict=True):
        seg = finite[s:e + 1]
        if np.isnan(seg).all():
            continue
        keep[s + int(np.nanargmin(seg))] = True
        keep[s + int(np.nanargmax(seg))] = True
    return x[keep], y[keep]


def _attrs(attrs: dict[str, object]) -> str:
    parts = []
    for k, v in attrs.items():
        if v is None or v is False:
            continue
        name = k.rstrip("_").replace("_", "-")
        val = fmt_num(v) if isinstance(v, float) else str(v)
        parts.append(f' {name}="{escape(val, quote=True)}"')
    return "".join(parts)


class Svg:
    """An SVG document built element by element. Keyword attributes use ``_`` for ``-``
    (``stroke_width``) and a trailing ``_`` for Python keywords (``class_``)."""

    def __init__(self, width: float, height: float, *, label: str = "",
                 class_: str = "plot") -> None:
        self.width, self.height = width, height
        self.parts: list[str] = []
        self.label = label
        self.class_ = class_

    def add(self, raw: str) -> None:
        self.parts.append(raw)

    def el(self, tag: str, text: str | None = None, **attrs: object) -> None:
        """``<tag attrs>text<title>…</title></tag>``; a ``title`` attribute becomes the
        element's tooltip."""
        self._emit(tag, dict(attrs), text)

    def _emit(self, tag: str, attrs: dict[str, object], text: str | None = None) -> None:
        title = attrs.pop("title", None)
        inner = (escape(text, quote=False) if text is not None else "") + (
            f"<title>{escape(str(title), quote=False)}</title>" if title else "")
        self.parts.append(f"<{tag}{_attrs(attrs)}>{inner}</{tag}>" if inner
                          else f"<{tag}{_attrs(attrs)}/>")

    def open(self, tag: str = "g", **attrs: object) -> None:
        self.parts.append(f"<{tag}{_attrs(attrs)}>")

    def close(self, tag: str = "g") -> None:
        self.parts.append(f"</{tag}>")

    def line(self, x1: float, y1: float, x2: float, y2: float, **attrs: object) -> None:
        self._emit("line", {"x1": float(x1), "y1": float(y1), "x2": float(x2),
                            "y2": float(y2), **attrs})

    def rect(self, x: float, y: float, w: float, h: float, **attrs: object) -> None:
        self._emit("rect", {"x": float(x), "y": float(y), "width": float(max(w, 0.0)),
                            "height": float(max(h, 0.0)), **attrs})

    def circle(self, cx: float, cy: float, r: float, **attrs: object) -> None:
        self._emit("circle", {"cx": float(cx), "cy": float(cy), "r": float(r), **attrs})

    def text(self, x: float, y: float, text: str, **attrs: object) -> None:
        self._emit("text", {"x": float(x), "y": float(y), **attrs}, text)

    def polyline(self, xs: Iterable[float], ys: Iterable[float], **attrs: object) -> None:
        for chunk in _points(xs, ys):
            if len(chunk) > 1:
                self._emit("polyline", {"points": " ".join(chunk), "fill": "none", **attrs})

    def polygon(self, xs: Iterable[float], ys: Iterable[float], **attrs: object) -> None:
        chunks = _points(xs, ys)
        if chunks and len(chunks[0]) > 2:
            self._emit("polygon", {"points": " ".join(chunks[0]), **attrs})

    def path(self, d: str, **attrs: object) -> None:
        self._emit("path", {"d": d, **attrs})

    def render(self) -> str:
        aria = f' role="img" aria-label="{escape(self.label, quote=True)}"' if self.label else ""
        return (f'<svg class="{self.class_}" '
                f'viewBox="0 0 {fmt_num(self.width)} {fmt_num(self.height)}" '
                f'width="{fmt_num(self.width)}" height="{fmt_num(self.height)}"'
                f'{aria}>' + "".join(self.parts) + "</svg>")


def _points(xs: Iterable[float], ys: Iterable[float]) -> list[list[str]]:
    """"x,y" strings, split into runs at non-finite values."""
    runs: list[list[str]] = [[]]
    for x, y in zip(xs, ys, strict=True):
        if math.isfinite(x) and math.isfinite(y):
            runs[-1].append(f"{fmt_num(x)},{fmt_num(y)}")
        elif runs[-1]:
            runs.append([])
    return [r for r in runs if r]
