"""Rendering on a background thread, so that the tick loop waits only for the renderer.

A frame is a pure function of the state at its tick, and :meth:`Renderer.capture` copies
everything a render needs out of ``MjData`` into an ``MjvScene``. So the loop's thread
captures (``mjv_updateScene``, fast) and hands the scene to one render thread, which owns the
OpenGL context and does ``mjr_render`` + ``mjr_readPixels`` (MuJoCo releases the GIL in both)
while the loop goes on with the next graphs, the systems under test and physics. What a
consumer gets is a :class:`PendingFrame`; its :meth:`~PendingFrame.rgb`,
:meth:`~PendingFrame.depth` and :meth:`~PendingFrame.frame` wait for the read-back, then flip
and convert it (:class:`~harness.sim.render.RawFrame`) on the consumer's thread, once each.

Frames are drawn in submission order with the same context and the same calls as
:meth:`Renderer.render`, so the bytes are the same as rendering on the loop's thread.

At most :data:`IN_FLIGHT` frames are captured and not yet drawn (each holds one ``MjvScene``
from a fixed pool); :meth:`RenderThread.submit` blocks when they are all in use. That bounds
the memory and is the only place the loop waits for rendering, besides a consumer that needs
a frame now. Parallel render threads are not used: on the GPU machines measured, the driver
serializes contexts (1 to 8 processes render the same aggregate frames per second).

While the thread runs, the interpreter's thread switch interval is lowered (to
:data:`SWITCH_INTERVAL_S`, restored on :meth:`RenderThread.close`): the render thread holds
the GIL only between MuJoCo calls, and with the default 5 ms it could wait that long for the
loop's thread at each of them, leaving the GPU idle.
"""

from __future__ import annotations

import queue
import sys
import threading
from typing import Any

import mujoco

from harness.errors import SimulationError
from harness.sim.render import CameraFrame, Float32Array, RawFrame, Renderer, RenderJob, UInt8Array

__all__ = ["IN_FLIGHT", "SWITCH_INTERVAL_S", "PendingFrame", "RenderThread"]

#: Frames captured but not yet drawn, at most (the size of the scene pool).
IN_FLIGHT = 8
#: The interpreter's switch interval while a render thread runs (seconds).
SWITCH_INTERVAL_S = 0.00005


class PendingFrame:
    """A frame submitted to a :class:`RenderThread`. Every accessor waits for the read-back;
    :meth:`rgb` and :meth:`depth` convert it once (whichever thread asks first) and then
    return the same read-only array."""

    __slots__ = ("_depth", "_done", "_error", "_lock", "_raw", "_rgb", "camera_id",
                 "intrinsics")

    def __init__(self, job: RenderJob) -> None:
        self.camera_id = job.camera_id
        self.intrinsics = job.intrinsics
        self._done = threading.Event()
        self._lock = threading.Lock()
        self._raw: RawFrame | None = None
        self._error: BaseException | None = None
        self._rgb: UInt8Array | None = None
        self._depth: Float32Array | None = None

    def _set(self, raw: RawFrame | None, error: BaseException | None = None) -> None:
        self._raw, self._error = raw, error
        self._done.set()

    def raw(self) -> RawFrame:
        """The read-back (waits for it); a render error is raised here."""
        self._done.wait()
        if self._error is not None:
            raise SimulationError(f"rendering camera {self.camera_id} failed: "
                                  f"{self._error}") from self._error
        assert self._raw is not None
        return self._raw

    def rgb(self) -> UInt8Array:
        raw = self.raw()
        with self._lock:
            if self._rgb is None:
                self._rgb = raw.rgb_image()
            return self._rgb

    def depth(self) -> Float32Array:
        raw = self.raw()
        with self._lock:
            if self._depth is None:
                self._depth = raw.depth_image()
            return self._depth

    def frame(self) -> CameraFrame:
        return CameraFrame(self.camera_id, self.rgb(), self.depth(), self.intrinsics)


class _Stop:
    pass


class RenderThread:
    """One thread that owns ``renderer``'s OpenGL context and draws captured scenes in order.

    Build it on the loop's thread; :meth:`submit` captures there and returns at once (unless
    :data:`IN_FLIGHT` frames are waiting); :meth:`close` draws what is queued, frees the GL
    resources on the render thread and restores the switch interval. Errors creating the
    context or an offscreen buffer are raised by :meth:`submit`, on the loop's thread.
    """

    def __init__(self, renderer: Renderer, in_flight: int = IN_FLIGHT) -> None:
        self.renderer = renderer
        self._jobs: queue.SimpleQueue[tuple[RenderJob, PendingFrame] | _Call | _Stop] = \
            queue.SimpleQueue()
        self._scenes: queue.SimpleQueue[mujoco.MjvScene] = queue.SimpleQueue()
        for _ in range(max(1, in_flight)):
            self._scenes.put(renderer.new_scene())
        self._sizes: set[tuple[int, int]] = set()
        self._switch = sys.getswitchinterval()
        sys.setswitchinterval(min(self._switch, SWITCH_INTERVAL_S))
        self._thread: threading.Thread | None = threading.Thread(
            target=self._run, name="srr-render", daemon=True)
        self._thread.start()
        try:
            self._call(renderer.start)
        except BaseException:
            self.close()
            raise

    def _call(self, fn: Any, *args: Any) -> None:
        """Run ``fn(*args)`` on the render thread and wait; its exception is raised here."""
        call = _Call(fn, args)
        self._jobs.put(call)
        call.done.wait()
        if call.error is not None:
            raise call.error

    def submit(self, camera_id: int, width: int, height: int) -> PendingFrame:
        """Capture camera ``camera_id`` now and queue its render."""
        if self._thread is None:
            raise SimulationError("render thread is closed")
        size = (int(width), int(height))
        if size not in self._sizes:  # the offscreen buffer's errors belong to the caller
            self._call(self.renderer.target, *size)
            self._sizes.add(size)
        scene = self._scenes.get()  # blocks while IN_FLIGHT frames wait: the renderer paces
        try:
            job = self.renderer.capture(camera_id, width, height, scene)
        except BaseException:
            self._scenes.put(scene)
            raise
        pending = PendingFrame(job)
        self._jobs.put((job, pending))
        return pending

    def _run(self) -> None:
        renderer = self.renderer
        while True:
            item = self._jobs.get()
            if isinstance(item, _Stop):
                break
            if isinstance(item, _Call):
                item.run()
                continue
            job, pending = item
            try:
                raw = renderer.draw(job, fresh=True)
            except BaseException as err:  # handed to whoever waits for the frame
                pending._set(None, err)
            else:
                pending._set(raw)
            finally:
                self._scenes.put(job.scene)
        renderer.close()

    def close(self) -> None:
        """Draw what is queued, free the GL resources (on the render thread), restore the
        switch interval. Idempotent."""
        thread, self._thread = self._thread, None
        if thread is None:
            return
        self._jobs.put(_Stop())
        thread.join()
        sys.setswitchinterval(self._switch)


class _Call:
    """A function to run on the render thread (context creation, an offscreen buffer)."""

    def __init__(self, fn: Any, args: tuple[Any, ...]) -> None:
        self.fn, self.args = fn, args
        self.done = threading.Event()
        self.error: BaseException | None = None

    def run(self) -> None:
        try:
            self.fn(*self.args)
        except BaseException as err:
            self.error = err
        finally:
            self.done.set()
