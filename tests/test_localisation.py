"""Back-projection of style words to style regions (pure core, synthetic meshes and drawings)."""
import numpy as np
from scipy import sparse
from skimage.draw import circle_perimeter, line

from style_coanalysis import regions
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


def _quad(x0, x1, y0, y1, z):
    v = np.array([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]], np.float64)
    return v, np.array([[0, 1, 2], [0, 2, 3]])


def test_face_buffer_keeps_the_nearest_face_and_marks_silhouettes():
    cam = Rig(elevation_deg=89.0).matrices()[0]          # looking straight down
    near, fn = _quad(-0.5, 0.5, -0.5, 0.5, 0.2)
    far, ff = _quad(-0.8, 0.8, -0.8, 0.8, -0.2)
    verts = np.concatenate([near, far])
    faces = np.concatenate([fn, ff + 4])
    bufs, depths = regions.face_buffers(verts, faces, cam[None], 200)
    buf, depth = bufs[0], depths[0]
    centre = project(cam[None], np.zeros((1, 3)))[0][0, 0].astype(int)
    assert buf[centre[1], centre[0]] in (0, 1)            # the near square hides the far one
    assert buf[0, 0] == -1 and not np.isfinite(depth[0, 0])
    assert set(np.unique(buf)) == {-1, 0, 1, 2, 3}        # the far square shows around it
    outline = regions.outline_pixels(depth[None], 0.1)[0]
    # the near square's border (a depth step of 0.4) and the far square's border are outlines;
    # the middle of a face is not
    assert outline[centre[1], centre[0]] == False          # noqa: E712
    row = centre[1]
    assert outline[row].sum() >= 4


def test_extension_fills_unseen_faces_from_neighbours_and_keeps_measured_ones():
    # a strip of 5 faces: 0-1-2-3-4; faces 1 and 3 never seen
    adj = sparse.diags([np.ones(4), np.ones(4)], [-1, 1], shape=(5, 5)).tocsr()
    marked = np.array([1.0, 0, 0, 0, 0])
    seen = np.array([1.0, 0, 2, 0, 1])
    out = regions.extend(marked, seen, adj, steps=2)
    assert out[0] == 1.0 and out[2] == 0.0 and out[4] == 0.0
    assert out[1] == 0.5 and out[3] == 0.0                  # mean of its measured neighbours


def test_carved_region_needs_a_seed_and_stops_where_the_strokes_stop():
    adj = sparse.diags([np.ones(5), np.ones(5)], [-1, 1], shape=(6, 6)).tocsr()
    dense = np.array([True, True, False, True, True, True])
    seed = np.array([False, False, False, False, True, False])
    assert regions.seeded_components(dense, seed, adj).tolist() == [False, False, False, True, True, True]


def _plate_and_drawings():
    """A finely tessellated small square (the 'ornament') beside a big plain square made of two
    triangles, on the ground plane; each view draws a ring motif over the small square and a
    straight generic line across the big one."""
    n = 8
    xs = np.linspace(-0.1, 0.1, n + 1)
    gx, gy = np.meshgrid(xs, xs)
    fine = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], 1)
    q = np.arange(n * (n + 1)).reshape(n, n + 1)[:, :n].ravel()
    fine_f = np.concatenate([np.stack([q, q + 1, q + n + 2], 1), np.stack([q, q + n + 2, q + n + 1], 1)])
    big, big_f = _quad(0.25, 0.95, -0.35, 0.35, 0.0)
    verts = np.concatenate([fine, big]).astype(np.float32)
    faces = np.concatenate([fine_f, big_f + len(fine)])
    rig = Rig()
    cams = rig.matrices()
    centres, _ = project(cams, np.array([[0.0, 0, 0], [0.6, 0, 0]]))
    images = np.zeros((12, 200, 200), np.float32)
    for v in range(12):
        (cx, cy), (bx, by) = centres[v]
        for radius in (4, 8):
            rr, cc = circle_perimeter(int(cy), int(cx), radius, shape=(200, 200))
            images[v, rr, cc] = 1
        rr, cc = line(int(by), int(bx) - 30, int(by), int(bx) + 30)
        images[v, rr, cc] = 1
    d = ShapeDrawings("s", images, cams, verts[:2], np.zeros(2, np.int32), np.ones((12, 2), bool),
                      np.zeros((12, 2, 2), np.float32))
    return d, verts, faces, centres, len(fine_f)


def test_the_style_motif_marks_the_small_faces_under_it_and_not_the_plain_face_beside_it():
    d, verts, faces, centres, n_fine = _plate_and_drawings()
    maps = hog_images(d.images)
    ring, _ = patch_descriptors(maps, np.array([0]), centres[0, 0][None], 24)
    edge, _ = patch_descriptors(maps, np.array([0]), centres[0, 1][None], 24)
    words = np.concatenate([ring, edge])
    loc = localise_shape(d, verts, faces, words, np.array([0, -1]), cluster=0, patch_size=24,
                         threshold=0.5, maps=maps)
    assert loc.face_weights.shape == (len(faces),) and loc.weights.shape == (len(verts),)
    assert (loc.face_weights[:n_fine] > 0.5).mean() > 0.9    # the ornament
    assert (loc.face_weights[n_fine:] <= 0.5).all()          # the big plain face beside it
    assert all(0 <= v < 12 for v, *_ in loc.matches) and loc.view_scores.sum() > 0
    # the same words seen as another cluster's style mark nothing
    other = localise_shape(d, verts, faces, words, np.array([1, -1]), cluster=0, patch_size=24,
                           threshold=0.5, maps=maps)
    assert other.face_weights.max() <= 0.5 and other.view_scores.sum() == 0


def test_vertex_weights_are_the_area_weighted_mean_of_their_faces():
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    w = regions.vertex_weights(np.array([1.0, 0.0]), faces, np.array([3.0, 1.0]), 5)
    assert np.allclose(w, [0.75, 1.0, 0.75, 0.0, 0.0])


def test_top_words_keeps_each_clusters_best():
    wc = np.array([0, 0, 0, 1, 1, -1])
    score = np.array([0.1, 0.9, 0.5, 0.2, 0.3, -np.inf])
    assert top_words(wc, score, 2).tolist() == [-1, 0, 0, 1, 1, -1]
    assert top_words(wc, score, 1).tolist() == [-1, 0, -1, -1, 1, -1]
