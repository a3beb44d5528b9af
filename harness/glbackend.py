"""Why MuJoCo could not load its OpenGL backend, in one line (no MuJoCo import here).

``import mujoco`` loads the backend ``MUJOCO_GL`` names (srr's default: ``egl``) at once, for
every command that builds a scene, whether or not it renders: a missing OSMesa or EGL library
surfaces as an ``AttributeError`` or ``ImportError`` deep inside PyOpenGL. :func:`gl_failure`
recognises such an error by where it was raised and says what to install, or that a scenario
without cameras runs with ``MUJOCO_GL=disable``.
"""

from __future__ import annotations

import os
import re
import traceback

from harness.errors import SrrError, reason

__all__ = ["gl_failure"]

_BACKEND_FRAME = re.compile(r"[/\\]mujoco[/\\](osmesa|egl|glfw)[/\\]")
_HINTS = {
    "osmesa": "install Mesa's OSMesa (Debian: apt-get install libosmesa6)",
    "egl": "install an EGL driver: the GPU's, or Mesa's on a machine without one (Debian: "
           "apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri libopengl0)",
    "glfw": "GLFW needs a display and its library; set MUJOCO_GL=egl to render offscreen",
}


def gl_failure(err: BaseException) -> SrrError | None:
    """The one-line error for ``err`` when it was raised while MuJoCo loaded its OpenGL
    backend (a frame of ``mujoco/osmesa``, ``mujoco/egl`` or ``mujoco/glfw``), else None."""
    for frame in traceback.extract_tb(err.__traceback__):
        found = _BACKEND_FRAME.search(frame.filename)
        if found is not None:
            backend = found.group(1)
            asked = os.environ.get("MUJOCO_GL", backend)
            return SrrError(f"MuJoCo cannot load its OpenGL backend (MUJOCO_GL={asked}: "
                            f"{type(err).__name__}: {reason(err)}): {_HINTS[backend]}; a "
                            "scenario without cameras also runs with MUJOCO_GL=disable")
    return None
