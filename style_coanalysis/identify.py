"""Style of 3D shapes from labelled 2D line drawings (paper 5.3, styles from sketches).

The drawings (one folder per style, PNG or JPEG, any size, dark lines on light or light on dark,
any view) are brought to the shapes' drawing form: ink found by Otsu's threshold with the
minority tone as ink, cropped to the ink and centred on a square canvas of the views' size so
that the ink spans as much of it as it does in the shapes' views (their median, measured, not
assumed), lines thinned to one pixel (a sketch's thick strokes would otherwise read as other words). Each
image, drawing or view, is then encoded with the analysis' own word dictionary: how often each
word is the best match of an inked window (the analysis' frequency pooling, per image). Each of a
shape's views votes for the style of its nearest drawing (cosine), and the style with the most
votes wins; ties go to the larger summed similarity.

Where on each shape the identified style lives (`style_regions`): the dictionary words most
characteristic of the winning style's drawings (`characteristic_words`) play the part the
cluster's style words play in the analysis, and the windows of the shape's views that match them
are back-projected to its faces by the analysis' own machinery (`localisation.localise_shape`,
`regions.face_weights`).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError
from skimage.filters import threshold_otsu
from skimage.morphology import skeletonize
from skimage.transform import resize
from sklearn.preprocessing import normalize

from . import localisation
from .encoding import frequency_features, word_counts
from .features import hog_images
from .meshes import InputError

EXTENSIONS = (".png", ".jpg", ".jpeg")


@dataclass
class DrawingSet:
    inks: list                # (M,) bool (H, W) ink masks as read, any size
    styles: list              # (M,) style of each drawing (its folder's name)
    paths: list

    def images(self, size: int, fill: float) -> np.ndarray:
        """(M, size, size) float32 drawings in the views' form (`normalise_drawing`)."""
        return np.stack([normalise_drawing(k, size, fill) for k in self.inks])


def _ink(path: Path) -> np.ndarray:
    try:
        with Image.open(path) as im:
            rgba = im.convert("RGBA")       # transparent paper counts as white
        white = Image.new("RGBA", rgba.size, (255, 255, 255, 255))
        img = np.asarray(Image.alpha_composite(white, rgba).convert("L"), np.float64) / 255.0
    except (OSError, UnidentifiedImageError, ValueError) as exc:
        raise InputError(f"'{path}' is not a readable image: {exc}") from None
    if img.ndim != 2 or min(img.shape) < 8:
        raise InputError(f"'{path}' is not a 2D drawing of at least 8x8 pixels")
    if np.ptp(img) == 0:
        raise InputError(f"'{path}' is blank: one tone, no lines")
    dark = img < threshold_otsu(img)
    return dark if dark.mean() <= 0.5 else ~dark     # the lines are the minority tone


def ink_extent(view_images) -> float:
    """Median share of the image side the ink spans in the given views (V, S, S)."""
    ext = []
    for im in view_images:
        r, c = np.nonzero(np.asarray(im) > 0.5)
        if len(r):
            ext.append((max(np.ptp(r), np.ptp(c)) + 1) / im.shape[0])
    return float(np.median(ext)) if ext else 1.0


def normalise_drawing(ink: np.ndarray, size: int, fill: float) -> np.ndarray:
    """Binary ink (H, W) -> (size, size) float32 one-pixel lines, cropped, centred, the ink
    spanning `fill` of the side."""
    ys, xs = np.nonzero(ink)
    crop = ink[ys.min():ys.max() + 1, xs.min():xs.max() + 1].astype(np.float32)
    side = int(np.ceil(max(crop.shape) / min(max(fill, 0.05), 1.0)))
    canvas = np.zeros((side, side), np.float32)
    y0, x0 = (side - crop.shape[0]) // 2, (side - crop.shape[1]) // 2
    canvas[y0:y0 + crop.shape[0], x0:x0 + crop.shape[1]] = crop
    small = resize(canvas, (size, size), order=1, anti_aliasing=True) > 0.2
    return skeletonize(small).astype(np.float32)


def load_drawings(folder) -> DrawingSet:
    """Every drawing under `folder` (one subfolder per style); InputError naming what is wrong,
    before any work on the shapes."""
    root = Path(folder)
    if not root.is_dir():
        raise InputError(f"--drawings '{folder}' is not a folder")
    subs = sorted(p for p in root.iterdir() if p.is_dir() and not p.name.startswith("."))
    loose = sorted(p.name for p in root.iterdir() if p.is_file() and p.suffix.lower() in EXTENSIONS)
    if loose:
        raise InputError(f"--drawings '{folder}': drawings must sit in one subfolder per style, "
                         f"found {', '.join(loose[:3])} at the top")
    images, styles, paths = [], [], []
    for sub in subs:
        files = sorted(p for p in sub.iterdir() if p.suffix.lower() in EXTENSIONS)
        if not files:
            raise InputError(f"style folder '{sub}' holds no PNG or JPEG drawing")
        for p in files:
            images.append(_ink(p))
            styles.append(sub.name)
            paths.append(str(p))
    if len(set(styles)) < 2:
        raise InputError(f"--drawings '{folder}' needs at least two style subfolders with "
                         f"drawings, found {len(set(styles))}")
    return DrawingSet(images, styles, paths)


def encode(images: np.ndarray, words: np.ndarray, maps: np.ndarray | None = None) -> np.ndarray:
    """(M, K) word frequencies of each image on its own (Hellinger-mapped, unit rows); `maps`,
    if given, are the images' HOG maps (M, by, bx, C), computed here otherwise."""
    if maps is None:
        maps = hog_images(np.asarray(images, np.float32))
    return normalize(frequency_features(word_counts(np.asarray(maps)[:, None], words)))


@dataclass
class Identification:
    style: str
    votes: dict               # style -> number of views that voted for it
    nearest: list             # per view: index of the nearest drawing


def vote(view_codes: np.ndarray, drawing_codes: np.ndarray, styles: list) -> Identification:
    """Each view (V, K) votes for the style of its nearest drawing (M, K) by cosine."""
    sim = view_codes @ drawing_codes.T
    nearest = sim.argmax(axis=1)
    names = sorted(set(styles))
    votes = {s: 0 for s in names}
    strength = {s: 0.0 for s in names}
    for v, j in enumerate(nearest):
        votes[styles[j]] += 1
        strength[styles[j]] += float(sim[v, j])
    best = max(names, key=lambda s: (votes[s], strength[s]))
    return Identification(best, votes, [int(j) for j in nearest])


def encode_drawings(view_images, drawings: DrawingSet, words: np.ndarray) -> np.ndarray:
    """(M, K) codes of the drawings, brought to the form of the given views (per shape (V, S, S))."""
    all_views = [im for views in view_images for im in views]
    size = np.asarray(all_views[0]).shape[-1]
    return encode(drawings.images(size, ink_extent(all_views)), words)


def identify(view_images, drawings: DrawingSet, words: np.ndarray, maps=None,
             codes: np.ndarray | None = None) -> list[Identification]:
    """view_images: per shape, its (V, S, S) views (1 = ink); maps: per shape its views' HOG
    maps, if already computed. One Identification per shape."""
    codes = encode_drawings(view_images, drawings, words) if codes is None else codes
    return [vote(encode(views, words, None if maps is None else maps[i]), codes, drawings.styles)
            for i, views in enumerate(view_images)]


def characteristic_words(codes: np.ndarray, styles: list, per_style: int):
    """(word_style (K,) int, index into sorted(set(styles)) or -1; names): each style's
    `per_style` words most over-represented in its drawings.

    A word's margin for style s is its mean code over s's drawings minus the largest mean over
    any other style's drawings: a word common in every style's drawings (corners, straight
    edges) has no margin and marks nothing, and only one style can have a positive margin for
    a word, so no word marks two styles. Only the drawings decide (their labels are the user's
    input); then the best `per_style` by margin are kept, as the analysis keeps its clusters'
    best words (`localisation.top_words`, LocalisationParams.words_per_cluster)."""
    names = sorted(set(styles))
    labels = np.array([names.index(s) for s in styles])
    means = np.stack([np.asarray(codes)[labels == k].mean(axis=0) for k in range(len(names))])
    margin = np.empty_like(means)
    for k in range(len(names)):
        margin[k] = means[k] - np.delete(means, k, axis=0).max(axis=0)
    best = margin.argmax(axis=0)
    score = margin.max(axis=0)
    word_style = np.where(score > 0, best, -1)
    return localisation.top_words(word_style, score, per_style), names


def style_regions(shape_drawings, normal_meshes, found: list, word_style: np.ndarray, names: list,
                  words: np.ndarray, patch_size: int, threshold: float, maps=None) -> list:
    """Per shape, the localisation.ShapeLocalisation of its identified style: the windows of
    all its views whose best word of the whole dictionary is one of that style's characteristic
    words, back-projected onto the faces (localise_shape). All views, not only those that voted
    for the style: a view closer overall to another style's drawing may still show the ornament.
    normal_meshes: the shapes in the normalised frame they were drawn in (`meshes.normalise`)."""
    out = []
    for i, (d, m, r) in enumerate(zip(shape_drawings, normal_meshes, found)):
        out.append(localisation.localise_shape(
            d, m.vertices, m.faces, words, word_style, names.index(r.style), patch_size,
            threshold, maps=None if maps is None else maps[i]))
    return out


def identify_shapes(shape_drawings, normal_meshes, drawings: DrawingSet, words: np.ndarray,
                    per_style: int, patch_size: int, threshold: float, progress=None):
    """(found, regions, word_style, names) for whole shapes (ShapeDrawings and their meshes in
    the normalised frame): the vote, the characteristic words, the regions. One shape at a time,
    so only one shape's HOG maps are held whatever the collection's size. `progress(stage, done,
    total)` before each shape."""
    codes = encode_drawings([d.images for d in shape_drawings], drawings, words)
    word_style, names = characteristic_words(codes, drawings.styles, per_style)
    found, regions = [], []
    for i, (d, m) in enumerate(zip(shape_drawings, normal_meshes)):
        if progress is not None:
            progress("identify", i, len(shape_drawings))
        maps = hog_images(d.images)
        found.append(vote(encode(None, words, maps), codes, drawings.styles))
        regions += style_regions([d], [m], found[-1:], word_style, names, words, patch_size,
                                 threshold, maps=[maps])
    return found, regions, word_style, names
