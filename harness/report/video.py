"""The report's camera videos: each camera's recording as a WebM file beside ``report.html``,
and short clips around what the reviewer should look at first.

Where they live: ``<run_dir>/video/<topic>.webm`` and ``video/clips/cNN-<topic>.webm``, with
``video/videos.json`` listing them (the diff page reads it to play a run's videos). The page
links them relatively, so it works from ``file://`` with no server. They are report
artifacts: the bag is only read.

Sources: per camera image stream the bag's best colour recording of it — a raw
``sensor_msgs/Image``, else a JPEG or PNG ``sensor_msgs/CompressedImage``, else the h264
``foxglove_msgs/CompressedVideo`` (decoded) — the same decoders as the keyframes
(:mod:`harness.report.images`). Depth streams are left out.

Time: a frame is shown from its log time (simulation time) on. A file's time 0 is its
first frame's log time (``t0_s``, in the manifest and on the page's ``<video>`` as
``data-t0``): simulation time ``t`` is video time ``t - t0_s``. Each frame keeps its own
timestamp (milliseconds), so a camera's frame rate, even an uneven one, is kept as recorded.

Cost bounds: frames wider than :data:`MAX_WIDTH` are shrunk by an integer factor, frames
closer than ``1 / MAX_FPS`` to the last kept one are dropped, at most :data:`MAX_CLIPS`
clips of at most :data:`MAX_CLIP_S` each. The encoder is :class:`harness.video.codec.WebmWriter`
(VP9 by default: with its settings the same frames give the same bytes).
"""

from __future__ import annotations

import itertools
import json
import re
import shutil
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from harness.errors import SrrError
from harness.recording.bagread import open_indexed
from harness.report.images import COMPRESSED_TYPE, IMAGE_TYPE, VIDEO_TYPE, image_array
from harness.video.codec import H264Decoder, WebmSettings, WebmWriter
from harness.video.errors import VideoError

__all__ = ["CLIP_PAD_S", "MANIFEST", "MAX_CLIPS", "MAX_CLIP_S", "MAX_FPS", "MAX_WIDTH",
           "VIDEO_DIR", "Clip", "ClipSpec", "VideoFile", "VideoSet", "camera_sources",
           "read_videos", "remove_videos", "write_videos"]

VIDEO_DIR = "video"
MANIFEST = "videos.json"
MAX_WIDTH = 640  # px: wider frames are shrunk by an integer factor
MAX_FPS = 30.0
CLIP_PAD_S = 1.5  # s before and after what a clip shows
MAX_CLIP_S = 8.0
MAX_CLIPS = 12

#: Preference among the recordings of one camera stream (lower first).
_RANK = {IMAGE_TYPE: 0, COMPRESSED_TYPE: 1, VIDEO_TYPE: 2}
_SUFFIX = {COMPRESSED_TYPE: "/compressed", VIDEO_TYPE: "/h264"}


@dataclass(frozen=True)
class ClipSpec:
    """A stretch of the run worth a clip: ``label`` says why, ``at_s`` is the time it is
    about (a moment, a window's start), ``start_s``/``end_s`` what the clip covers."""

    label: str
    at_s: float
    start_s: float
    end_s: float
    kind: str  # "metric" or "moment"


@dataclass(frozen=True)
class VideoFile:
    """One WebM file: the camera ``topic`` it shows, its ``file`` relative to the report's
    folder (``/`` separated), the simulation time of its first frame (``t0_s``) and of its
    last (``last_s``), its size in pixels, frames and bytes."""

    topic: str
    file: str
    t0_s: float
    last_s: float
    width: int
    height: int
    frames: int
    bytes: int
    codec: str


@dataclass(frozen=True)
class Clip:
    spec: ClipSpec
    files: tuple[VideoFile, ...]


@dataclass(frozen=True)
class VideoSet:
    """What :func:`write_videos` wrote: one :class:`VideoFile` per camera stream, the clips;
    ``root`` the folder the files' paths are relative to (the report's)."""

    videos: tuple[VideoFile, ...]
    clips: tuple[Clip, ...] = ()
    codec: str = "vp9"
    root: str = ""

    def path(self, f: VideoFile) -> Path:
        """Where the file ``f`` lies."""
        return Path(self.root) / f.file

    @property
    def bytes(self) -> int:
        return sum(v.bytes for v in self.videos) + sum(f.bytes for c in self.clips
                                                       for f in c.files)

    def to_json(self) -> dict[str, Any]:
        return {"format": "srr-videos/1", "codec": self.codec,
                "videos": [asdict(v) for v in self.videos],
                "clips": [{"spec": asdict(c.spec), "files": [asdict(f) for f in c.files]}
                          for c in self.clips]}


def _slug(topic: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", topic.strip("/")) or "camera"


def camera_sources(connections: Sequence[Any]) -> list[list[Any]]:
    """The image connections of a bag grouped by the camera stream they record (a raw topic
    and its ``/compressed`` and ``/h264`` recordings), each group best first (raw, then
    JPEG/PNG, then h264), groups in topic order."""
    groups: dict[str, list[Any]] = {}
    for c in connections:
        if c.msgtype not in _RANK:
            continue
        base = c.topic
        suffix = _SUFFIX.get(c.msgtype)
        if suffix and base.endswith(suffix):
            base = base[:-len(suffix)]
        groups.setdefault(base, []).append(c)
    return [sorted(g, key=lambda c: (_RANK[c.msgtype], c.topic))
            for _, g in sorted(groups.items())]


def _even_rgb(px: np.ndarray) -> np.ndarray:
    a = px if px.ndim == 3 else np.repeat(px[:, :, None], 3, axis=2)
    factor = -(-a.shape[1] // MAX_WIDTH)
    if factor > 1:
        a = a[::factor, ::factor]
    h, w = a.shape[0] & ~1, a.shape[1] & ~1
    return np.ascontiguousarray(a[:h, :w, :3])


def _frames(reader: Any, conn: Any) -> Iterator[tuple[int, np.ndarray | None]]:
    """(log time, pixels or None: not a colour image) of every message of ``conn``."""
    decoder = H264Decoder() if conn.msgtype == VIDEO_TYPE else None
    for _, ts, raw in reader.messages(connections=[conn]):
        msg: Any = reader.decode(raw, conn)
        if decoder is not None:
            try:
                out = decoder.decode(bytes(msg.data))
            except VideoError:
                continue  # a damaged access unit: the frames around it still show
            if out:
                yield ts, out[-1]
            continue
        yield ts, image_array(msg, max_width=None)


@dataclass
class _Open:
    writer: WebmWriter
    file: str
    t0_ns: int
    last_ns: int


def _close(o: _Open, topic: str, codec: str) -> VideoFile:
    o.writer.close()
    return VideoFile(topic, o.file, o.t0_ns / 1e9, o.last_ns / 1e9, o.writer.width,
                     o.writer.height, o.writer.frames, o.writer.path.stat().st_size, codec)


def _encode_topic(reader: Any, group: Sequence[Any], root: Path, clips: Sequence[ClipSpec],
                  fps: float, settings: WebmSettings
                  ) -> tuple[VideoFile | None, list[VideoFile | None]]:
    """The whole-run video of one camera stream and its clips (None: no frame in a clip)."""
    for conn in group:  # the best recording that holds colour images
        frames = _frames(reader, conn)
        first = next(frames, None)
        if first is None or first[1] is None:  # depth, or no frame at all
            continue
        topic = group[0].topic if group[0].msgtype == IMAGE_TYPE else conn.topic
        name = _slug(topic)
        n = 1
        while (root / f"{name}.webm").exists():  # "/a/b" and "/a_b": one name, two files
            n += 1
            name = f"{_slug(topic)}-{n}"
        main: _Open | None = None
        open_clips: dict[int, _Open] = {}
        done: dict[int, VideoFile] = {}
        min_gap = int(1e9 / MAX_FPS) - 1
        last_kept = -(2**62)

        for ts, px in itertools.chain([first], frames):
            if px is None or ts - last_kept < min_gap:
                continue
            last_kept = ts
            a = _even_rgb(px)
            h, w = a.shape[:2]
            if main is None:
                main = _Open(WebmWriter(root / f"{name}.webm", w, h, fps, settings),
                             f"{VIDEO_DIR}/{name}.webm", ts, ts)
            if (h, w) != (main.writer.height, main.writer.width):
                continue  # a frame of another size (a resized stream): left out
            main.writer.add(a, round((ts - main.t0_ns) / 1e6))
            main.last_ns = ts
            t_s = ts / 1e9
            for k, spec in enumerate(clips):
                if k in done:
                    continue
                o = open_clips.get(k)
                if spec.start_s <= t_s <= spec.end_s:
                    if o is None:
                        rel = f"clips/c{k + 1:02d}-{name}.webm"
                        (root / "clips").mkdir(exist_ok=True)
                        o = open_clips[k] = _Open(WebmWriter(root / rel, w, h, fps, settings),
                                                  f"{VIDEO_DIR}/{rel}", ts, ts)
                    o.writer.add(a, round((ts - o.t0_ns) / 1e6))
                    o.last_ns = ts
                elif o is not None and t_s > spec.end_s:
                    done[k] = _close(open_clips.pop(k), topic, settings.codec)
        for k, o in open_clips.items():
            done[k] = _close(o, topic, settings.codec)
        assert main is not None
        return (_close(main, topic, settings.codec),
                [done.get(k) for k in range(len(clips))])
    return None, [None] * len(clips)


def write_videos(bag_dir: Path, report_dir: Path, clips: Sequence[ClipSpec] = (), *,
                 rates_hz: Mapping[str, float] | None = None,
                 settings: WebmSettings | None = None) -> VideoSet | None:
    """Encode every camera stream of the bag (and the ``clips`` of each) into
    ``report_dir/video/`` with its manifest; returns what was written, or None (and no
    ``video/`` folder) when the bag has no colour camera images.

    The files are written into a temporary folder that replaces ``video/`` only once every
    file is complete: a failure (:class:`SrrError`) leaves the previous videos as they were.
    ``rates_hz``: topic → message rate (the summary's), the nominal frame rate of each;
    ``settings``: the encoder's (VP9, CRF 30, a keyframe every 2 s by default)."""
    settings = settings or WebmSettings()
    clips = list(clips)[:MAX_CLIPS]
    final = report_dir / VIDEO_DIR
    tmp = report_dir / f".{VIDEO_DIR}.tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    try:
        videos: list[VideoFile] = []
        per_clip: list[list[VideoFile]] = [[] for _ in clips]
        with open_indexed(bag_dir) as reader:
            for group in camera_sources(reader.connections):
                rate = next((float(r) for c in group
                             if (r := (rates_hz or {}).get(c.topic)) and r > 0), 10.0)
                main, cl = _encode_topic(reader, group, tmp, clips, min(rate, MAX_FPS),
                                         settings)
                if main is not None:
                    videos.append(main)
                for k, f in enumerate(cl):
                    if f is not None:
                        per_clip[k].append(f)
        if not videos:
            shutil.rmtree(tmp, ignore_errors=True)
            remove_videos(report_dir)
            return None
        result = VideoSet(tuple(videos),
                          tuple(Clip(s, tuple(fs)) for s, fs in zip(clips, per_clip,
                                                                     strict=True) if fs),
                          settings.codec, str(report_dir))
        (tmp / MANIFEST).write_text(json.dumps(result.to_json(), indent=1) + "\n",
                                    encoding="utf-8")
        old = report_dir / f".{VIDEO_DIR}.old"
        shutil.rmtree(old, ignore_errors=True)
        if final.exists():
            final.rename(old)
        tmp.rename(final)
        shutil.rmtree(old, ignore_errors=True)
        return result
    except SrrError as err:  # a bag that does not open
        shutil.rmtree(tmp, ignore_errors=True)
        raise SrrError(f"{final}: the camera videos could not be written: {err}") from err
    except Exception as err:  # a damaged chunk or message, a full disk: the videos only
        shutil.rmtree(tmp, ignore_errors=True)
        raise SrrError(f"{final}: the camera videos could not be written "
                       f"({type(err).__name__}: {err})") from err
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def remove_videos(report_dir: Path) -> None:
    """Remove ``report_dir/video/`` (a report rendered without videos must not link stale
    ones)."""
    shutil.rmtree(report_dir / VIDEO_DIR, ignore_errors=True)


def _file(d: dict[str, Any]) -> VideoFile:
    return VideoFile(str(d["topic"]), str(d["file"]), float(d["t0_s"]), float(d["last_s"]),
                     int(d["width"]), int(d["height"]), int(d["frames"]), int(d["bytes"]),
                     str(d["codec"]))


def read_videos(report_dir: Path) -> VideoSet | None:
    """The videos :func:`write_videos` left in ``report_dir`` (None: none, or a manifest that
    does not read, or names a file that is not there)."""
    path = report_dir / VIDEO_DIR / MANIFEST
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
        videos = tuple(_file(v) for v in raw["videos"])
        clips = tuple(Clip(ClipSpec(**c["spec"]), tuple(_file(f) for f in c["files"]))
                      for c in raw.get("clips", []))
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if not videos or not all((report_dir / v.file).is_file() for v in videos):
        return None
    return VideoSet(videos, clips, str(raw.get("codec", "vp9")), str(report_dir))
