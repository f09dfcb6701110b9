"""Style from 2D drawings: reading and normalising drawings, the vote (pure: no Blender)."""
import numpy as np
import pytest
from PIL import Image
from skimage.draw import circle_perimeter, line

from style_coanalysis.identify import (ink_extent, load_drawings, normalise_drawing, vote)
from style_coanalysis.meshes import InputError


def drawing(size=120):
    img = np.zeros((size, size), bool)
    rr, cc = circle_perimeter(size // 2, size // 2, size // 4, shape=img.shape)
    img[rr, cc] = True
    rr, cc = line(10, 10, size - 10, size // 2)
    img[rr, cc] = True
    return img


def save(path, ink, dark_on_light=True):
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.where(ink != dark_on_light, 255, 0).astype(np.uint8)).save(path)


def test_polarity_position_and_size_do_not_matter(tmp_path):
    save(tmp_path / "a" / "dark.png", drawing())
    save(tmp_path / "a" / "light.png", drawing(), dark_on_light=False)
    save(tmp_path / "b" / "moved.png", np.pad(drawing(), ((30, 0), (0, 45))))
    ds = load_drawings(tmp_path)
    assert ds.styles == ["a", "a", "b"]
    imgs = ds.images(64, 0.8)
    assert imgs.shape == (3, 64, 64) and imgs.dtype == np.float32
    assert np.array_equal(imgs[0], imgs[1])           # dark on light == light on dark
    assert np.array_equal(imgs[0], imgs[2])           # cropped to the ink: position is gone
    r, c = np.nonzero(imgs[0])
    assert abs(max(np.ptp(r), np.ptp(c)) + 1 - 0.8 * 64) <= 2      # spans the asked share


def test_ink_extent_is_measured():
    views = np.zeros((2, 100, 100), np.float32)
    views[0, 20:80, 50] = 1
    views[1, 50, 10:90] = 1
    assert ink_extent(views) == pytest.approx(0.7)
    big = normalise_drawing(np.pad(drawing(), 50), 100, 0.7)
    r, c = np.nonzero(big)
    assert abs(max(np.ptp(r), np.ptp(c)) + 1 - 70) <= 2


def test_bad_drawing_folders_are_refused_by_name(tmp_path):
    with pytest.raises(InputError, match="is not a folder"):
        load_drawings(tmp_path / "none")
    save(tmp_path / "loose.png", drawing())
    with pytest.raises(InputError, match="one subfolder per style, found loose.png"):
        load_drawings(tmp_path)
    (tmp_path / "loose.png").unlink()
    save(tmp_path / "a" / "x.png", drawing())
    with pytest.raises(InputError, match="at least two style subfolders"):
        load_drawings(tmp_path)
    (tmp_path / "b").mkdir()
    with pytest.raises(InputError, match="holds no PNG or JPEG"):
        load_drawings(tmp_path)
    Image.fromarray(np.full((50, 50), 255, np.uint8)).save(tmp_path / "b" / "blank.png")
    with pytest.raises(InputError, match="blank.png' is blank"):
        load_drawings(tmp_path)
    (tmp_path / "b" / "blank.png").write_bytes(b"\x89PNG broken")
    with pytest.raises(InputError, match="blank.png' is not a readable image"):
        load_drawings(tmp_path)


def test_each_view_votes_for_its_nearest_drawing():
    drawings = np.eye(3)                        # drawing j is unit vector j
    styles = ["x", "y", "y"]
    views = np.array([[1, 0.1, 0], [0.9, 0, 0.2], [0, 0, 1]], float)
    r = vote(views / np.linalg.norm(views, axis=1, keepdims=True), drawings, styles)
    assert r.nearest == [0, 0, 2] and r.votes == {"x": 2, "y": 1} and r.style == "x"
    r = vote(np.array([[1.0, 0, 0], [0, 0.5, 0]]), drawings, styles)      # 1-1: the stronger
    assert r.style == "x"


def test_characteristic_words_are_over_represented_in_one_style_only():
    from style_coanalysis.identify import characteristic_words
    # words: 0 frequent in a only, 1 in every style alike, 2 frequent in b only, 3 in a and b
    # alike (characteristic of neither), 4 a little more frequent in a than elsewhere
    base = np.array([0.1, 0.8, 0.1, 0.1, 0.1])
    codes = np.stack([base + [0.7, 0, 0, 0.5, 0.2], base + [0.6, 0, 0, 0.5, 0.2],
                      base + [0, 0, 0.6, 0.5, 0], base + [0, 0, 0.7, 0.5, 0], base, base])
    styles = ["a", "a", "b", "b", "c", "c"]
    word_style, names = characteristic_words(codes, styles, per_style=2)
    assert names == ["a", "b", "c"]
    assert word_style.tolist() == [0, -1, 1, -1, 0]       # c has no word of its own
    word_style, _ = characteristic_words(codes, styles, per_style=1)
    assert word_style.tolist() == [0, -1, 1, -1, -1]      # the larger margin is kept
