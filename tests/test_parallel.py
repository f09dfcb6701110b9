"""Worker processes share the cores: each caps its numeric libraries' threads (parallel)."""
import os

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from style_coanalysis.parallel import core_share, in_processes


def most_threads() -> int:
    """The largest thread count of the numeric libraries loaded in this process."""
    return max(p["num_threads"] for p in threadpool_info())


def threads_here(x: int) -> tuple[int, int]:
    """A task: its argument and the threads its process's numeric libraries may use."""
    np.dot(np.ones((4, 4)), np.ones((4, 4)))      # BLAS loaded and in use
    return x, most_threads()


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="needs 2 cores")
def test_workers_get_their_share_of_the_cores_and_results_stay_in_order():
    items = [{"x": i} for i in range(5)]
    out = list(in_processes(threads_here, items, len(items), jobs=2))
    assert [x for x, _ in out] == list(range(5))
    assert {t for _, t in out} == {core_share(2)} == {max(1, os.cpu_count() // 2)}
    # in this process (one job): not capped, so the analysis' sums do not change with --jobs
    here = list(in_processes(threads_here, items[:1], 1, jobs=1))
    assert here[0][1] == most_threads() == os.cpu_count()
