"""Back-projection of style words to vertex weights (pure core, synthetic drawings)."""
import numpy as np
from skimage.draw import circle_perimeter, line

from style_coanalysis.drawings import ShapeDrawings
from style_coanalysis.features import hog_images, patch_descriptors
from style_coanalysis.localisation import coverage, localise_shape, top_words
from style_coanalysis.rig import Rig, project


def test_a_style_window_covers_exactly_its_pixels():
    style = np.zeros((1, 23, 23), bool)
    style[0, 3, 5] = True
    cover = coverage(style, 24, 200)
    rows, cols = np.nonzero(cover[0])
    assert (rows.min(), rows.max(), cols.min(), cols.max()) == (24, 47, 40, 63)


def _drawings(motif_views):
    """Rig views with a ring motif at the image centre in `motif_views` and a straight line near
    the top in every view; vertex 0 is the centroid (projects to the centre), vertex 1 lies
    above it (projects onto the line)."""
    rig = Rig()
    cams = rig.matrices()
    verts = np.array([[0, 0, 0], [0, 0, 0.75]], np.float32)
    pix, _ = project(cams, verts)
    images = np.zeros((12, 200, 200), np.float32)
    for v in range(12):
        y = int(pix[v, 1, 1])
        rr, cc = line(y, 50, y, 150)
        images[v, rr, cc] = 1
        if v in motif_views:
            for radius in (4, 8):
                rr, cc = circle_perimeter(100, 100, radius)
                images[v, rr, cc] = 1
    d = ShapeDrawings("s", images, cams, verts, np.zeros(2, np.int32), np.ones((12, 2), bool),
                      pix.astype(np.float32), np.ones((12, 2), bool))
    return d, verts, pix


def test_vertex_under_the_style_motif_is_marked_and_one_under_a_generic_line_is_not():
    motif_views = {0, 1, 2, 3, 4, 5}
    d, verts, pix = _drawings(motif_views)
    maps = hog_images(d.images)
    ring, _ = patch_descriptors(maps, np.array([0]), np.array([[100.0, 100.0]]), 24)
    edge, _ = patch_descriptors(maps, np.array([0]), pix[0, 1][None], 24)
    words = np.concatenate([ring, edge])
    loc = localise_shape(d, verts, words, np.array([0, -1]), cluster=0, patch_size=24,
                         threshold=0.5, maps=maps)
    # the centre is style-bearing in the 6 of 12 views that show the ring
    assert abs(loc.weights[0] - 0.5) < 1e-6
    assert loc.weights[1] == 0.0
    assert loc.best_view in motif_views and loc.view_scores[6:].sum() == 0
    assert all(v in motif_views for v, *_ in loc.matches)
    # the same words seen as another cluster's style mark nothing
    other = localise_shape(d, verts, words, np.array([1, -1]), cluster=0, patch_size=24,
                           threshold=0.5, maps=maps)
    assert other.weights.max() == 0.0


def test_top_words_keeps_each_clusters_best():
    wc = np.array([0, 0, 0, 1, 1, -1])
    score = np.array([0.1, 0.9, 0.5, 0.2, 0.3, -np.inf])
    assert top_words(wc, score, 2).tolist() == [-1, 0, 0, 1, 1, -1]
    assert top_words(wc, score, 1).tolist() == [-1, 0, -1, -1, 1, -1]
