"""NumPy's BLAS held to one thread while a drawing is made.

Every matrix product of a drawing is an (N, 3) or (N, 4) array by a 3 x 3 or 4 x 4 matrix: too
little work to share out, but OpenBLAS wakes its threads for it all the same, and they spin a
while after each product, on the cores the software rasteriser's threads need (the drawings
stay the same byte for byte, as a row of a product is one thread's either way).
threadpoolctl sets the limit where it can; an environment set up before it was a dependency
draws as before, only slower.
"""

from __future__ import annotations

import functools
from contextlib import nullcontext

try:
    from threadpoolctl import threadpool_limits
except ImportError:  # an environment installed before threadpoolctl was a dependency
    threadpool_limits = None

__all__ = ["one_blas_thread"]


def one_blas_thread(func):
    """``func`` run with NumPy's BLAS limited to one thread (restored after)."""

    @functools.wraps(func)
    def limited(*args, **kwargs):
        with threadpool_limits(1, user_api="blas") if threadpool_limits is not None else nullcontext():
            return func(*args, **kwargs)

    return limited
