"""Convolutional encoding: a filter finds its own patch, 5 pooled values per filter."""
import numpy as np

from style_coanalysis.encoding import FilterBank, distinct_rows, representatives, unit_rows
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


def test_the_dictionary_pools_views_and_keeps_real_patches():
    from style_coanalysis.encoding import DescriptorDraw
    rng = np.random.default_rng(5)
    images = np.zeros((6, 200, 200), np.float32)
    for i in range(6):
        for _ in range(4):
            x, y = rng.integers(30, 170, 2)
            _stamp(images[i], _motif(["ring", "cross", "bars"][i % 3]), x, y)
    maps = hog_images(images).reshape(3, 2, 24, 24, -1)
    centres = rng.integers(30, 170, (40, 2)).astype(np.float32)
    shape, view = rng.integers(0, 3, 40), rng.integers(0, 2, 40)
    draw = DescriptorDraw(48)
    for s in range(3):                  # fed shape by shape, as encode does
        at = shape == s
        draw.add(maps[s], s, f"shape-{s}", view[at], np.flatnonzero(at), centres[at])
    bank = draw.bank(5, random_state=0)
    assert 0 < len(bank) <= 5
    desc, _ = patch_descriptors(maps.reshape(-1, *maps.shape[2:]),
                                shape * maps.shape[1] + view, centres, 48)
    for f in range(len(bank)):          # each filter is a patch of its recorded source
        i = np.flatnonzero((shape == bank.shape[f]) & (view == bank.view[f])
                           & np.all(centres == bank.pixel[f], axis=1))
        assert len(i) and np.allclose(unit_rows(desc[i[:1]]).reshape(bank.hog[f].shape), bank.hog[f])


def test_the_descriptor_draw_is_bounded_and_independent_of_the_shape_order():
    """A draw capped below the number of patches keeps the same patches (by place) however the
    shapes are fed, holds at most twice the cap meanwhile, and equals one capped draw of them
    all at once."""
    from style_coanalysis.encoding import DescriptorDraw, patch_keys
    rng = np.random.default_rng(2)
    maps = rng.random((8, 2, 12, 12, 36)).astype(np.float32)
    view = rng.integers(0, 2, (8, 30))
    centres = rng.uniform(10, 90, (8, 30, 2)).astype(np.float32)

    def draw(order, limit, m=maps):
        d = DescriptorDraw(24, limit=limit, salt=3)
        held = 0
        for s in order:
            d.add(m[s], int(s), f"shape-{s}", view[s], np.arange(30), centres[s])
            held = max(held, sum(len(p[0]) for p in d._parts))
        return d, held

    a, held = draw(range(8), 25)
    b, _ = draw(rng.permutation(8), 25)
    assert held <= 2 * 25 + 30
    ba, bb = a.bank(6, 0), b.bank(6, 0)
    np.testing.assert_array_equal(ba.hog, bb.hog)
    np.testing.assert_array_equal(ba.shape, bb.shape)
    # the kept patches are the 25 with the smallest place keys of all 240
    keys = np.sort(np.concatenate([patch_keys(f"shape-{s}", view[s], np.arange(30), 3)
                                   for s in range(8)]))[:25]
    kept = np.sort(np.concatenate([p[0] for p in a._parts]))
    np.testing.assert_allclose(kept, keys)

    # lines redrawn a little (every value moved by up to 1e-3): the same places are drawn and
    # the dictionary comes from the same patches
    c, _ = draw(range(8), 25, maps + rng.uniform(0, 1e-3, maps.shape).astype(np.float32))
    bc = c.bank(6, 0)
    np.testing.assert_array_equal(np.sort(np.concatenate([p[0] for p in c._parts])), kept)
    np.testing.assert_array_equal(ba.shape, bc.shape)
    np.testing.assert_array_equal(ba.seed, bc.seed)


def test_patch_keys_depend_on_place_and_salt_only():
    from style_coanalysis.encoding import patch_keys
    v, s = np.repeat(np.arange(12), 30), np.tile(np.arange(30), 12)
    k = patch_keys("chair_01", v, s, 1)
    assert k.shape == (360,) and (k >= 0).all() and (k < 1).all()
    assert len(np.unique(k)) == 360
    np.testing.assert_array_equal(k, patch_keys("chair_01", v, s, 1))
    assert not np.isclose(k, patch_keys("chair_02", v, s, 1)).any()
    assert not np.isclose(k, patch_keys("chair_01", v, s, 2)).any()
    assert 0.4 < k.mean() < 0.6                  # spread over [0, 1)


def test_a_shape_turned_by_whole_views_draws_the_same_patches():
    """Turned about +Z by a multiple of the rig's 30 degrees, a shape is drawn in the same 12
    drawings, in another order (view v's drawing becomes view v + 3 at 90 degrees): the
    dictionary draw keeps the same patches, with the same keys, and so the same words."""
    from style_coanalysis.encoding import DescriptorDraw, home_views
    rng = np.random.default_rng(5)
    maps = rng.random((12, 12, 12, 36)).astype(np.float32)
    seeds = rng.normal(0, 0.5, (30, 3))
    view = rng.integers(0, 12, 200)
    seed = rng.integers(0, 30, 200)
    centres = rng.uniform(20, 80, (200, 2)).astype(np.float32)

    def drawn(turns):
        a = turns * np.pi / 6
        rot = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
        d = DescriptorDraw(24, limit=50, salt=1)
        d.add(np.roll(maps, turns, axis=0), 0, "chair", (view + turns) % 12, seed, centres,
              home_views(seeds @ rot.T, 12))
        keys, desc = (np.concatenate(c) for c in list(zip(*d._parts))[:2])
        order = np.argsort(keys)
        return keys[order], desc[order], d.bank(8, 0).hog

    k0, d0, w0 = drawn(0)
    for turns in (3, 1, 7):
        k, d, w = drawn(turns)
        np.testing.assert_array_equal(k, k0)
        np.testing.assert_array_equal(d, d0)
        np.testing.assert_array_equal(w, w0)
    # keyed by the view itself (no home views), the turned shape draws other patches
    plain = DescriptorDraw(24, limit=50, salt=1)
    plain.add(np.roll(maps, 3, axis=0), 0, "chair", (view + 3) % 12, seed, centres)
    assert not np.array_equal(np.sort(np.concatenate([p[0] for p in plain._parts])), k0)


def test_the_key_driven_kmeans_start_follows_small_changes_and_spreads():
    """A few descriptors changed a little (lines redrawn by a pixel) leave the k-means++ start
    nearly as it was; it is a k-means++ start (spread out), and the seed changes it."""
    from style_coanalysis.encoding import plusplus_by_key
    rng = np.random.default_rng(4)
    x = rng.normal(0, 1, (60, 16))[rng.integers(0, 60, 3000)] + rng.normal(0, 0.05, (3000, 16))
    keys = rng.random(3000)
    a = plusplus_by_key(x, keys, 60, 0)
    y = x.copy()
    y[rng.choice(3000, 10, replace=False)] += rng.normal(0, 1e-3, (10, 16))
    b = plusplus_by_key(y, keys, 60, 0)
    assert len(set(a) & set(b)) >= 57
    assert len(set(a) & set(plusplus_by_key(x, keys, 60, 1))) < 20
    def potential(idx):                           # what k-means++ keeps low: d^2 to the start
        return (((x[:, None] - x[idx][None]) ** 2).sum(axis=2).min(axis=1)).sum()
    assert potential(a) < min(potential(rng.choice(3000, 60, replace=False)) for _ in range(5))


def test_a_few_changed_descriptors_change_no_other_word():
    """Descriptors without clusters (where Lloyd's steps run to convergence carry any change
    through the whole dictionary): changing 3 of 2,000 changes no word but, at most, those 3."""
    for s in range(4):
        rng = np.random.default_rng(s)
        x = rng.random((2000, 36)).astype(np.float32)
        keys = rng.random(2000)
        changed = rng.choice(2000, 3, replace=False)
        y = x.copy()
        y[changed] += rng.normal(0, 0.05, (3, 36)).astype(np.float32)
        a, b = representatives(x, 50, 0, keys), representatives(y, 50, 0, keys)
        assert len(a) == 50 and set(a) ^ set(b) <= set(changed)
