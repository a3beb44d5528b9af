"""WebmWriter: the report's video files, VP9 (or AV1) in WebM through PyAV, each frame at its
own time, the same bytes for the same frames."""

from __future__ import annotations

from pathlib import Path

import av
import numpy as np
import pytest

from harness.video.codec import WebmSettings, WebmWriter, psnr
from harness.video.errors import VideoError


def _frames(n: int) -> list[np.ndarray]:
    out = []
    for i in range(n):
        a = np.full((48, 64, 3), 40, np.uint8)
        a[:, (i * 5) % 48:(i * 5) % 48 + 16] = (220, 60, 30)  # a bar moving right
        out.append(a)
    return out


def _write(path: Path, frames: list[np.ndarray], times: list[int],
           settings: WebmSettings | None = None) -> None:
    w = WebmWriter(path, 64, 48, 5, settings or WebmSettings())
    for f, t in zip(frames, times, strict=True):
        w.add(f, t)
    w.close()


@pytest.mark.parametrize("codec", ["vp9", "av1"])
def test_frames_keep_their_times_and_pixels(codec: str, tmp_path: Path) -> None:
    frames = _frames(12)
    times = [0, 200, 400, 650, 800, 1000, 1200, 1400, 1600, 1800, 2000, 2300]  # uneven
    _write(tmp_path / "a.webm", frames, times, WebmSettings(codec=codec))  # type: ignore[arg-type]
    with av.open(str(tmp_path / "a.webm")) as c:
        stream = c.streams.video[0]
        assert c.format.name.startswith("matroska,webm")
        assert stream.codec_context.name in {"vp9": ("vp9", "libvpx-vp9"),
                                             "av1": ("av1", "libdav1d", "libaom-av1")}[codec]
        decoded = list(c.decode(video=0))
    assert [round(float(f.pts * f.time_base) * 1000) for f in decoded] == times
    for k, f in enumerate(decoded):  # each decoded frame is its own source frame's image
        scores = [psnr(f.to_ndarray(format="rgb24"), want) for want in frames]
        assert scores[k] > 25 and int(np.argmax(scores)) == k


def test_same_frames_same_bytes(tmp_path: Path) -> None:
    frames, times = _frames(20), [k * 200 for k in range(20)]
    _write(tmp_path / "a.webm", frames, times)
    _write(tmp_path / "b.webm", frames, times)
    assert (tmp_path / "a.webm").read_bytes() == (tmp_path / "b.webm").read_bytes()


def test_times_that_do_not_increase_are_moved_after_the_last(tmp_path: Path) -> None:
    _write(tmp_path / "a.webm", _frames(3), [0, 0, 0])
    with av.open(str(tmp_path / "a.webm")) as c:
        assert [f.pts for f in c.decode(video=0)] == [0, 1, 2]


def test_odd_size_and_wrong_frame_are_refused(tmp_path: Path) -> None:
    with pytest.raises(VideoError, match="even width and height"):
        WebmWriter(tmp_path / "odd.webm", 63, 48, 5)
    w = WebmWriter(tmp_path / "a.webm", 64, 48, 5)
    with pytest.raises(VideoError, match="expected a 64x48 RGB frame"):
        w.add(np.zeros((48, 62, 3), np.uint8), 0)
    w.close()
