"""A run directory as a Rerun recording (``srr export RUN_DIR --rerun FILE.rrd``; the
``rerun`` extra, rerun-sdk).

Everything is logged on one timeline, ``sim_time`` (a duration: the messages' log times,
simulated nanoseconds); the wall-clock timelines Rerun adds by default (``log_time``,
``log_tick``) and its start-time property are left out, and the recording id is the run's
digest, so the same run exports the same data. The entities:

* ``/tf/<root>/<frame>/…``: one entity per TF frame, nested as ``/tf`` and ``/tf_static``
  parent them (a frame's first parent wins), each a ``Transform3D`` from its parent (static
  for ``/tf_static``);
* ``/tf/<world>/ground_truth/<robot>`` and ``/tf/<world>/workers/<worker>``: the ground truth
  (``/gt/<name>/tf``) as a position per message (``Points3D``) and the whole path
  (``LineStrips3D``, static); a robot's odometry (``nav_msgs/Odometry``) likewise under its
  odometry frame, ``/tf/…/<odom frame>/odometry/<topic>``;
* ``/tf/…/<frame>/scan/<topic>``: each ``LaserScan`` as 3D points in its frame;
* ``/tf/…/<optical frame>/image``: a ``Pinhole`` per camera frame (from its first
  ``CameraInfo``), with ``<topic>`` under it for each image stream of that frame: raw images
  (``Image``; depth as ``DepthImage``, 32FC1 in metres, 16UC1 in millimetres), JPEG and PNG
  (``EncodedImage``; 16-bit depth PNG as ``EncodedDepthImage``, millimetres) and h264
  (``VideoStream``); streams of a frame without camera info go to ``/cameras/<topic>``;
* ``/tf/<frame>/<topic>``: the tracked objects' positions (``MarkerArray``), ``/topics/…``:
  ``Bool`` and ``Twist`` topics as scalars;
* ``/metrics/…``: the series behind the scores (:func:`harness.report.data.load_run`: cross-
  track error, expected and actual mute state, perception errors and counts) as ``Scalars``,
  and ``/summary``: the verdict and every metric's value as a text document (static).

Topics of other types are counted in :attr:`RerunExport.skipped`. Foxglove users keep the
MCAP: it opens there as recorded.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from harness import runlock
from harness.atomic import discard_partial
from harness.errors import SrrError, reason
from harness.recording.bagread import DECODE_ERRORS, Connection, Recording, open_indexed
from harness.recording.errors import BagError
from harness.recording.verify import verify_recording
from harness.summary import read_summary

__all__ = ["TIMELINE", "RerunExport", "export_rerun", "rerun_module"]

#: The timeline every entity is logged on: simulated time since the run's start.
TIMELINE = "sim_time"

_TF = "tf2_msgs/msg/TFMessage"
_RAW = "sensor_msgs/msg/Image"
_JPEG_PNG = "sensor_msgs/msg/CompressedImage"
_VIDEO = "foxglove_msgs/msg/CompressedVideo"
_SCAN = "sensor_msgs/msg/LaserScan"
_ODOM = "nav_msgs/msg/Odometry"
_MARKERS = "visualization_msgs/msg/MarkerArray"
_BOOL = "std_msgs/msg/Bool"
_TWIST = "geometry_msgs/msg/Twist"
_INFO = "sensor_msgs/msg/CameraInfo"


@dataclass(frozen=True)
class RerunExport:
    """What was written: the file, its size, the entities logged and each one's rows on
    ``sim_time`` (0 for static-only ones), and the topics left out by type."""

    path: Path
    bytes: int
    rows: Mapping[str, int]
    skipped: Mapping[str, str] = field(default_factory=dict)  # topic → type

    @property
    def entities(self) -> tuple[str, ...]:
        return tuple(sorted(self.rows))


def rerun_module() -> ModuleType:
    """rerun-sdk, or :class:`SrrError` saying which extra installs it."""
    try:
        import rerun
    except ImportError as err:
        raise SrrError("--rerun: needs rerun-sdk, the rerun extra (pip install "
                       f"'srr[rerun]'): {err}") from None
    return rerun


def _part(rr: ModuleType, name: str) -> str:
    return str(rr.escape_entity_path_part(name.strip("/") or "_"))


def _topic_path(rr: ModuleType, topic: str) -> str:
    return "/".join(_part(rr, p) for p in topic.strip("/").split("/") if p) or "_"


class _Frames:
    """The TF tree: each frame's parent (the first one seen) and its entity path."""

    def __init__(self, rr: ModuleType) -> None:
        self.rr = rr
        self.parent: dict[str, str] = {}

    def add(self, parent: str, child: str) -> None:
        if child != parent and child not in self.parent and not self._above(child, parent):
            self.parent[child] = parent

    def _above(self, frame: str, of: str) -> bool:
        """``frame`` is ``of`` or one of its ancestors (a loop otherwise)."""
        seen = set()
        while of not in seen:
            if of == frame:
                return True
            seen.add(of)
            if of not in self.parent:
                return False
            of = self.parent[of]
        return False

    def path(self, frame: str) -> str:
        chain = [frame]
        while chain[-1] in self.parent:
            chain.append(self.parent[chain[-1]])
        return "/tf/" + "/".join(_part(self.rr, f) for f in reversed(chain))


class _Writer:
    """Logs to the recording: row by row (:meth:`log`, at the time :meth:`at` set), or
    gathered per entity and sent as columns at the end (:meth:`add`, :meth:`finish`: the
    transforms, positions and scalars, most of the rows)."""

    def __init__(self, rr: ModuleType, rec: Any) -> None:
        self.rr, self.rec = rr, rec
        self.rows: dict[str, int] = {}
        self.t_ns = 0
        self.gathered: dict[tuple[str, str], tuple[list[int], list[Any]]] = {}

    def at(self, t_ns: int) -> None:
        self.t_ns = int(t_ns)
        self.rec.set_time(TIMELINE, duration=np.timedelta64(self.t_ns, "ns"))

    def log(self, path: str, item: Any, *, static: bool = False) -> None:
        self.rec.log(path, item, static=static)
        self.rows[path] = self.rows.get(path, 0) + (0 if static else 1)

    def add(self, kind: str, path: str, value: Any) -> None:
        """One row of ``kind`` (``transform``: (xyz, xyzw); ``position``: xyz; ``scalar``)
        at the current time."""
        times, values = self.gathered.setdefault((kind, path), ([], []))
        times.append(self.t_ns)
        values.append(value)

    def finish(self) -> None:
        rr = self.rr
        for (kind, path), (times, values) in self.gathered.items():
            if kind == "transform":
                cols = rr.Transform3D.columns(
                    translation=np.array([v[0] for v in values], dtype=np.float64),
                    quaternion=np.array([v[1] for v in values], dtype=np.float64))
            elif kind == "position":
                cols = rr.Points3D.columns(positions=np.array(values, dtype=np.float64))
            else:
                cols = rr.Scalars.columns(scalars=np.array(values, dtype=np.float64))
            self._send(path, np.array(times, dtype="timedelta64[ns]"), cols)
        self.gathered.clear()

    def columns(self, path: str, t_s: np.ndarray, values: np.ndarray) -> None:
        """A scalar series at times ``t_s`` (seconds)."""
        if t_s.size == 0:
            return
        t_ns = np.round(np.asarray(t_s, dtype=np.float64) * 1e9).astype("timedelta64[ns]")
        self._send(path, t_ns, self.rr.Scalars.columns(
            scalars=np.asarray(values, dtype=np.float64)))

    def _send(self, path: str, t_ns: np.ndarray, cols: Any) -> None:
        self.rec.send_columns(path, indexes=[self.rr.TimeColumn(TIMELINE, duration=t_ns)],
                              columns=cols)
        self.rows[path] = self.rows.get(path, 0) + int(t_ns.size)


def _quat(r: Any) -> list[float]:
    return [float(r.x), float(r.y), float(r.z), float(r.w)]


def _vec(v: Any) -> list[float]:
    return [float(v.x), float(v.y), float(v.z)]


def _image(rr: ModuleType, msg: Any) -> Any:
    h, w, enc = int(msg.height), int(msg.width), str(msg.encoding).lower()
    data = np.asarray(msg.data, dtype=np.uint8)
    rows = data.reshape(h, int(msg.step))
    if enc in ("32fc1", "16uc1", "mono16"):
        dtype = np.dtype(np.float32 if enc == "32fc1" else np.uint16)
        dtype = dtype.newbyteorder(">" if msg.is_bigendian else "<")
        values = rows[:, : w * dtype.itemsize].copy().view(dtype).reshape(h, w)
        values = values.astype(dtype.newbyteorder("="))
        if enc == "mono16":
            return rr.Image(values, color_model="L")
        # REP 118: 32FC1 depth in metres, 16UC1 in millimetres
        return rr.DepthImage(values, meter=1.0 if enc == "32fc1" else 1000.0)
    channels = {"rgb8": 3, "bgr8": 3, "rgba8": 4, "bgra8": 4, "mono8": 1, "8uc1": 1,
                "8uc3": 3}.get(enc)
    if channels is None:
        return None
    pixels = rows[:, : w * channels].reshape(h, w, channels) if channels > 1 else \
        rows[:, :w]
    model = {"rgb8": "RGB", "bgr8": "BGR", "rgba8": "RGBA", "bgra8": "BGRA", "8uc3": "BGR"}.get(
        enc, "L")
    return rr.Image(pixels, color_model=model)


def _scan_points(msg: Any) -> np.ndarray:
    r = np.asarray(msg.ranges, dtype=np.float64)
    a = float(msg.angle_min) + float(msg.angle_increment) * np.arange(r.size)
    ok = np.isfinite(r) & (r >= float(msg.range_min)) & (r <= float(msg.range_max))
    return np.stack([r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok]), np.zeros(int(ok.sum()))],
                    axis=1)


class _Exporter:
    def __init__(self, rr: ModuleType, w: _Writer, bag: Recording,
                 robots: frozenset[str]) -> None:
        self.rr, self.w, self.bag, self.robots = rr, w, bag, robots
        self.frames = _Frames(rr)
        self.paths: dict[str, list[list[float]]] = {}  # entity → positions over time
        self.video: set[str] = set()
        self.skipped: dict[str, str] = {}
        self.pinholes: dict[str, Any] = {}  # optical frame → its first CameraInfo

    def tf_tree(self) -> None:
        """First pass, over the TF and camera-info topics alone: the frames' parents, and the
        first intrinsics of each camera frame."""
        tf = {c.id for c in self.bag.connections
              if c.msgtype == _TF and not c.topic.startswith("/gt/")}
        info = {c.id for c in self.bag.connections if c.msgtype == _INFO}
        for conn, t_ns, raw in self.bag.scan(tf | info):
            if raw is None or conn.id not in tf | info:
                continue
            msg = self.decode(conn, t_ns, raw)
            if conn.id in tf:
                for t in msg.transforms:
                    self.frames.add(t.header.frame_id, t.child_frame_id)
            elif msg.header.frame_id not in self.pinholes and int(msg.width) > 0:
                self.pinholes[msg.header.frame_id] = msg

    def pinhole_entities(self) -> None:
        """A ``Pinhole`` (static) per camera frame, the images of that frame under it: Rerun
        shows them in the camera's frustum (depth as points) and in 2D."""
        for frame, info in sorted(self.pinholes.items()):
            k = np.asarray(info.k, dtype=np.float64).reshape(3, 3)
            self.w.log(self._camera_entity(frame), self.rr.Pinhole(
                image_from_camera=k, resolution=[int(info.width), int(info.height)],
                camera_xyz=self.rr.ViewCoordinates.RDF), static=True)

    def _camera_entity(self, frame: str) -> str:
        return f"{self.frames.path(frame)}/image"

    def decode(self, conn: Connection, t_ns: int, raw: bytes) -> Any:
        try:
            return self.bag.decode(raw, conn)
        except DECODE_ERRORS as err:
            raise BagError(f"{self.bag.shown}: a {conn.msgtype} message on {conn.topic} at "
                           f"{t_ns / 1e9:.3f} s does not decode: {reason(err)}") from err

    def message(self, conn: Connection, t_ns: int, raw: bytes) -> None:
        msg = self.decode(conn, t_ns, raw)
        self.w.at(t_ns)
        try:
            self._message(conn, msg)
        except (ValueError, IndexError) as err:  # decoded, but its fields disagree
            raise BagError(f"{self.bag.shown}: a {conn.msgtype} message on {conn.topic} at "
                           f"{t_ns / 1e9:.3f} s does not export: {reason(err)}") from err

    def _message(self, conn: Connection, msg: Any) -> None:
        kind = conn.msgtype
        if kind == _TF and conn.topic.startswith("/gt/"):
            self._gt(conn, msg)
        elif kind == _TF:
            static = conn.topic.endswith("tf_static") or conn.latched
            for t in msg.transforms:
                path = self.frames.path(t.child_frame_id)
                xyz, xyzw = _vec(t.transform.translation), _quat(t.transform.rotation)
                if static:
                    self.w.log(path, self.rr.Transform3D(
                        translation=xyz, quaternion=self.rr.Quaternion(xyzw=xyzw)), static=True)
                else:
                    self.w.add("transform", path, (xyz, xyzw))
        elif kind == _ODOM:
            p = msg.pose.pose.position
            self._position(f"{self.frames.path(msg.header.frame_id)}/odometry/"
                           f"{_topic_path(self.rr, conn.topic)}", _vec(p))
        elif kind == _SCAN:
            self.w.log(f"{self.frames.path(msg.header.frame_id)}/scan/"
                       f"{_topic_path(self.rr, conn.topic)}",
                       self.rr.Points3D(_scan_points(msg)))
        elif kind in (_RAW, _JPEG_PNG, _VIDEO):
            self._camera(conn, msg)
        elif kind == _MARKERS:
            pts = [_vec(m.pose.position) for m in msg.markers if int(m.action) == 0]
            frame = next((m.header.frame_id for m in msg.markers), "world")
            self.w.log(f"{self.frames.path(frame)}/{_topic_path(self.rr, conn.topic)}",
                       self.rr.Points3D(pts))
        elif kind == _BOOL:
            self.w.add("scalar", f"/topics/{_topic_path(self.rr, conn.topic)}",
                       1.0 if msg.data else 0.0)
        elif kind == _TWIST:
            base = f"/topics/{_topic_path(self.rr, conn.topic)}"
            self.w.add("scalar", f"{base}/linear_x", float(msg.linear.x))
            self.w.add("scalar", f"{base}/angular_z", float(msg.angular.z))

    def _gt(self, conn: Connection, msg: Any) -> None:
        for t in msg.transforms:
            name = t.child_frame_id
            where = "ground_truth" if name in self.robots else "workers"
            self._position(f"{self.frames.path(t.header.frame_id)}/{where}/"
                           f"{_part(self.rr, name)}", _vec(t.transform.translation))

    def _position(self, base: str, xyz: list[float]) -> None:
        self.w.add("position", base, xyz)
        self.paths.setdefault(f"{base}/path", []).append(xyz)

    def _camera(self, conn: Connection, msg: Any) -> None:
        frame = str(msg.frame_id if conn.msgtype == _VIDEO else msg.header.frame_id)
        base = self._camera_entity(frame) if frame in self.pinholes else "/cameras"
        path = f"{base}/{_topic_path(self.rr, conn.topic)}"
        rr = self.rr
        if conn.msgtype == _RAW:
            image = _image(rr, msg)
            if image is None:
                self.skipped[conn.topic] = f"{conn.msgtype} ({msg.encoding})"
                return
            self.w.log(path, image)
        elif conn.msgtype == _JPEG_PNG:
            fmt = str(msg.format).lower()
            media = "image/png" if "png" in fmt else "image/jpeg"
            blob = bytes(np.asarray(msg.data, dtype=np.uint8))
            if "16uc1" in fmt or "mono16" in fmt:  # srr's depth PNG: millimetres
                self.w.log(path, rr.EncodedDepthImage(blob=blob, media_type=media, meter=1000.0))
            else:
                self.w.log(path, rr.EncodedImage(contents=blob, media_type=media))
        else:
            if str(msg.format).lower() not in ("h264", "avc"):
                self.skipped[conn.topic] = f"{conn.msgtype} ({msg.format})"
                return
            if path not in self.video:
                self.video.add(path)
                self.w.log(path, rr.VideoStream(codec=rr.VideoCodec.H264), static=True)
            self.w.log(path, rr.VideoStream.from_fields(
                sample=bytes(np.asarray(msg.data, dtype=np.uint8))))

    def finish(self) -> None:
        self.w.finish()
        for path, pts in self.paths.items():
            self.w.log(path, self.rr.LineStrips3D([pts]), static=True)


_HANDLED = frozenset({_TF, _RAW, _JPEG_PNG, _VIDEO, _SCAN, _ODOM, _MARKERS, _BOOL, _TWIST})


def _metric_series(rr: ModuleType, w: _Writer, run_dir: Path, summary: dict[str, Any]) -> None:
    """The series the scores were computed from (what the report plots)."""
    from harness.report.data import load_run

    data = load_run(run_dir, summary=summary)
    for c in data.control:
        base = f"/metrics/control/{_part(rr, c.robot)}"
        w.columns(f"{base}/cross_track_error", c.t, c.cte)
    s = data.safety
    if s is not None:
        w.columns("/metrics/safety/expected_muted", s.t, s.expected.astype(np.float64))
        w.columns("/metrics/safety/muted", s.t, s.actual.astype(np.float64))
        w.columns("/metrics/safety/worker_in_roi", s.t, s.worker_in_roi.astype(np.float64))
    for p in data.perception:
        base = f"/metrics/perception/{_part(rr, p.cls)}"
        w.columns(f"{base}/position_error", p.err_t, p.err_v)
        for name in ("n_tracks", "n_objects", "n_missed", "n_false"):
            w.columns(f"{base}/{name}", p.frame_t, getattr(p, name).astype(np.float64))


def _summary_text(summary: Mapping[str, Any]) -> str:
    lines = [f"# {summary.get('scenario', '?')}: {summary.get('verdict', '?')}", ""]
    lines += [f"- {r}" for r in summary.get("reasons", [])]
    lines += ["", "| metric | value | unit |", "|---|---|---|"]
    for m in summary.get("metrics", []):
        v = m.get("value")
        lines.append(f"| {m.get('name')} | {'—' if v is None else f'{v:.6g}'} | "
                     f"{m.get('unit', '')} |")
    return "\n".join(lines) + "\n"


def _robots(run_dir: Path) -> frozenset[str]:
    from harness.scenario import load_scenario

    try:
        sc = load_scenario(run_dir / "scenario.yaml")
    except SrrError:
        return frozenset()
    return frozenset(r.name for r in sc.robots)


def _write(rr: ModuleType, run_dir: Path, summary: dict[str, Any], tmp: Path) -> RerunExport:
    digest = str(summary.get("digest") or "")
    rec = rr.RecordingStream("srr", recording_id=digest[:32] or None, send_properties=False)
    rec.set_log_tick_enabled(False)  # wall-clock and call-count timelines: not in the data
    rec.set_log_time_enabled(False)
    rec.save(str(tmp))
    w = _Writer(rr, rec)
    try:
        # a damaged value beyond float32 (Rerun's positions, transforms) becomes inf, unwarned
        with np.errstate(over="ignore"):
            rec.send_recording_name(f"{summary.get('scenario', 'run')} ({run_dir.name})")
            w.log("/summary", rr.TextDocument(_summary_text(summary), media_type="text/markdown"),
                  static=True)
            with open_indexed(run_dir / "bag", shown=run_dir / "bag", what="cannot export") as bag:
                ex = _Exporter(rr, w, bag, _robots(run_dir))
                ex.tf_tree()
                ex.pinhole_entities()
                wanted = [c for c in bag.connections if c.msgtype in _HANDLED]
                ex.skipped.update({c.topic: c.msgtype for c in bag.connections
                                   if c.msgtype not in _HANDLED | {_INFO}})
                for conn, t_ns, raw in bag.messages(wanted):
                    ex.message(conn, t_ns, raw)
                ex.finish()
            _metric_series(rr, w, run_dir, summary)
            try:
                rec.flush()
            except RuntimeError as err:  # rerun-sdk's file writer failed (disk full)
                raise OSError(f"rerun-sdk's file writer stopped ({err}; its log above says "
                              "why)") from err
    finally:
        rec.disconnect()
    return RerunExport(tmp, tmp.stat().st_size, dict(sorted(w.rows.items())),
                       dict(sorted(ex.skipped.items())))


def export_rerun(run_dir: str | Path, out: str | Path) -> RerunExport:
    """Write the finished run ``run_dir`` (its bag and ``summary.json``) to the Rerun
    recording ``out`` (``.rrd``), replaced only once complete. :class:`SrrError` (exit 2) for
    a directory that is not a finished run, a run still being written, a bag that does not
    read back whole or does not match the summary (:func:`~harness.recording.verify.
    verify_recording`), an ``out`` that cannot be written, or rerun-sdk missing."""
    run = Path(run_dir)
    target = Path(out)
    rr = rerun_module()
    summary = read_summary(run)
    runlock.refuse_if_live(run)
    if target.suffix != ".rrd":
        raise SrrError(f"--rerun {target}: expected a file name ending in .rrd")
    if target.is_dir() or not target.parent.is_dir():
        raise SrrError(f"--rerun {target}: " + ("is a directory" if target.is_dir() else
                                               f"directory {target.parent} does not exist"))
    verify_recording(run, summary)  # the bag read back is the summary's, its CRCs checked
    tmp = target.with_name(f".{target.name}.partial")
    try:
        # made here first: rerun-sdk says a folder it cannot write to with a RuntimeError
        tmp.open("wb").close()
        result = _write(rr, run, summary, tmp)
        os.replace(tmp, target)
    except OSError as err:
        discard_partial(tmp)
        raise SrrError(f"--rerun {target}: cannot write: {err.strerror or err}") from err
    except BaseException:
        discard_partial(tmp)
        raise
    return RerunExport(target, result.bytes, result.rows, result.skipped)

