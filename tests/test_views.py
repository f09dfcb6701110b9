"""The look-alike ladder (views.py), pure."""
import numpy as np

from style_coanalysis.views import (RUNG_SAMPLE, look_alikes, neighbour_ladder, rung_ranks,
                                    structure_relative)


def test_look_alikes_are_the_nearest_in_order():
    rng = np.random.default_rng(0)
    layout = rng.random((40, 6))
    near = look_alikes(layout, 10)
    s = (layout - layout.mean(0)) / layout.std(0)
    d = ((s[:, None] - s[None]) ** 2).sum(-1)
    np.fill_diagonal(d, np.inf)
    np.testing.assert_array_equal(near, np.argsort(d, axis=1, kind="stable")[:, :10])


def test_small_rungs_subtract_the_exact_mean_and_large_ones_an_even_sample_of_it():
    rng = np.random.default_rng(1)
    n = 2 * RUNG_SAMPLE + 40
    words = rng.random((n, 7))
    ks = neighbour_ladder(n)
    assert ks[0] == n - 1 and max(k for k in ks if k < n - 1) > RUNG_SAMPLE
    near = look_alikes(rng.random((n, 5)), max(k for k in ks if k < n - 1))
    out = structure_relative(words, near, ks)
    np.testing.assert_allclose(out[0], words - words.mean(0))            # the whole collection
    for k, rel in zip(ks[1:], out[1:]):
        r = rung_ranks(k)
        assert len(r) == min(k, RUNG_SAMPLE) and r[0] == 0 and r[-1] == k - 1
        assert np.all(np.diff(r) > 0)
        np.testing.assert_allclose(rel, words - words[near[:, r]].mean(axis=1))
        if k <= RUNG_SAMPLE:
            np.testing.assert_allclose(rel, words - words[near[:, :k]].mean(axis=1))
