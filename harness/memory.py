"""Keeping a long run's resident memory flat: give freed heap memory back to the system.

A run allocates and frees the same kinds of buffers every tick (images, their CDR bytes,
chunks of the bag) on several threads. glibc's allocator keeps freed memory in per-thread
arenas and raises its mmap threshold after large frees, so over minutes of simulated time
the resident set creeps up through fragmentation although nothing is kept (measured: +10 MB
over 600 s with four cameras). :func:`release_free_memory` (``malloc_trim(0)``: free pages
anywhere in the heaps go back to the kernel) stops that; the tick loop calls it once per
simulated second and again before scoring. Elsewhere than glibc it does nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
from collections.abc import Callable

__all__ = ["release_free_memory"]


@functools.cache
def _malloc_trim() -> Callable[[int], int] | None:
    name = ctypes.util.find_library("c")
    if name is None:
        return None
    try:
        libc = ctypes.CDLL(name)
        trim = libc.malloc_trim
    except (OSError, AttributeError):  # not glibc (musl, macOS)
        return None
    trim.argtypes = [ctypes.c_size_t]
    trim.restype = ctypes.c_int
    fn: Callable[[int], int] = trim
    return fn


def release_free_memory() -> bool:
    """Return the heap's free pages to the system (glibc ``malloc_trim(0)``; releases the
    GIL while it runs). True when memory was released."""
    trim = _malloc_trim()
    return bool(trim(0)) if trim is not None else False
