"""srr: a record-and-replay regression harness for robot software tested in simulation."""

import os

# srr renders offscreen. MuJoCo picks its OpenGL platform when it is first imported, and its
# default (GLFW) needs a display, so default to EGL (a GPU, or Mesa's llvmpipe on a CPU).
# An explicit MUJOCO_GL (egl, osmesa, glfw) in the environment wins.
os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"
__all__ = ["__version__"]
