"""glibc's allocator set for the command line's process, which owns it (a program that calls the
library keeps its allocator as it set it).

A drawing of a big model allocates and frees arrays of tens of megabytes one after another. By
default glibc gives each back to the system as it is freed, so the next one is faulted in
again, a page at a time; the command's process keeps the memory it freed for what it allocates
next instead (``keep_freed``), and serves every thread from one arena (``one_arena``).
"""

from __future__ import annotations

import os

__all__ = ["keep_freed", "one_arena"]

# mallopt's parameters (malloc.h)
_M_TRIM_THRESHOLD, _M_TOP_PAD, _M_MMAP_THRESHOLD, _M_ARENA_MAX = -1, -2, -3, -8
# blocks up to this size come from the heap, not from a mapping of their own: the most glibc
# takes on a 64-bit system
MMAP_THRESHOLD = 32 << 20
# the heap grows by this much more than a request, and keeps as much when it could shrink
TOP_PAD = 256 << 20
# the heap's free top above which it is given back: never, in a process that ends with its command
TRIM_THRESHOLD = (1 << 31) - 1
# a user's own settings of glibc's allocator, which it reads at the process's start
USER_SETTINGS = ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TOP_PAD_", "MALLOC_TRIM_THRESHOLD_", "GLIBC_TUNABLES")


def _mallopt(settings: tuple[tuple[int, int], ...]) -> None:
    try:
        import ctypes

        mallopt = ctypes.CDLL("libc.so.6").mallopt
    except (OSError, AttributeError):
        return  # not glibc: its allocator's own ways
    for param, value in settings:
        mallopt(param, value)


def keep_freed() -> None:
    """Keep the memory freed in this process for its next allocations (see the module's
    docstring), unless the user set glibc's allocator in the environment."""
    if any(name in os.environ for name in USER_SETTINGS):
        return
    _mallopt(
        (
            (_M_MMAP_THRESHOLD, MMAP_THRESHOLD),
            (_M_TOP_PAD, TOP_PAD),
            (_M_TRIM_THRESHOLD, TRIM_THRESHOLD),
        )
    )


def one_arena() -> None:
    """Serve every thread from one arena: by default each thread that allocates gets an arena of
    its own, whose freed blocks the others never reuse, so the memory a pool's thread frees
    stays with the process through the drawing after it."""
    _mallopt(((_M_ARENA_MAX, 1),))
