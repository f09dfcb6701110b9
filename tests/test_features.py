"""The patch descriptor is the view map's own window: filter and map are comparable."""
import numpy as np
import pytest
from skimage.feature import hog

from style_coanalysis import features
from style_coanalysis.features import hog_images, patch_blocks, patch_descriptors


def _drawing(rng, size=200):
    img = np.zeros((size, size), np.float32)
    for _ in range(120):                        # random strokes of several orientations
        r, c = rng.integers(10, size - 10, 2)
        dr, dc = rng.integers(-1, 2, 2)
        n = rng.integers(10, 40)
        rr = np.clip(r + dr * np.arange(n), 0, size - 1)
        cc = np.clip(c + dc * np.arange(n), 0, size - 1)
        img[rr, cc] = 1.0
    return img


def test_map_layout_is_one_grid_for_views_and_patches():
    maps = hog_images(np.zeros((2, 200, 200), np.float32))
    assert maps.shape == (2, 24, 24, features.CHANNELS)
    assert patch_blocks(48) == 5
    assert hog_images(np.zeros((3, 48, 48))).shape == (3, 5, 5, features.CHANNELS)


@pytest.mark.parametrize("size", [(200, 200), (48, 48), (203, 197)])
def test_maps_are_skimage_hog_bit_for_bit(size):
    """hog_images vectorises skimage's HOG for speed; every number must stay the library's."""
    rng = np.random.default_rng(7)
    h, w = size
    imgs = [_drawing(rng, max(h, w))[:h, :w], rng.random((h, w), dtype=np.float32),
            np.zeros((h, w), np.float32), np.ones((h, w), np.float32)]
    imgs[1][rng.random((h, w)) < 0.5] = 0.0          # grey levels, flat runs, ties between bins
    maps = hog_images(np.stack(imgs))
    for img, m in zip(imgs, maps):
        ref = hog(img, orientations=9, pixels_per_cell=(8, 8), cells_per_block=(2, 2),
                  block_norm="L2-Hys", feature_vector=False)
        assert m.dtype == np.float32
        np.testing.assert_array_equal(m, ref.reshape(m.shape))
    assert np.abs(maps[0]).sum() > 0


def test_crop_hog_equals_map_window_away_from_the_crop_border():
    """HOG of a cell-aligned 48x48 crop = the view-map window, except the blocks touching the
    crop border (skimage zeroes the outermost pixels' gradient) - which is why we cut from the map."""
    rng = np.random.default_rng(1)
    img = _drawing(rng)
    view_map = hog_images(img)[0]
    border_diff = 0.0
    for r0, c0 in [(8, 16), (96, 40), (152, 152)]:
        assert img[r0:r0 + 48, c0:c0 + 48].sum() > 50
        crop_hog = hog_images(img[r0:r0 + 48, c0:c0 + 48])[0]
        window = view_map[r0 // 8:r0 // 8 + 5, c0 // 8:c0 // 8 + 5]
        np.testing.assert_allclose(crop_hog[1:4, 1:4], window[1:4, 1:4], atol=1e-5)
        border_diff = max(border_diff, float(np.abs(crop_hog - window).max()))
    assert border_diff > 1e-2                                  # the crop's border really differs


def test_descriptor_is_cut_at_the_nearest_cell_and_batched():
    rng = np.random.default_rng(2)
    maps = hog_images(np.stack([_drawing(rng) for _ in range(3)]))
    # centre (x, y) = (64 + dx, 100 + dy): top-left pixel (40 + dx, 76 + dy) -> cells (5, 9/10)
    pixels = np.array([[64.0, 100.0], [67.9, 97.2], [61.0, 103.5], [5.0, 199.0]])
    which = np.array([0, 1, 2, 1])
    desc, origins = patch_descriptors(maps, which, pixels, 48)
    assert desc.shape == (4, 5, 5, features.CHANNELS)
    np.testing.assert_array_equal(origins[0], [round(76 / 8), 5])
    np.testing.assert_array_equal(origins[1], [round(73 / 8), round(43 / 8)])
    np.testing.assert_array_equal(origins[3], [24 - 5, 0])        # clipped inside the map
    for i in range(4):
        r, c = origins[i]
        np.testing.assert_array_equal(desc[i], maps[which[i], r:r + 5, c:c + 5])


def test_the_map_store_gives_back_each_shape_s_maps():
    from style_coanalysis.features import MapStore
    rng = np.random.default_rng(0)
    maps = rng.random((5, 3, 4, 4, 36)).astype(np.float32)
    store = MapStore()
    for m in maps:
        store.append(m)
    assert len(store) == 5
    for i in (3, 0, 4):
        np.testing.assert_array_equal(store[i], maps[i])
    with pytest.raises(ValueError):
        store.append(maps[0, :2])
    store.close()


def test_line_character_is_the_same_bits_whatever_the_views_order():
    """A shape turned by a quarter is drawn as the same views in another order; its line
    character must not change in the last bit (a float32 mean over every cell at once did,
    and moved a 2-label partition of hu2017-all)."""
    rng = np.random.default_rng(3)
    maps = (rng.random((12, 9, 9, 36)) ** 4).astype(np.float32)
    maps[rng.random(maps.shape[:3]) < 0.6] = 0                     # blank blocks, as drawings have
    ref = features.line_character(maps)
    assert ref.shape == (26,) and np.isclose(ref[:9].sum(), 1.0)
    for k in range(1, 12):
        assert np.array_equal(features.line_character(np.roll(maps, k, axis=0)), ref)
    assert np.array_equal(features.line_character(maps[rng.permutation(12)]), ref)
