"""Offscreen camera rendering: RGB and linear depth from ONE render pass.

:class:`Renderer` draws a MuJoCo camera with the low-level API — ``mjv_updateScene`` once,
``mjr_render`` once and ``mjr_readPixels`` once for colour *and* depth. (``mujoco.Renderer``
renders RGB and depth in two passes; on an H100 that caps 4 cameras at 640x480 to ~39 sets/s,
the single pass gives ~58-60; measured here on an H100, a 640x480 frame costs 3.9 ms from
scene update to linear depth, most of it the synchronous read-back.) A frame is a pure function
of the model and the state in ``data``: nothing is carried over from one render to the next.
Images depend on the OpenGL implementation: EGL and OSMesa on Mesa's llvmpipe give identical
bytes, a GPU driver different ones, so camera digests are per renderer.

OpenGL comes from ``mujoco.GLContext``, whose backend ``MUJOCO_GL`` selects before ``mujoco``
is imported: ``egl`` on a GPU (or with Mesa's llvmpipe on a CPU-only machine: Debian packages
``libegl1 libegl-mesa0 libgl1-mesa-dri libopengl0``), or ``osmesa`` (``libosmesa6``).

Conventions of a :class:`CameraFrame`:

* images are top row first (OpenGL reads bottom-up; the renderer flips);
* ``rgb`` is ``uint8`` ``(height, width, 3)``;
* ``depth`` is ``float32`` ``(height, width)`` metres along the optical axis (distance to the
  image plane, as ROS ``32FC1`` depth images and Isaac's ``distance_to_image_plane``), ``+inf``
  where nothing was hit (REP 117's "no return"; ROS ``depth_image_proc`` treats every
  non-finite value as invalid). "Nothing" means the far clip plane or the sky: MuJoCo draws
  the skybox into the depth buffer at a range of about 0.69 x zfar, so every pixel whose
  *range* (distance from the camera) is at least :data:`SKY_RANGE_FRACTION` x zfar is
  ``+inf``. The world puts zfar at 3 x its extent, far beyond any of its geometry;
* :class:`Intrinsics` are those of the ideal pinhole MuJoCo renders with: square pixels,
  ``fy = fx = h / (2 tan(fovy / 2))`` and the principal point at the image centre in ROS/OpenCV
  pixel coordinates (integer coordinates are pixel *centres*): ``cx = (w - 1) / 2``,
  ``cy = (h - 1) / 2``.

Contexts: one GL context per renderer (so per world), made current before each render, and
one ``MjrContext`` per output resolution, created on first use with its offscreen buffer
exactly that size and *without multisampling* (the model's ``offwidth``, ``offheight`` and
``offsamples`` are set for the duration of ``mjr_makeContext`` and restored). Multisampling
would antialias the colour, but the depth read back from a multisampled buffer is one sample's,
taken off the pixel centre (0.35 px on Mesa's llvmpipe), which shifts every back-projected point;
a depth camera wants the depth at the pixel centre, and one pass serves both images. Call
:meth:`Renderer.close` to free the contexts. In a process that runs renders one after another
(:func:`keep_gl_contexts`, EGL) the GL context outlives its renderer, released, for the next
one; its ``MjrContext`` does not.
"""

from __future__ import annotations

import functools
import math
import os
import time
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
import numpy.typing as npt

from harness.errors import SimulationError
from harness.scenario.schema import RenderSpec

__all__ = [
    "MAX_GEOMS",
    "SKY_RANGE_FRACTION",
    "CameraFrame",
    "Intrinsics",
    "RawFrame",
    "RenderJob",
    "Renderer",
    "apply_render_settings",
    "depth_from_buffer",
    "gl_context_seconds",
    "gl_contexts_made",
    "gl_renderer_name",
    "is_software_renderer",
    "keep_gl_contexts",
    "points_from_depth",
    "rendered_in_this_process",
    "warm_gl",
]

MAX_GEOMS = 10_000
#: Ranges at or beyond this fraction of the far clip distance are sky (see the module doc).
SKY_RANGE_FRACTION = 0.65

UInt8Array = npt.NDArray[np.uint8]
Float32Array = npt.NDArray[np.float32]


@dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics of a ``width`` x ``height`` image (pixels; see the module doc)."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    @classmethod
    def from_fovy(cls, width: int, height: int, fovy_deg: float) -> Intrinsics:
        """Square pixels, vertical field of view ``fovy_deg``, centred principal point."""
        if width < 1 or height < 1:
            raise SimulationError(f"image size must be positive, got {width}x{height}")
        if not 0.0 < fovy_deg < 180.0:
            raise SimulationError(f"fovy must be in (0, 180) degrees, got {fovy_deg}")
        f = height / (2.0 * math.tan(math.radians(fovy_deg) / 2.0))
        return cls(int(width), int(height), f, f, (width - 1) / 2.0, (height - 1) / 2.0)

    @property
    def k(self) -> tuple[float, ...]:
        """Row-major 3x3 camera matrix ``K``."""
        return (self.fx, 0.0, self.cx, 0.0, self.fy, self.cy, 0.0, 0.0, 1.0)

    @property
    def p(self) -> tuple[float, ...]:
        """Row-major 3x4 projection matrix ``P = [K | 0]`` (monocular, no rectification)."""
        return (self.fx, 0.0, self.cx, 0.0, 0.0, self.fy, self.cy, 0.0, 0.0, 0.0, 1.0, 0.0)

    def project(self, xyz_optical: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Pixel coordinates ``(u, v)`` of points in the optical frame (+Z forward)."""
        p = np.asarray(xyz_optical, dtype=np.float64).reshape(-1, 3)
        return np.stack([self.fx * p[:, 0] / p[:, 2] + self.cx,
                         self.fy * p[:, 1] / p[:, 2] + self.cy], axis=1)


@dataclass(frozen=True)
class CameraFrame:
    """One render of one camera (arrays are read-only; see the module doc)."""

    camera_id: int
    rgb: UInt8Array
    depth: Float32Array
    intrinsics: Intrinsics


_CONTEXTS_MADE = 0  # OpenGL contexts this process created
_CONTEXT_S = 0.0  # wall seconds this process spent creating OpenGL contexts
_SPARE: list[Any] = []  # contexts released, current on no thread, for the next renderers
_KEEP = False  # keep_gl_contexts() was called: a closing renderer's context goes to _SPARE
_GL_RENDERER: str | None = None  # GL_RENDERER of this process's contexts, once read


def rendered_in_this_process() -> bool:
    """Whether this process has created an OpenGL context (its driver's threads and state then
    live here: a process forked from it must not render)."""
    return _CONTEXTS_MADE > 0


def gl_context_seconds() -> float:
    """Wall seconds this process has spent creating OpenGL contexts (every renderer's, on
    whichever thread); 0 when it never rendered."""
    return _CONTEXT_S


def gl_renderer_name() -> str | None:
    """The OpenGL ``GL_RENDERER`` string of this process's contexts (``llvmpipe (LLVM 15.0.6,
    256 bits)``, ``NVIDIA H100 80GB HBM3/PCIe/SSE2``), read when the first renderer started;
    None before any did, "" when it could not be read."""
    return _GL_RENDERER


def gl_contexts_made() -> int:
    """How many OpenGL contexts this process has created (:func:`warm_gl`'s included)."""
    return _CONTEXTS_MADE


def _backend() -> str:
    return str(getattr(mujoco.GLContext, "__module__", "")).rsplit(".", 1)[-1]


def keep_gl_contexts() -> None:
    """From now on, a :class:`Renderer` that closes in this process keeps its OpenGL context
    for the next one instead of destroying it (EGL only: an EGL context released by one thread
    can be made current on another, and it has no size; OSMesa's and GLFW's are sized and
    bound to their buffer, so they are freed as before). For a process that runs renders one
    after another (a suite's host): creating a context is the costly part, 0.3 s alone and
    over a second each when 16 processes make one at once. The model's own GL resources
    (``MjrContext``: textures, meshes, offscreen buffer) are still made and freed per
    renderer, so nothing of one run's model reaches the next."""
    global _KEEP
    _KEEP = True


def warm_gl() -> float:
    """Make an OpenGL context now, before a renderer needs it (EGL only: the display's and the
    driver's one-time set-up, then the context, made current once and released), and keep it
    for the next :class:`Renderer` that starts here; its seconds (0 when nothing was made).
    For a process that will render anyway (a suite's host): it then counts as one that
    rendered. Errors are left to the run, which makes its own context and reports them."""
    global _CONTEXTS_MADE
    if _backend() != "egl" or _SPARE:  # EGL's context has no size: any renderer's
        return 0.0
    t0 = time.monotonic()
    try:
        _CONTEXTS_MADE += 1
        gl = mujoco.GLContext(1, 1)
        with gl.as_current():  # current on no thread afterwards: a render thread may take it
            pass
        _SPARE.append(gl)
    except Exception:  # the run makes its own context and says what failed
        pass
    return time.monotonic() - t0


def _new_context(width: int, height: int) -> Any:
    """A spare context (:func:`warm_gl`, a closed renderer's), else a new one."""
    global _CONTEXTS_MADE
    if _SPARE:
        return _SPARE.pop()
    _CONTEXTS_MADE += 1
    return mujoco.GLContext(width, height)


def _read_renderer() -> str:
    """``GL_RENDERER`` of the context current on this thread; "" when it cannot be read."""
    try:
        from OpenGL import GL

        name = GL.glGetString(GL.GL_RENDERER)
    except Exception:  # informational: PyOpenGL missing or the platform disagrees
        return ""
    return name.decode(errors="replace") if isinstance(name, bytes) else str(name or "")


def _release(gl: Any) -> None:
    """Make ``gl`` (current on this thread) current on none and keep it in :data:`_SPARE`;
    free it instead unless :func:`keep_gl_contexts` was called and the backend is EGL."""
    if not (_KEEP and _backend() == "egl"):
        gl.free()
        return
    from mujoco import egl

    released = egl.EGL.eglMakeCurrent(egl.EGL_DISPLAY, egl.EGL.EGL_NO_SURFACE,
                                      egl.EGL.EGL_NO_SURFACE, egl.EGL.EGL_NO_CONTEXT)
    if not released:  # it cannot be handed on safely: gone, like any other renderer's
        gl.free()
        return
    egl.EGL.eglReleaseThread()
    _SPARE.append(gl)


def is_software_renderer(gl_renderer: str) -> bool:
    """Whether an OpenGL renderer string names a CPU rasterizer (Mesa's llvmpipe, softpipe,
    swrast): one that already renders on every core."""
    name = gl_renderer.lower()
    return any(k in name for k in ("llvmpipe", "softpipe", "swrast", "software rasterizer"))


def apply_render_settings(model: mujoco.MjModel, settings: RenderSpec) -> None:
    """Put a scenario's ``render:`` block into a compiled model, so that every renderer of it
    draws the same way: the shadow map size, no shadow-casting lights without ``shadows``, no
    reflective materials without ``reflections``, only directional lights with ``lights: sun``.
    Nothing here changes physics, ray casts or depth (see :class:`RenderSpec`)."""
    model.vis.quality.shadowsize = int(settings.shadow_size)
    if not settings.shadows:
        model.light_castshadow[:] = False
    if not settings.reflections:
        model.mat_reflectance[:] = 0.0
    if settings.lights == "sun":
        directional = model.light_type == mujoco.mjtLightType.mjLIGHT_DIRECTIONAL
        model.light_active[:] = model.light_active & directional


def depth_from_buffer(buffer: npt.NDArray[np.floating[Any]], near: float, far: float,
                      z_limit: npt.NDArray[np.float64] | float | None = None) -> Float32Array:
    """Linear depth in metres from MuJoCo's reversed-Z depth buffer.

    The buffer is read with ``mjDEPTH_ZEROFAR`` (window depth 1 at the near plane, 0 at the far
    plane), so eye-space depth is ``z = near·far / (near + d·(far - near))``; ``d <= 0``
    (nothing drawn) and ``z >= z_limit`` (per pixel or scalar: the sky) become ``+inf``.
    Computed in float32 (relative error below 1e-6).
    """
    limit = 0.0 if z_limit is None else _buffer_limit(near, far, z_limit)
    return _linear_depth(np.asarray(buffer, dtype=np.float32), near, far, limit)


def _buffer_limit(near: float, far: float,
                  z_limit: npt.NDArray[np.float64] | float) -> npt.NDArray[np.float32] | float:
    """Window depth of ``z_limit`` (``z >= z_limit`` ⇔ ``d <= this``), at least 0."""
    z = np.asarray(z_limit, dtype=np.float64)
    d = np.maximum((near * far / z - near) / (far - near), 0.0).astype(np.float32)
    return float(d) if d.ndim == 0 else d


def _linear_depth(buffer: npt.NDArray[np.float32], near: float, far: float,
                  d_limit: npt.NDArray[np.float32] | float) -> Float32Array:
    """``near·far / (near + d·(far - near))`` in float32, ``+inf`` where ``d <= d_limit``
    (``d_limit >= 0``, as :func:`_buffer_limit` makes it: a camera's every frame compares
    with its cached limit as it is, no clamped copy of it a frame)."""
    z = np.multiply(buffer, np.float32(far - near))
    z += np.float32(near)
    np.divide(np.float32(near * far), z, out=z)
    np.copyto(z, np.float32(np.inf), where=np.less_equal(buffer, d_limit))
    return z


def _ray_norms(intr: Intrinsics) -> npt.NDArray[np.float64]:
    """Per pixel, range ÷ depth: the length of the pixel's ray with unit depth."""
    u = (np.arange(intr.width) - intr.cx) / intr.fx
    v = (np.arange(intr.height) - intr.cy) / intr.fy
    return np.sqrt(1.0 + u[None, :] ** 2 + v[:, None] ** 2)


def points_from_depth(depth: Float32Array, intr: Intrinsics) -> Float32Array:
    """Points ``(N, 3)`` float32 in the optical frame (x right, y down, z forward) for every
    finite depth pixel, in row-major pixel order; non-finite pixels are dropped."""
    h, w = depth.shape
    if (w, h) != (intr.width, intr.height):
        raise SimulationError(f"depth image {w}x{h} does not match intrinsics "
                              f"{intr.width}x{intr.height}")
    ray_x, ray_y = _pixel_rays(intr)
    valid = np.isfinite(depth)
    z = depth[valid]
    out = np.empty((z.size, 3), dtype=np.float32)
    np.multiply(ray_x[valid], z, out=out[:, 0])
    np.multiply(ray_y[valid], z, out=out[:, 1])
    out[:, 2] = z
    return out


@functools.lru_cache(maxsize=32)
def _pixel_rays(intr: Intrinsics) -> tuple[Float32Array, Float32Array]:
    """Per pixel, ``(u - cx) / fx`` and ``(v - cy) / fy`` (float32, read-only)."""
    u = (np.arange(intr.width) - intr.cx) / intr.fx
    v = (np.arange(intr.height) - intr.cy) / intr.fy
    ray_x = np.broadcast_to(u[None, :], (intr.height, intr.width)).astype(np.float32)
    ray_y = np.broadcast_to(v[:, None], (intr.height, intr.width)).astype(np.float32)
    ray_x.flags.writeable = False
    ray_y.flags.writeable = False
    return ray_x, ray_y


class _Target:
    """Per-resolution state: the MjrContext (offscreen buffer of exactly that size), the
    viewport and the read-back buffers."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int) -> None:
        vis, quality = model.vis.global_, model.vis.quality
        saved = (vis.offwidth, vis.offheight, quality.offsamples)
        vis.offwidth, vis.offheight, quality.offsamples = width, height, 0
        try:
            self.context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
        finally:
            vis.offwidth, vis.offheight, quality.offsamples = saved
        # Read depth as stored (reversed Z: 0 at the far plane), which keeps float32
        # precision far away; depth_from_buffer undoes it.
        self.context.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self.context)
        if (self.context.offWidth, self.context.offHeight) != (width, height):
            raise SimulationError(f"offscreen buffer is {self.context.offWidth}x"
                                  f"{self.context.offHeight}, wanted {width}x{height}")
        self.viewport = mujoco.MjrRect(0, 0, width, height)
        self.rgb = np.empty((height, width, 3), dtype=np.uint8)
        self.depth = np.empty((height, width), dtype=np.float32)

    def free(self) -> None:
        self.context.free()


@dataclass(frozen=True)
class RenderJob:
    """One camera's scene captured for one render (``mjv_updateScene`` done): everything
    :meth:`Renderer.draw` needs, none of it shared with the live ``MjData``."""

    camera_id: int
    intrinsics: Intrinsics
    scene: mujoco.MjvScene
    near: float
    far: float
    d_limit: Float32Array  # per pixel, the window depth of the sky's range, top row first


@dataclass(frozen=True)
class RawFrame:
    """A frame as OpenGL reads it back: bottom row first, depth as the reversed-Z buffer.
    :meth:`rgb_image` and :meth:`depth_image` give the :class:`CameraFrame` arrays (each a new
    read-only array; the same bytes whichever thread computes them)."""

    camera_id: int
    intrinsics: Intrinsics
    rgb: UInt8Array
    buffer: Float32Array
    near: float
    far: float
    d_limit: Float32Array

    def rgb_image(self) -> UInt8Array:
        rgb = np.ascontiguousarray(self.rgb[::-1])
        rgb.flags.writeable = False
        return rgb

    def depth_image(self) -> Float32Array:
        depth = _linear_depth(self.buffer[::-1], self.near, self.far, self.d_limit)
        depth.flags.writeable = False
        return depth

    def frame(self) -> CameraFrame:
        return CameraFrame(self.camera_id, self.rgb_image(), self.depth_image(), self.intrinsics)


class Renderer:
    """Renders the cameras of one MuJoCo model/data pair (one world).

    ``render(camera_id, width, height)`` is one ``mjv_updateScene`` + one ``mjr_render`` + one
    ``mjr_readPixels``; :attr:`renders` counts them (tests and benchmarks read it). It is
    :meth:`capture` (reads ``data``: the loop's thread) then :meth:`draw` (OpenGL: whichever
    one thread owns the context, see :mod:`harness.sim.render_pipeline`) then
    :meth:`RawFrame.frame`.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, *,
                 max_geoms: int = MAX_GEOMS) -> None:
        self._model = model
        self._data = data
        # An MjvScene costs ~1 kB per geom slot: size it for this model (every geom and site
        # several times over), not for the largest scene any model could need.
        self._max_geoms = min(max_geoms, 4 * (model.ngeom + model.nsite + model.ntendon) + 1000)
        self._gl: Any = None
        self._scene: mujoco.MjvScene | None = None
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._targets: dict[tuple[int, int], _Target] = {}
        self._bound: _Target | None = None
        self._d_limits: dict[Intrinsics, npt.NDArray[np.float32]] = {}
        self._closed = False
        self.renders = 0

    @property
    def near_far(self) -> tuple[float, float]:
        """Clip distances in metres: ``map.znear`` and ``map.zfar`` scaled by the extent."""
        extent = float(self._model.stat.extent)
        return (float(self._model.vis.map.znear) * extent,
                float(self._model.vis.map.zfar) * extent)

    def intrinsics(self, camera_id: int, width: int, height: int) -> Intrinsics:
        """Intrinsics of ``camera_id`` rendered at ``width`` x ``height``."""
        self._check_camera(camera_id)
        return Intrinsics.from_fovy(width, height, float(self._model.cam_fovy[camera_id]))

    def _check_camera(self, camera_id: int) -> None:
        if not 0 <= camera_id < self._model.ncam:
            raise SimulationError(f"no camera with id {camera_id} (the model has "
                                  f"{self._model.ncam})")

    def start(self) -> None:
        """Create the OpenGL context (once) and make it current on this thread."""
        if self._closed:
            raise SimulationError("renderer is closed")
        if self._gl is None:
            vis = self._model.vis.global_
            if _backend() == "glfw" and not (os.environ.get("DISPLAY")
                                          or os.environ.get("WAYLAND_DISPLAY")):
                # GLFW without a display aborts the process inside mjr_makeContext.
                raise SimulationError(
                    "cannot render: MuJoCo uses GLFW (MUJOCO_GL unset or 'glfw') and there is "
                    "no display; set MUJOCO_GL=egl (GPU, or Mesa llvmpipe) or MUJOCO_GL=osmesa "
                    "before starting")
            global _CONTEXT_S, _GL_RENDERER
            t0 = time.monotonic()
            try:
                self._gl = _new_context(max(1, vis.offwidth), max(1, vis.offheight))
                self._gl.make_current()
                _CONTEXT_S += time.monotonic() - t0
            except Exception as err:  # backend-specific (ImportError, RuntimeError, ...)
                raise SimulationError(
                    f"cannot create an OpenGL context for rendering ({type(err).__name__}: "
                    f"{err}); set MUJOCO_GL=egl (GPU, or Mesa llvmpipe) or MUJOCO_GL=osmesa"
                ) from err
            if _GL_RENDERER is None:
                _GL_RENDERER = _read_renderer()
        else:
            self._gl.make_current()

    def gl_renderer(self) -> str:
        """The OpenGL ``GL_RENDERER`` string (creates the context on this thread); empty when
        it cannot be read."""
        self.start()
        return _GL_RENDERER or ""

    def target(self, width: int, height: int) -> None:
        """Create the offscreen buffer for ``width`` x ``height`` now (the context must be
        current on this thread); :meth:`draw` does it on first use."""
        self._target(width, height)

    def _target(self, width: int, height: int) -> _Target:
        key = (int(width), int(height))
        target = self._targets.get(key)
        if target is None:
            if width < 1 or height < 1:
                raise SimulationError(f"image size must be positive, got {width}x{height}")
            target = _Target(self._model, *key)
            self._targets[key] = target
            self._bound = target  # making the context binds its offscreen buffer
        return target

    def new_scene(self) -> mujoco.MjvScene:
        """An abstract scene to :meth:`capture` into (no OpenGL needed)."""
        return mujoco.MjvScene(self._model, self._max_geoms)

    def capture(self, camera_id: int, width: int, height: int,
                scene: mujoco.MjvScene | None = None) -> RenderJob:
        """Capture camera ``camera_id`` for the current state into ``scene`` (default: the
        renderer's own); reads the model and ``data``, uses no OpenGL."""
        self._check_camera(camera_id)
        if self._closed:
            raise SimulationError("renderer is closed")
        intr = self.intrinsics(camera_id, width, height)
        if scene is None:
            if self._scene is None:
                self._scene = self.new_scene()
            scene = self._scene
        self._camera.fixedcamid = camera_id
        mujoco.mjv_updateScene(self._model, self._data, self._option, None, self._camera,
                               mujoco.mjtCatBit.mjCAT_ALL, scene)
        if scene.ngeom >= scene.maxgeom:  # MuJoCo drops what does not fit: refuse instead
            raise SimulationError(f"the scene has more than {scene.maxgeom} visual geoms; "
                                  "camera images would miss some")
        near, far = self.near_far
        d_limit = self._d_limits.get(intr)
        if d_limit is None:
            z_limit = SKY_RANGE_FRACTION * far / _ray_norms(intr)
            d_limit = np.asarray(_buffer_limit(near, far, z_limit), dtype=np.float32)
            self._d_limits[intr] = d_limit
        return RenderJob(camera_id, intr, scene, near, far, d_limit)

    def draw(self, job: RenderJob, *, fresh: bool = False) -> RawFrame:
        """``mjr_render`` + ``mjr_readPixels`` of a captured scene. The frame's arrays are the
        target's read-back buffers, overwritten by the next draw of that size, unless
        ``fresh`` (new arrays, for a frame used after the next draw)."""
        self.start()
        intr = job.intrinsics
        target = self._target(intr.width, intr.height)
        if fresh:
            rgb = np.empty_like(target.rgb)
            buffer = np.empty_like(target.depth)
        else:
            rgb, buffer = target.rgb, target.depth
        if target is not self._bound:  # mjr_render leaves its context's buffer bound
            mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, target.context)
            self._bound = target
        mujoco.mjr_render(target.viewport, job.scene, target.context)
        mujoco.mjr_readPixels(rgb, buffer, target.viewport, target.context)
        self.renders += 1
        return RawFrame(job.camera_id, intr, rgb, buffer, job.near, job.far, job.d_limit)

    def render(self, camera_id: int, width: int, height: int) -> CameraFrame:
        """RGB and linear depth of camera ``camera_id`` for the current state."""
        return self.draw(self.capture(camera_id, width, height)).frame()

    def close(self) -> None:
        """Free the MjrContexts and the GL context (idempotent)."""
        if self._closed:
            return
        self._closed = True
        if self._gl is not None:
            self._gl.make_current()
            for target in self._targets.values():
                target.free()
            _release(self._gl)
        self._targets.clear()
        self._bound = None
        self._gl = None
        self._scene = None

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
