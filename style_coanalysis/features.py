"""HOG features of line drawings (paper 4.1-4.2) on one cell grid shared by views and patches.

Why one grid: a representative patch is used as a convolution filter over a view's HOG map
(paper 4.2), so the patch descriptor must be made of exactly the same numbers as the map window
it is compared with. We therefore compute the HOG map of each whole view once (the numbers of
`skimage.feature.hog`: 8x8-pixel cells, 2x2-cell blocks, L2-Hys, `feature_vector=False`) and
*cut* a patch's descriptor out of that map: a 48x48 patch spans 6x6 cells = 5x5 overlapping
blocks of 2x2x9 values, i.e. a (5, 5, 36) window of the view's (24, 24, 36) block map.

Alignment: a patch centred on an arbitrary pixel is snapped to the nearest cell boundary (its
top-left pixel, as `patches.window_origins` defines it, is rounded to a multiple of 8), so the
descriptor describes the window at most 4 pixels from the seed's own window. HOG pools
gradients over 8x8 cells anyway, so this shift is within the descriptor's own resolution.
Cutting from the map (rather than running HOG on the 48x48 crop) is also exact at the patch
border: skimage sets the gradient of an image's outermost pixels to zero, so a crop's outer
cells differ from the same cells seen inside the view (tests/test_features.py shows the interior
blocks are identical and only the border blocks differ). `hog_images` still computes HOG of any
crops with the same settings, for matching patches from elsewhere against filters.
"""
from __future__ import annotations

import tempfile

import numpy as np

PIXELS_PER_CELL = 8
CELLS_PER_BLOCK = 2
ORIENTATIONS = 9
CHANNELS = CELLS_PER_BLOCK * CELLS_PER_BLOCK * ORIENTATIONS   # values per block position


def hog_images(images: np.ndarray) -> np.ndarray:
    """HOG block maps of a batch of images (n, H, W) -> (n, by, bx, 36) float32.

    The numbers of `skimage.feature.hog` (9 orientations, 8x8 cells, 2x2 blocks, L2-Hys,
    `feature_vector=False`), bit for bit (tests/test_features.py), computed for a whole batch
    at once: skimage normalises the 576 blocks of a 200 px image one by one in Python, 80% of
    its 8.6 ms an image; here an image takes about 2.5 ms. A cell's histogram is summed pixel by
    pixel in float32, in skimage's order, so that the maps (and every result read from them) are
    the library's.
    """
    images = np.asarray(images, np.float32)
    if images.ndim == 2:
        images = images[None]
    n, h, w = images.shape
    by = h // PIXELS_PER_CELL - CELLS_PER_BLOCK + 1
    bx = w // PIXELS_PER_CELL - CELLS_PER_BLOCK + 1
    if by <= 0 or bx <= 0:
        return np.zeros((n, max(by, 0), max(bx, 0), CHANNELS), np.float32)
    batch = 12                              # one shape's views: the arrays stay in cache
    return np.concatenate([_normalised_blocks(_cell_histograms(images[i:i + batch]))
                           for i in range(0, n, batch)])


def _cell_histograms(images: np.ndarray) -> np.ndarray:
    """(n, cy, cx, 9) float64 orientation histograms of 8x8-pixel cells, as skimage's
    `_hoghistogram`: central-difference gradients (zero on the image border), unsigned
    orientation in 20-degree bins, each cell's magnitudes added in float32 in row-major order,
    divided by the cell's area."""
    n, h, w = images.shape
    p = PIXELS_PER_CELL
    cy, cx = h // p, w // p
    g_row = np.zeros_like(images)
    g_col = np.zeros_like(images)
    g_row[:, 1:-1, :] = images[:, 2:, :] - images[:, :-2, :]
    g_col[:, :, 1:-1] = images[:, :, 2:] - images[:, :, :-2]
    g_row = g_row[:, :cy * p, :cx * p].astype(np.float64)
    g_col = g_col[:, :cy * p, :cx * p].astype(np.float64)
    magnitude = np.hypot(g_col, g_row)
    orientation = np.arctan2(g_row, g_col) * (180 / np.pi) % 180
    edges = np.float32(180.0 / ORIENTATIONS) * np.arange(1, ORIENTATIONS, dtype=np.float32)
    bins = np.searchsorted(edges.astype(np.float64), orientation, side="right")

    def by_cell(a):                         # (cells, 64): each cell's pixels, row-major
        return a.reshape(n, cy, p, cx, p).transpose(0, 1, 3, 2, 4).reshape(n * cy * cx, p * p)

    magnitude = by_cell(magnitude)
    slot = np.arange(n * cy * cx)[:, None] * ORIENTATIONS + by_cell(bins)
    total = np.zeros(n * cy * cx * ORIENTATIONS, np.float32)
    for k in range(p * p):                  # a float64 sum rounded to float32 at every pixel
        total[slot[:, k]] = total[slot[:, k]] + magnitude[:, k]
    total /= np.float32(p * p)
    return total.reshape(n, cy, cx, ORIENTATIONS).astype(np.float64)


def _normalised_blocks(hist: np.ndarray, eps: float = 1e-5) -> np.ndarray:
    """(n, by, bx, 36) float32 L2-Hys normalised 2x2-cell blocks of (n, cy, cx, 9) histograms."""
    b = CELLS_PER_BLOCK
    n, cy, cx, _ = hist.shape
    by, bx = cy - b + 1, cx - b + 1
    blocks = np.stack([hist[:, r:r + by, c:c + bx] for r in range(b) for c in range(b)], axis=3)
    blocks = np.ascontiguousarray(blocks.reshape(n, by, bx, CHANNELS))
    out = blocks / np.sqrt(np.sum(blocks ** 2, axis=-1, keepdims=True) + eps ** 2)
    out = np.minimum(out, 0.2)
    out = out / np.sqrt(np.sum(out ** 2, axis=-1, keepdims=True) + eps ** 2)
    return out.astype(np.float32)


def collection_maps(drawings, step=None) -> np.ndarray:
    """HOG maps of every shape's views: (N, V, by, bx, 36). `step(i, n)` is called before each
    shape (progress and cancel)."""
    maps = []
    for i, d in enumerate(drawings):
        if step is not None:
            step(i, len(drawings))
        maps.append(hog_images(d.images))
    return np.stack(maps)


class MapStore:
    """Every shape's HOG maps in a temporary file, read back one shape at a time.

    A shape's maps take 1 MB (12 views of 200 px), so a collection of 5,000 would need 5 GB held
    at once; here they need disk space only, and the file goes when the store is closed or
    collected. Indexable like the (N, V, by, bx, C) array it replaces."""

    def __init__(self, directory: str | None = None):
        self._file = tempfile.TemporaryFile(dir=directory)
        self._offsets: list[int] = []
        self._shape: tuple | None = None

    def append(self, maps: np.ndarray) -> None:
        maps = np.ascontiguousarray(maps, np.float32)
        if self._shape is None:
            self._shape = maps.shape
        elif maps.shape != self._shape:
            raise ValueError(f"maps of shape {maps.shape}, the store holds {self._shape}")
        self._file.seek(0, 2)
        self._offsets.append(self._file.tell())
        self._file.write(maps.tobytes())

    def __len__(self) -> int:
        return len(self._offsets)

    def __getitem__(self, i: int) -> np.ndarray:
        self._file.seek(self._offsets[i])
        data = self._file.read(int(np.prod(self._shape)) * 4)
        return np.frombuffer(data, np.float32).reshape(self._shape)

    def close(self) -> None:
        self._file.close()


def patch_blocks(size: int) -> int:
    """Blocks along one side of a patch descriptor: a 48-pixel patch is 6 cells = 5 blocks."""
    cells = max(CELLS_PER_BLOCK, int(round(size / PIXELS_PER_CELL)))
    return cells - CELLS_PER_BLOCK + 1


def patch_block_origins(pixels: np.ndarray, size: int, map_shape: tuple[int, int]) -> np.ndarray:
    """(n, 2) integer (block row, block col) where the patch centred on each (x, y) starts.

    The patch's top-left pixel (floor(x) - size//2, as in patches.window_origins) is rounded to
    the nearest cell and clipped so the window lies inside the map (patches overhanging the image
    edge are shifted inwards by whole cells).
    """
    pixels = np.asarray(pixels, np.float64).reshape(-1, 2)
    nb = patch_blocks(size)
    col0 = np.floor(pixels[:, 0]) - size // 2
    row0 = np.floor(pixels[:, 1]) - size // 2
    bc = np.rint(col0 / PIXELS_PER_CELL).astype(np.int64)
    br = np.rint(row0 / PIXELS_PER_CELL).astype(np.int64)
    br = np.clip(br, 0, max(map_shape[0] - nb, 0))
    bc = np.clip(bc, 0, max(map_shape[1] - nb, 0))
    return np.stack([br, bc], axis=1)


def cut_windows(maps: np.ndarray, map_index: np.ndarray, origins: np.ndarray, nb: int) -> np.ndarray:
    """Windows (n, nb, nb, C) cut from `maps` (m, by, bx, C) at `origins` (n, 2) of map `map_index`.

    Pure fancy indexing: one gather for the whole batch.
    """
    map_index = np.asarray(map_index, np.int64)
    origins = np.asarray(origins, np.int64).reshape(-1, 2)
    off = np.arange(nb)
    rows = (origins[:, 0, None] + off)[:, :, None]            # (n, nb, 1)
    cols = (origins[:, 1, None] + off)[:, None, :]            # (n, 1, nb)
    return maps[map_index[:, None, None], rows, cols]          # (n, nb, nb, C)


def patch_descriptors(maps: np.ndarray, map_index: np.ndarray, pixels: np.ndarray,
                      size: int) -> tuple[np.ndarray, np.ndarray]:
    """HOG descriptors of patches centred on `pixels`, cut from the views' maps.

    maps: (m, by, bx, C) HOG maps; map_index: (n,) which map each patch lies in; pixels: (n, 2)
    (x, y) centres. Returns (windows (n, nb, nb, C), block origins (n, 2)).
    """
    maps = np.asarray(maps)
    origins = patch_block_origins(pixels, size, maps.shape[1:3])
    return cut_windows(maps, map_index, origins, patch_blocks(size)), origins


def line_character(maps: np.ndarray) -> np.ndarray:
    """What the lines of one shape are like, from its HOG maps (V, by, bx, 36): a (26,) vector.

    Averaged over every inked cell of every view, so it needs no dictionary and no azimuth:
    the orientation histogram (9 bins: how much is vertical, horizontal, slanted), and the
    distributions of each cell's orientation concentration (its strongest bin's share: 1 on a
    straight line, low where lines curve or cross) and entropy (8 bins each), and the share of
    inked cells. Curvy and straight-lined styles differ in exactly these; on a real furniture
    collection, whole-image orientation statistics alone separated its two styles at 0.92 purity.
    A cell is inked when its gradient mass is above half the median of the shape's non-empty
    cells, the same rule the word counts use for windows.

    The same views in another order give the same bits (a shape turned by a quarter is drawn
    with its views in another order): the mean histogram sums each view, then the views' sums
    in sorted order, since a float sum over all cells at once rounds by the order."""
    maps = np.asarray(maps, np.float32)
    cells = maps.reshape(-1, ORIENTATIONS)                # every cell of every block
    total = cells.sum(axis=1)
    nz = total[total > 1e-6]
    inked = total > 0.5 * np.median(nz) if len(nz) else np.zeros(len(total), bool)
    if not inked.any():
        return np.zeros(ORIENTATIONS + 8 + 8 + 1)
    h = cells[inked] / total[inked, None]
    conc = h.max(axis=1)
    ent = -(h * np.log(h + 1e-9)).sum(axis=1)
    m = len(h)
    view = np.repeat(np.arange(len(maps)), cells.shape[0] // max(len(maps), 1))[inked]
    per_view = np.stack([h[view == v].sum(axis=0, dtype=np.float64) for v in range(len(maps))])
    return np.r_[np.sort(per_view, axis=0).sum(axis=0) / m,
                 np.histogram(conc, bins=8, range=(0.0, 1.0))[0] / m,
                 np.histogram(ent, bins=8, range=(0.0, np.log(ORIENTATIONS)))[0] / m,
                 inked.mean()]
