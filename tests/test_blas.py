"""A drawing holds NumPy's BLAS to one thread while it is made, and gives the threads back."""

import pytest

from blueprint.blas import one_blas_thread


def test_blas_runs_on_one_thread_inside_and_as_before_after():
    threadpoolctl = pytest.importorskip("threadpoolctl")

    def blas_threads():
        return [p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"]

    before = blas_threads()
    if not before:
        pytest.skip("NumPy runs no BLAS that threadpoolctl knows")
    inside = one_blas_thread(blas_threads)()
    assert inside == [1] * len(before)
    assert blas_threads() == before
