"""The report's building blocks, without a run: PNG writer, ticks, formatting, graph layout."""

from __future__ import annotations

import numpy as np
import pytest

from harness.report.graphs import graph_diagrams, layout_depths
from harness.report.html import fmt_value, fmt_windows
from harness.report.images import encode_png, image_array
from harness.report.svg import Svg, decimate, nice_ticks, tick_label
from tests.report.pngread import read_png


@pytest.mark.parametrize("shape", [(7, 5, 3), (4, 9), (1, 1, 3), (120, 160, 3)])
def test_png_round_trip(shape: tuple[int, ...]) -> None:
    rng = np.random.default_rng(0)
    px = rng.integers(0, 256, size=shape, dtype=np.uint8)
    back = read_png(encode_png(px))
    assert back.shape[:2] == shape[:2]
    np.testing.assert_array_equal(back.reshape(px.shape), px)


def test_png_refuses_other_shapes() -> None:
    with pytest.raises(ValueError, match="pixels"):
        encode_png(np.zeros((2, 2, 4), dtype=np.uint8))


class _Image:
    def __init__(self, encoding: str, h: int, w: int, step: int, data: bytes) -> None:
        self.encoding, self.height, self.width, self.step, self.data = (encoding, h, w, step,
                                                                        data)


def test_image_array_reads_colour_and_skips_depth() -> None:
    px = np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3)
    padded = np.concatenate([px.reshape(2, 9), np.zeros((2, 3), np.uint8)], axis=1)
    rgb = image_array(_Image("rgb8", 2, 3, 12, padded.tobytes()))
    np.testing.assert_array_equal(rgb, px)
    bgr = image_array(_Image("bgr8", 2, 3, 9, px[:, :, ::-1].tobytes()))
    np.testing.assert_array_equal(bgr, px)
    assert image_array(_Image("32FC1", 2, 3, 12, bytes(24))) is None
    assert image_array(_Image("rgb8", 2, 3, 9, bytes(5))) is None  # truncated
    big = image_array(_Image("mono8", 480, 640, 640, bytes(480 * 640)))
    assert big is not None and big.shape == (240, 320)  # shrunk for the page


def test_nice_ticks_and_labels() -> None:
    assert nice_ticks(0, 36, 14) == [0, 5, 10, 15, 20, 25, 30, 35]
    assert nice_ticks(0, 0.19, 4) == [0, 0.05, 0.1, 0.15]
    t = nice_ticks(-15.5, 28.3, 12)
    assert t[0] >= -15.5 and t[-1] <= 28.3 and len(t) >= 8
    assert [tick_label(v, [0, 0.25]) for v in (0, 0.25, 0.5)] == ["0", "0.25", "0.50"]
    assert tick_label(-0.0, [0, 1]) == "0"


def test_decimate_keeps_peaks() -> None:
    x = np.linspace(0, 10, 100_000)
    y = np.sin(x)
    y[54_321] = 5.0
    dx, dy = decimate(x, y, 300)
    assert dx.size <= 4 * 300 + 2 and dy.max() == 5.0 and dy.min() == pytest.approx(-1, 1e-3)
    assert np.all(np.diff(dx) > 0)


def test_formatting() -> None:
    assert fmt_value(None, "m") == "—"
    assert fmt_value(86.6213, "%") == "86.62 %"
    assert fmt_value(1.0, "bool") == "yes" and fmt_value(0.0, "bool") == "no"
    assert fmt_value(3.0, "count") == "3" and fmt_value(0.0, "s", signed=True) == "0"
    assert fmt_value(1.5, "s", signed=True) == "+1.5 s"
    assert fmt_windows([(1.0, 2.5), (3.0, 3.0)]) == "1.00–2.50, @3.00"
    assert fmt_windows([(i, i + 1.0) for i in range(5)]).endswith("+2 more")


def test_svg_escapes_text() -> None:
    svg = Svg(10, 10, label='a "b" <c>')
    svg.text(1, 2, "<script>x</script>", title="t&")
    out = svg.render()
    assert "<script>" not in out and "&lt;script&gt;" in out and "t&amp;" in out


def test_layout_depths_follow_exec_and_data() -> None:
    nodes = ["Tick", "Ctx", "Sub", "IK", "Art"]
    edges = [("Tick", "Sub"), ("Ctx", "Sub"), ("Sub", "IK"), ("IK", "Art"), ("Sub", "Art")]
    assert layout_depths(nodes, edges) == {"Tick": 0, "Ctx": 0, "Sub": 1, "IK": 2, "Art": 3}
    cyc = layout_depths(["A", "B"], [("A", "B"), ("B", "A")])  # a cycle ends, capped
    assert max(cyc.values()) <= 2


def test_graph_diagram_draws_every_node_and_edge() -> None:
    stage = {"graphs": [{
        "path": "/World/G", "evaluator_name": "execution",
        "nodes": [{"name": "OnTick", "type": "omni.graph.action.OnPlaybackTick",
                   "canonical_type": "srr.OnPlaybackTick", "kind": "event", "values": {}},
                  {"name": "Time", "type": "t", "canonical_type": "srr.ReadSimulationTime",
                   "kind": "data", "values": {}},
                  {"name": "Pub<1>", "type": "p", "canonical_type": "srr.PublishClock",
                   "kind": "action", "values": {"inputs:topicName": "clock"}}],
        "connections": [{"src": "OnTick.outputs:tick", "dst": "Pub<1>.inputs:execIn",
                         "kind": "exec"},
                        {"src": "Time.outputs:simulationTime",
                         "dst": "Pub<1>.inputs:timeStamp", "kind": "data"}]}]}
    (d,) = graph_diagrams(stage)
    assert d.path == "/World/G" and d.nodes == 3 and d.connections == 2
    assert d.svg.count('class="g-node') == 3 and d.svg.count('class="g-edge') == 2
    assert "Pub&lt;1&gt;" in d.svg and "inputs:topicName = clock" in d.svg


@pytest.mark.parametrize("rows", [0, 1, 40])
def test_positions_per_frame_are_pandas_groups(rows: int) -> None:
    """The report's per-frame positions: what a groupby gives (same keys, each frame's rows in
    table order), for frames out of order and repeated."""
    import pandas as pd

    from harness.report.data import _xy_by_frame

    rng = np.random.default_rng(rows)
    df = pd.DataFrame({"frame": rng.integers(0, 7, rows), "x": rng.normal(size=rows),
                       "y": rng.normal(size=rows)})
    want = {int(k): g[["x", "y"]].to_numpy(np.float64)
            for k, g in df.groupby("frame", sort=False)}
    got = _xy_by_frame(df)
    assert sorted(got) == sorted(want)
    for k, xy in want.items():
        np.testing.assert_array_equal(got[k], xy)
