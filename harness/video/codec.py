"""Encoders and decoders for camera images: h264 video, WebM (VP9/AV1) files, JPEG and PNG
stills, PNG depth.

Everything goes through PyAV (FFmpeg; its wheels ship libx264 and the NVENC encoders), so the
bag path and the RTSP streams share one implementation.

* :class:`H264Encoder`: one access unit (Annex B) per frame, no B-frames and no lookahead
  (``tune=zerolatency``), so each frame's packet comes out at once and decodes on its own
  given the frames before it (what Foxglove's ``CompressedVideo`` asks for). A keyframe (IDR,
  with SPS and PPS in front of it) opens the stream and comes every ``keyframe_interval``
  frames, and whenever :meth:`H264Encoder.encode` is asked for one (a new RTSP client);
  scene-cut keyframes are off. Every access unit carries its simulation time
  (:mod:`harness.video.sei`). ``x264`` runs on the CPU and, with ``threads`` fixed, gives the
  same bytes for the same frames on every run; ``nvenc`` runs on an NVIDIA GPU's video
  engine (see :data:`ENCODERS`).
* :class:`WebmWriter`: a WebM file of RGB frames for a browser (the report's videos): VP9
  (``libvpx-vp9``) or AV1 (``libsvtav1``), both played by every current browser, unlike h264.
  Each frame keeps its own timestamp (milliseconds from the first frame: a variable frame
  rate is kept as recorded). VP9 with one thread and FFmpeg's ``bitexact`` muxing gives the
  same bytes for the same frames on every run.
* :func:`encode_jpeg`, :func:`encode_png`: ``sensor_msgs/CompressedImage`` payloads of an
  RGB frame (FFmpeg's ``bitexact`` mode: no version string, the same bytes everywhere the
  codec is the same).
* :func:`encode_depth_png` / :func:`decode_depth_png`: depth (float32 metres, ``+inf`` for
  no return) as a 16-bit grey PNG of millimetres, 0 = no return (``16UC1``, REP 118's
  convention): lossless for the millimetre grid, 0.5 mm at most off, 65.535 m at most.
"""

from __future__ import annotations

import fractions
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from harness.video.errors import VideoError
from harness.video.sei import insert_sim_time

__all__ = [
    "DEPTH_PNG_FORMAT",
    "ENCODERS",
    "WEBM_ENCODERS",
    "EncodedFrame",
    "H264Decoder",
    "H264Encoder",
    "H264Settings",
    "WebmSettings",
    "WebmWriter",
    "check_encoder",
    "decode_depth_png",
    "decode_image",
    "decode_rgb",
    "depth_to_mm",
    "encode_depth_png",
    "encode_jpeg",
    "encode_png",
    "psnr",
    "reformatter",
    "settings_of",
]

#: ``encoder`` setting → FFmpeg encoder name.
ENCODERS: dict[str, str] = {"x264": "libx264", "nvenc": "h264_nvenc"}

#: ``sensor_msgs/CompressedImage.format`` of a depth image (image_transport's
#: "<raw encoding>; <codec>" form, which its compressed subscriber decodes to 16UC1).
DEPTH_PNG_FORMAT = "16UC1; png"

_NS = fractions.Fraction(1, 1_000_000_000)
# BT.601 limited range, written into the stream's VUI so that every decoder converts back
# with the matrix the encoder used.
_SMPTE170M = 6


def _av() -> Any:
    try:
        import av
    except ImportError as err:  # pragma: no cover - av is a dependency
        raise VideoError("video encoding needs PyAV (pip install av)") from err
    return av


@dataclass(frozen=True)
class H264Settings:
    """How :class:`H264Encoder` encodes.

    ``encoder``: ``x264`` (CPU) or ``nvenc`` (NVIDIA GPU). ``keyframe_interval``: frames from
    one keyframe to the next. ``crf``: constant quality (x264's CRF; NVENC's ``cq``), 0-51,
    lower is better; used unless ``bitrate_kbps`` is set (then a constant bit rate with a
    one-second buffer, as streaming servers expect). ``threads``: x264's encoder threads
    (1 by default: with a fixed count x264 is deterministic, and the count must not depend on
    the machine); ignored by NVENC. ``preset``: the encoder's speed preset (x264
    ``ultrafast`` … ``veryslow``, NVENC ``p1`` … ``p7``); None: ``veryfast`` / ``p4``."""

    encoder: Literal["x264", "nvenc"] = "x264"
    keyframe_interval: int = 30
    crf: int = 23
    bitrate_kbps: int | None = None
    threads: int = 1
    preset: str | None = None

    def options(self) -> dict[str, str]:
        """The FFmpeg encoder options for these settings."""
        if self.encoder == "x264":
            opts = {"preset": self.preset or "veryfast", "tune": "zerolatency",
                    "forced-idr": "1",
                    # keyframes exactly every keyframe_interval frames, no scene cuts
                    "x264-params": f"scenecut=0:keyint={self.keyframe_interval}:"
                                   f"min-keyint={self.keyframe_interval}"}
            if self.bitrate_kbps is None:
                opts["crf"] = str(self.crf)
            return opts
        opts = {"preset": self.preset or "p4", "tune": "ll", "zerolatency": "1", "delay": "0",
                "forced-idr": "1", "bf": "0", "no-scenecut": "1"}
        if self.bitrate_kbps is None:
            opts.update({"rc": "vbr", "cq": str(self.crf)})
        else:
            opts["rc"] = "cbr"
        return opts


@dataclass(frozen=True)
class EncodedFrame:
    """One encoded access unit: Annex B bytes, whether it is a keyframe, its simulation time
    and its index in the stream."""

    data: bytes
    keyframe: bool
    time_ns: int
    index: int


class H264Encoder:
    """Encodes ``(h, w, 3)`` uint8 RGB frames of one size to h264 access units.

    The FFmpeg encoder is opened on the first frame (so building a graph never needs one).
    An encoder that cannot open — ``nvenc`` without an NVIDIA GPU and driver, say — raises
    :class:`~harness.video.errors.VideoError` with FFmpeg's reason."""

    def __init__(self, width: int, height: int, fps: float, settings: H264Settings,
                 where: str = "h264") -> None:
        if width % 2 or height % 2:
            raise VideoError(f"{where}: h264 (4:2:0) needs an even width and height, got "
                             f"{width}x{height}")
        self.width, self.height = int(width), int(height)
        self.fps = float(fps)
        self.settings = settings
        self.where = where
        self._cc: Any = None
        self._reformat: Any = None
        self._count = 0
        self._times: dict[int, tuple[int, int]] = {}  # pts → (time_ns, index)

    @property
    def frames(self) -> int:
        """Frames handed to the encoder so far."""
        return self._count

    def _open(self) -> Any:
        av = _av()
        import av.logging as av_logging

        level = av_logging.get_level()
        try:
            with av_logging.Capture() as logs:
                av_logging.set_level(av_logging.ERROR)  # FFmpeg's reason, for the message
                return self._open_codec(av)
        except VideoError as err:
            why = " ".join(m.strip() for lvl, _n, m in logs if lvl <= av_logging.ERROR)
            raise VideoError(f"{err}{': ' + why if why else ''}") from err.__cause__
        finally:
            av_logging.set_level(level)

    def _open_codec(self, av: Any) -> Any:
        s = self.settings
        try:
            cc = av.CodecContext.create(ENCODERS[s.encoder], "w")
            cc.width, cc.height, cc.pix_fmt = self.width, self.height, "yuv420p"
            cc.time_base = _NS
            cc.framerate = fractions.Fraction(self.fps).limit_denominator(1001)
            cc.gop_size = s.keyframe_interval
            cc.max_b_frames = 0
            cc.thread_count = s.threads if s.encoder == "x264" else 0
            if s.bitrate_kbps is not None:
                cc.bit_rate = s.bitrate_kbps * 1000
                cc.rc_max_rate = cc.bit_rate
                cc.rc_buffer_size = cc.bit_rate
            cc.color_range = 1  # MPEG (limited)
            cc.colorspace = _SMPTE170M
            cc.color_primaries = _SMPTE170M
            cc.color_trc = _SMPTE170M
            cc.options = s.options()
            cc.open()
        except (av.FFmpegError, ValueError, KeyError) as err:
            reason = getattr(err, "strerror", None) or str(err)
            raise VideoError(f"{self.where}: cannot open the {s.encoder} h264 encoder "
                             f"({ENCODERS.get(s.encoder, s.encoder)}): {reason}") from err
        return cc

    def encode(self, rgb: np.ndarray, time_ns: int, *, keyframe: bool = False,
               index: int | None = None) -> list[EncodedFrame]:
        """Encode one frame taken at ``time_ns``; ``keyframe`` forces an IDR. ``index`` is
        the frame's number in the stream (default: frames encoded so far); frames whose
        index is a multiple of ``keyframe_interval`` are keyframes. Returns the access
        units that came out (one per frame with both encoders' settings here)."""
        av = _av()
        if self._cc is None:
            self._cc = self._open()
        a = np.ascontiguousarray(rgb, dtype=np.uint8)
        if a.shape != (self.height, self.width, 3):
            raise VideoError(f"{self.where}: expected a {self.width}x{self.height} RGB frame, "
                             f"got shape {a.shape}")
        index = self._count if index is None else int(index)
        self._count += 1
        if self._reformat is None:
            self._reformat = reformatter()
        frame = self._reformat.reformat(av.VideoFrame.from_ndarray(a, format="rgb24"),
                                        format="yuv420p", dst_colorspace="ITU601",
                                        dst_color_range="MPEG")
        frame.pts = int(time_ns)
        if keyframe or index % self.settings.keyframe_interval == 0:
            frame.pict_type = av.video.frame.PictureType.I
        self._times[int(time_ns)] = (int(time_ns), index)
        try:
            packets = self._cc.encode(frame)
        except av.FFmpegError as err:
            raise VideoError(f"{self.where}: encoding failed: {err}") from err
        return [self._wrap(p) for p in packets]

    def _wrap(self, packet: Any) -> EncodedFrame:
        t, index = self._times.pop(int(packet.pts), (int(packet.pts), -1))
        data = insert_sim_time(bytes(packet), t, index)
        return EncodedFrame(data, bool(packet.is_keyframe), t, index)

    def flush(self) -> list[EncodedFrame]:
        """Whatever the encoder still holds (nothing, with the settings used here)."""
        if self._cc is None:
            return []
        out = [self._wrap(p) for p in self._cc.encode(None)]
        self._cc = None
        return out


class H264Decoder:
    """Decodes h264 access units (Annex B) one by one to ``(h, w, 3)`` uint8 RGB frames."""

    def __init__(self) -> None:
        av = _av()
        self._cc = av.CodecContext.create("h264", "r")
        self._cc.thread_count = 1  # no frame threading: a frame comes out of its own packet

    def decode(self, data: bytes) -> list[np.ndarray]:
        av = _av()
        try:
            frames = self._cc.decode(av.Packet(data))
        except av.FFmpegError as err:
            raise VideoError(f"h264: cannot decode: {err}") from err
        return [f.to_ndarray(format="rgb24") for f in frames]


def settings_of(spec: Any) -> H264Settings:
    """:class:`H264Settings` from a scenario's ``h264`` block (same field names)."""
    return H264Settings(encoder=spec.encoder, keyframe_interval=spec.keyframe_interval,
                        crf=spec.crf, bitrate_kbps=spec.bitrate_kbps, threads=spec.threads,
                        preset=spec.preset)


def check_encoder(settings: H264Settings) -> None:
    """Open (and close) the encoder ``settings`` ask for, on a small picture: a
    :class:`~harness.video.errors.VideoError` when it cannot open here (NVENC without an NVIDIA GPU
    that has an encoder, an unknown preset)."""
    H264Encoder(64, 64, 30, settings, f"h264.encoder {settings.encoder}")._open()


#: ``WebmSettings.codec`` → FFmpeg encoder name (both in PyAV's wheels).
WEBM_ENCODERS: dict[str, str] = {"vp9": "libvpx-vp9", "av1": "libsvtav1"}
_MS = fractions.Fraction(1, 1000)


@dataclass(frozen=True)
class WebmSettings:
    """How :class:`WebmWriter` encodes: ``codec`` ``vp9`` or ``av1``; ``crf`` constant quality
    (VP9 0-63, AV1 0-63; lower is better); ``keyframe_s`` seconds from one keyframe to the
    next (a browser seeks to the keyframe before the time and decodes from there)."""

    codec: Literal["vp9", "av1"] = "vp9"
    crf: int = 30
    keyframe_s: float = 2.0

    def options(self, fps: float) -> dict[str, str]:
        gop = str(max(1, round(self.keyframe_s * fps)))
        if self.codec == "vp9":
            # constant quality (b=0), one thread, no row threads: the same bytes every run;
            # realtime speed 6: ~10x faster than "good" speed 4 for ~10 % more bytes
            return {"crf": str(self.crf), "b": "0", "deadline": "realtime", "cpu-used": "6",
                    "row-mt": "0", "g": gop, "auto-alt-ref": "0", "lag-in-frames": "0"}
        return {"crf": str(self.crf), "preset": "8", "g": gop,
                "svtav1-params": "lp=1:pin=0"}


class WebmWriter:
    """Writes ``(h, w, 3)`` uint8 RGB frames of one size into a WebM file, each at its own
    time (:meth:`add`); :meth:`close` finishes the file. ``width`` and ``height`` must be even
    (4:2:0). An encoder that cannot open raises
    :class:`~harness.video.errors.VideoError`."""

    def __init__(self, path: str | Path, width: int, height: int, fps: float,
                 settings: WebmSettings = WebmSettings()) -> None:
        av = _av()
        if width % 2 or height % 2 or width <= 0 or height <= 0:
            raise VideoError(f"{path}: WebM (4:2:0) needs an even width and height, got "
                             f"{width}x{height}")
        self.path = Path(path)
        self.width, self.height = int(width), int(height)
        self.frames = 0
        self._last_ms = -1
        self._reformat = reformatter()
        try:
            self._out = av.open(str(self.path), "w", format="webm",
                                options={"fflags": "+bitexact"})
        except (av.FFmpegError, OSError) as err:
            raise VideoError(f"{self.path}: cannot write: {err}") from err
        try:
            name = WEBM_ENCODERS[settings.codec]
            rate = fractions.Fraction(max(float(fps), 1e-3)).limit_denominator(1001)
            self._stream = self._out.add_stream(name, rate=rate)
            cc = self._stream.codec_context
            cc.width, cc.height, cc.pix_fmt = self.width, self.height, "yuv420p"
            cc.time_base = _MS
            cc.thread_count = 1
            cc.color_range = 1  # MPEG (limited), BT.601: written into the stream
            cc.colorspace = _SMPTE170M
            cc.color_primaries = _SMPTE170M
            cc.color_trc = _SMPTE170M
            cc.options = settings.options(float(fps))
            cc.flags |= getattr(av.codec.context.Flags, "bitexact", 0)
            self._stream.time_base = _MS
        except (av.FFmpegError, ValueError, KeyError) as err:
            self._out.close()
            raise VideoError(f"{self.path}: cannot open the {settings.codec} encoder: "
                             f"{err}") from err

    def add(self, rgb: np.ndarray, time_ms: int) -> None:
        """Encode one frame shown from ``time_ms`` (milliseconds from the file's start; a
        time not after the previous frame's is moved 1 ms after it)."""
        av = _av()
        a = np.ascontiguousarray(rgb, dtype=np.uint8)
        if a.shape != (self.height, self.width, 3):
            raise VideoError(f"{self.path}: expected a {self.width}x{self.height} RGB frame, "
                             f"got shape {a.shape}")
        t = max(int(time_ms), self._last_ms + 1)
        self._last_ms = t
        frame = self._reformat.reformat(av.VideoFrame.from_ndarray(a, format="rgb24"),
                                        format="yuv420p", dst_colorspace="ITU601",
                                        dst_color_range="MPEG")
        frame.pts = t
        frame.time_base = _MS
        self._mux(self._stream.encode(frame))
        self.frames += 1

    def _mux(self, packets: Any) -> None:
        av = _av()
        try:
            for p in packets:
                self._out.mux(p)
        except av.FFmpegError as err:
            raise VideoError(f"{self.path}: encoding failed: {err}") from err

    def close(self) -> None:
        """Flush the encoder and finish the file."""
        try:
            self._mux(self._stream.encode(None))
        finally:
            self._out.close()


def _still(codec: str, pix_fmt: str, frame: Any, width: int, height: int,
           qscale: int | None = None) -> bytes:
    av = _av()
    cc = av.CodecContext.create(codec, "w")
    cc.width, cc.height, cc.pix_fmt = width, height, pix_fmt
    cc.time_base = fractions.Fraction(1, 1)
    cc.options = {"flags": "+bitexact"}
    if qscale is not None:
        cc.qmin = cc.qmax = qscale
    packets = [*cc.encode(frame), *cc.encode(None)]
    return b"".join(bytes(p) for p in packets)


def _rgb(rgb: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(rgb, dtype=np.uint8)
    if a.ndim != 3 or a.shape[2] != 3:
        raise VideoError(f"expected an (h, w, 3) RGB frame, got shape {a.shape}")
    return a


def reformatter() -> Any:
    """A PyAV ``VideoReformatter``: it keeps its swscale context from one frame to the next
    of the same size (converting a 160×120 frame costs 0.06 ms with it, 0.5 ms without)."""
    return _av().video.reformatter.VideoReformatter()


def encode_jpeg(rgb: np.ndarray, qscale: int = 3, reformat: Any = None) -> bytes:
    """JPEG bytes of an RGB frame (4:2:0, full range). ``qscale`` is FFmpeg's ``-q:v``:
    2 (best) … 31. ``reformat``: a :func:`reformatter` to reuse across frames."""
    av = _av()
    a = _rgb(rgb)
    frame = (reformat or reformatter()).reformat(av.VideoFrame.from_ndarray(a, format="rgb24"),
                                                 format="yuvj420p")
    return _still("mjpeg", "yuvj420p", frame, a.shape[1], a.shape[0], qscale)


def encode_png(rgb: np.ndarray) -> bytes:
    """PNG bytes (8-bit RGB) of an RGB frame: lossless."""
    av = _av()
    a = _rgb(rgb)
    frame = av.VideoFrame.from_ndarray(a, format="rgb24")
    return _still("png", "rgb24", frame, a.shape[1], a.shape[0])


def depth_to_mm(depth_m: np.ndarray) -> np.ndarray:
    """Depth in metres → uint16 millimetres, 0 where there is no return (inf, NaN, <= 0) or
    the depth is beyond 65.535 m."""
    d = np.asarray(depth_m, dtype=np.float64)
    mm = np.rint(d * 1000.0)
    ok = np.isfinite(mm) & (mm > 0) & (mm <= 65535)
    return np.where(ok, mm, 0).astype(np.uint16)


def encode_depth_png(depth_m: np.ndarray) -> bytes:
    """A 16-bit grey PNG of the depth in millimetres (see :func:`depth_to_mm`)."""
    av = _av()
    d = np.asarray(depth_m)
    if d.ndim != 2:
        raise VideoError(f"expected an (h, w) depth image, got shape {d.shape}")
    frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(depth_to_mm(d)),
                                       format="gray16be")  # PyAV swaps the bytes
    return _still("png", "gray16be", frame, d.shape[1], d.shape[0])


def decode_image(data: bytes, codec: Literal["mjpeg", "png"]) -> Any:
    """The one frame of a JPEG or PNG (a PyAV ``VideoFrame``)."""
    av = _av()
    try:
        frames = av.CodecContext.create(codec, "r").decode(av.Packet(data))
    except av.FFmpegError as err:
        raise VideoError(f"{codec}: cannot decode: {err}") from err
    if len(frames) != 1:
        raise VideoError(f"{codec}: expected one image, got {len(frames)}")
    return frames[0]


def decode_depth_png(data: bytes) -> np.ndarray:
    """Float32 metres (``+inf`` where the PNG holds 0) from :func:`encode_depth_png` bytes."""
    frame = decode_image(data, "png")
    if frame.format.name not in ("gray16be", "gray16le"):
        raise VideoError(f"png: expected a 16-bit grey depth image, got {frame.format.name}")
    mm = frame.to_ndarray().astype(np.float32)  # native uint16 from gray16be or -le
    out: np.ndarray = np.where(mm > 0, mm / np.float32(1000.0), np.float32(math.inf))
    return out.astype(np.float32)


def decode_rgb(data: bytes, codec: Literal["mjpeg", "png"]) -> np.ndarray:
    """``(h, w, 3)`` uint8 RGB from JPEG or PNG bytes."""
    arr: np.ndarray = decode_image(data, codec).to_ndarray(format="rgb24")
    return arr


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    """Peak signal-to-noise ratio (dB) of two uint8 images of one shape (inf when equal)."""
    x = np.asarray(a, dtype=np.float64)
    y = np.asarray(b, dtype=np.float64)
    if x.shape != y.shape:
        raise ValueError(f"shapes differ: {x.shape} vs {y.shape}")
    mse = float(np.mean((x - y) ** 2))
    return math.inf if mse == 0 else 10.0 * math.log10(255.0 ** 2 / mse)
