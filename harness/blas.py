"""One OpenBLAS thread for srr's own process; the user's environment for the processes it starts.

NumPy's and SciPy's wheels each carry an OpenBLAS that starts a pool of one thread per CPU when
it is loaded, and each thread spins for a while before it sleeps. On a 16-CPU machine that made
importing both cost 4.5 CPU-seconds for 0.8 s of import, about 4 CPU-seconds of every
``srr run`` (whose own work took under 3), and more on larger machines. srr's matrices are 3×3
to 4×4: nothing it computes is faster on BLAS threads. So the ``srr`` command sets
``OPENBLAS_NUM_THREADS=1`` before anything imports NumPy (:func:`one_blas_thread`), unless
``OPENBLAS_NUM_THREADS`` or ``OMP_NUM_THREADS`` is already set, and notes that it did. The
nodes under test that srr starts (``ros2.external``) get the environment without what srr
added (:func:`users_environ`): their BLAS threads stay theirs to choose.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, MutableMapping

__all__ = ["one_blas_thread", "users_environ"]

_VAR = "OPENBLAS_NUM_THREADS"
# Set beside _VAR when srr set it, so that a process srr starts (and its own children, which
# inherit both) can tell srr's choice from the user's.
_ADDED = "SRR_ADDED_OPENBLAS_NUM_THREADS"


def one_blas_thread(environ: MutableMapping[str, str] = os.environ) -> bool:
    """Ask OpenBLAS for one thread unless the environment already chooses (see the module
    doc); True when this call set it. Effective only before NumPy is first imported."""
    if _VAR in environ or "OMP_NUM_THREADS" in environ:
        return False
    environ[_VAR] = "1"
    environ[_ADDED] = "1"
    return True


def users_environ(environ: Mapping[str, str] = os.environ) -> dict[str, str]:
    """A copy of ``environ`` without what :func:`one_blas_thread` added."""
    env = dict(environ)
    if env.pop(_ADDED, None) is not None:
        env.pop(_VAR, None)
    return env
