"""Convolutional encoding: a filter finds its own patch, 5 pooled values per filter."""
import numpy as np

from style_coanalysis.encoding import (FilterBank, distinct_rows, representatives, shape_word_counts,
                                       unit_rows)
from style_coanalysis.paper_method import build_filter_bank, correlate_pooled, encode, view_features
from style_coanalysis.features import hog_images, patch_descriptors


def _motif(kind, size=32):
    m = np.zeros((size, size), np.float32)
    yy, xx = np.mgrid[:size, :size] - (size - 1) / 2
    if kind == "ring":
        m[np.abs(np.hypot(yy, xx) - size / 3) < 1.0] = 1
    elif kind == "cross":
        m[np.abs(yy - xx) < 1.0] = 1
        m[np.abs(yy + xx) < 1.0] = 1
    elif kind == "bars":
        m[:, ::6] = 1
    return m


def _stamp(img, motif, x, y):
    s = motif.shape[0]
    img[y - s // 2:y - s // 2 + s, x - s // 2:x - s // 2 + s] = np.maximum(
        img[y - s // 2:y - s // 2 + s, x - s // 2:x - s // 2 + s], motif)


def test_filter_responds_most_where_its_patch_is():
    rng = np.random.default_rng(0)
    img = np.zeros((200, 200), np.float32)
    _stamp(img, _motif("cross"), 40, 40)
    _stamp(img, _motif("bars"), 150, 50)
    _stamp(img, _motif("ring"), 144, 152)      # the target, bottom-right quadrant
    img += (rng.random(img.shape) > 0.995)     # sparse noise pixels
    maps = hog_images(img)
    filt, origin = patch_descriptors(maps, [0], np.array([[144.0, 152.0]]), 48)
    pooled = correlate_pooled(maps, filt, (200, 200))
    assert pooled.shape == (1, 1, 5)
    assert np.isclose(pooled[0, 0, 0], 1.0, atol=1e-4)          # exact self-match
    assert np.isclose(pooled[0, 0, 4], pooled[0, 0, 0])         # found in the right quadrant
    assert pooled[0, 0, 1:4].max() < 0.9 * pooled[0, 0, 0]      # others answer less


def test_cosine_ignores_ink_density():
    """Scaling an image's ink changes nothing; a denser tangle does not beat the true motif."""
    img = np.zeros((200, 200), np.float32)
    _stamp(img, _motif("ring"), 60, 60)
    maps = hog_images(img)
    filt, _ = patch_descriptors(maps, [0], np.array([[60.0, 60.0]]), 48)
    dense = np.zeros((200, 200), np.float32)
    for x in range(20, 200, 40):
        for y in range(20, 200, 40):
            _stamp(dense, _motif("bars"), x, y)
            _stamp(dense, _motif("cross"), x, y)
    both = np.stack([hog_images(img)[0], hog_images(0.5 * img)[0], hog_images(dense)[0]])
    pooled = correlate_pooled(both, filt, (200, 200))
    assert np.isclose(pooled[0, 0, 0], pooled[1, 0, 0], atol=1e-3)
    assert pooled[2, 0, 0] < 0.8 * pooled[0, 0, 0]


def test_distinct_rows_counts_up_to_the_limit_wherever_the_distinct_rows_are():
    rng = np.random.default_rng(0)
    words = rng.random((30, 4))
    for lead in (0, 7, 100):                       # repeats of one row before the others
        x = np.concatenate([np.repeat(words[:1], lead, axis=0), words[1:],
                            words[rng.integers(0, 30, 50)]])
        full = len(np.unique(x.round(5), axis=0))
        assert full == 30
        for limit in (1, 5, 29, 30, 31, 500):
            assert distinct_rows(x, limit) == min(limit, full)
    assert distinct_rows(np.zeros((0, 4)), 3) == 0


def test_representatives_are_real_patches_one_per_centre():
    rng = np.random.default_rng(3)
    base = rng.random((4, 900))
    x = np.repeat(base, 10, axis=0) + 0.01 * rng.random((40, 900))
    idx = representatives(x, 4, random_state=0)
    assert len(idx) == 4 and len(set(idx // 10)) == 4          # one per true group
    assert len(representatives(x[:3], 50)) == 3                # fewer patches than k


def test_representatives_are_the_same_whatever_the_threads():
    # scikit-learn's k-means sums per thread: with two threads rather than one, these patches
    # (analysis seed 2's 48 px synthetic words) gave other representatives
    from threadpoolctl import threadpool_limits
    from style_coanalysis.vocabulary import synthetic_descriptors
    desc = synthetic_descriptors(48, 2)
    picked = []
    for threads in (1, 2):
        with threadpool_limits(limits=threads):
            picked.append(representatives(desc, 50, 2))
    np.testing.assert_array_equal(picked[0], picked[1])


def test_encoding_is_5k_per_view_and_vectorised_over_shapes():
    rng = np.random.default_rng(4)
    n, v = 6, 2
    images = np.zeros((n, v, 200, 200), np.float32)
    kinds = ["ring", "cross", "bars"]
    for i in range(n):
        for j in range(v):
            for _ in range(4):
                x, y = rng.integers(30, 170, 2)
                _stamp(images[i, j], _motif(kinds[i % 3]), x, y)
    maps = hog_images(images.reshape(-1, 200, 200)).reshape(n, v, 24, 24, -1)
    centres = rng.integers(30, 170, (40, 2)).astype(np.float32)
    shape = rng.integers(0, n, 40)
    view = rng.integers(0, v, 40)
    bank = build_filter_bank(maps, shape, view, np.arange(40), centres, 48, k=5, random_state=0)
    assert isinstance(bank, FilterBank) and set(bank.view) <= {0, 1}
    pooled = encode(maps, bank, (200, 200))
    assert pooled.shape == (n, len(bank), 5)
    assert pooled.min() >= 0 and pooled.max() <= 1
    feats = view_features(pooled, bank.view, None, v)
    assert [f.shape for f in feats] == [(n, 5 * int((bank.view == j).sum())) for j in range(v)]
    # each filter answers 1 in its own source view (it is a window of that map)
    assert np.allclose(pooled[bank.shape, np.arange(len(bank)), 0], 1.0, atol=1e-4)
    # the batched encoding equals encoding one shape at a time
    one = np.concatenate([encode(maps[i:i + 1], bank, (200, 200)) for i in range(n)])
    np.testing.assert_allclose(one, pooled, atol=1e-5)


def test_word_counts_assign_each_inked_window_to_its_best_filter():
    from style_coanalysis.encoding import frequency_features, word_counts
    rng = np.random.default_rng(0)
    maps = rng.random((2, 3, 6, 6, 36)).astype(np.float32)
    maps[1, :, :3] = 0.0                              # shape 1: top half blank
    filters = np.stack([maps[0, 0, :2, :2], maps[0, 1, 3:5, 1:3]])
    counts = word_counts(maps, filters)
    assert counts.shape == (2, 3, 2)
    assert counts[0].sum() == 3 * 25                  # every window of a fully inked map counts
    assert counts[1].sum() < counts[0].sum()          # blank windows count for nothing
    # a window equal to a filter is assigned to it (cosine 1 beats any other)
    one = word_counts(maps[:1, :1, :2, :2], filters)
    assert one[0, 0].tolist() == [1.0, 0.0]
    f = frequency_features(counts)
    assert f.shape == (2, 2) and np.allclose((f ** 2).sum(axis=1), 1.0)


def test_counts_against_several_dictionaries_are_each_dictionarys_own():
    from style_coanalysis.encoding import shape_word_counts, word_counts
    rng = np.random.default_rng(3)
    maps = rng.random((3, 8, 8, 36)).astype(np.float32)
    banks = [rng.random((k, 2, 2, 36)).astype(np.float32) for k in (7, 0, 4, 11)]
    together = shape_word_counts(maps, banks)
    assert [c.shape for c in together] == [(3, 7), (3, 0), (3, 4), (3, 11)]
    for counts, filters in zip(together, banks):
        np.testing.assert_array_equal(counts, word_counts(maps[None], filters)[0])
        if len(filters):
            assert counts.sum() > 0


def test_best_windows_are_the_windows_most_like_each_word():
    """The window `shape_word_counts` names for a word is the inked window most like it."""
    rng = np.random.default_rng(7)
    maps = rng.random((3, 9, 9, 36)).astype(np.float32)
    maps[1, :4] = 0                                   # blank paper is never a source
    words = unit_rows(rng.random((5, 2, 2, 36))).reshape(5, 2, 2, 36)
    (counts,), ((cos, view, row, col),) = shape_word_counts(maps, [words], best=True)
    assert counts.shape == (3, 5)
    windows = np.array([[[maps[v, r:r + 2, c:c + 2].ravel() for c in range(8)] for r in range(8)]
                        for v in range(3)])           # (3, 8, 8, 144)
    norm = np.linalg.norm(windows, axis=3)
    inked = norm > 0.5 * np.median(norm[norm > 0])
    for f in range(5):
        sim = windows @ words[f].ravel() / np.maximum(norm, 1e-9)
        assert inked[view[f], row[f], col[f]]
        assert np.isclose(cos[f], sim[view[f], row[f], col[f]], atol=1e-6)
        assert np.isclose(cos[f], sim[inked].max(), atol=1e-6)
