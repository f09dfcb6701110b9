"""Issue 15: a second run on unchanged shapes reads what the first computed (HOG maps) instead of
redoing it, gives the identical result, and never trusts a damaged or foreign entry."""
import numpy as np
import pytest

from style_coanalysis import features
from style_coanalysis.cache import HogCache, hog_key, images_digest


def images(seed=0, n=3, size=48):
    """Line-like images: a few random strokes of ink on paper (HOG of them is not all zero)."""
    rng = np.random.default_rng(seed)
    out = np.zeros((n, size, size), np.float32)
    for v in range(n):
        for _ in range(6):
            r, c = rng.integers(0, size, 2)
            out[v, r, :] = 1.0
            out[v, :, c] = 1.0
    return out


class Counter:
    def __init__(self, imgs):
        self.imgs, self.calls = imgs, 0

    def __call__(self):
        self.calls += 1
        return features.hog_images(self.imgs)


def test_hog_maps_round_trip_exactly(tmp_path):
    cache, imgs = HogCache(tmp_path), images()
    compute = Counter(imgs)
    first, cached = cache.get_or_compute(imgs, compute)
    assert not cached and first.any()
    again, cached = cache.get_or_compute(imgs.copy(), compute)
    assert cached and compute.calls == 1
    assert again.dtype == np.float32 and np.array_equal(again, first)
    assert (tmp_path / "hog").is_dir()               # its own subfolder of the cache root
    assert not list(tmp_path.rglob(".tmp-*"))         # no temporary files left behind


def test_other_images_or_version_miss(tmp_path):
    cache, imgs = HogCache(tmp_path), images()
    cache.get_or_compute(imgs, Counter(imgs))
    moved = imgs.copy()
    moved[0, 0, 0] = 1.0 - moved[0, 0, 0]             # one pixel of one view
    compute = Counter(moved)
    cache.get_or_compute(moved, compute)
    assert compute.calls == 1
    assert hog_key(images_digest(imgs)) != hog_key(images_digest(imgs), version="hog-other")
    assert hog_key(images_digest(imgs)) != hog_key(images_digest(imgs.astype(np.float64)))


@pytest.mark.parametrize("damage", ["truncate", "flip", "swap"])
def test_damaged_hog_entry_is_recomputed(tmp_path, damage):
    cache, imgs = HogCache(tmp_path), images()
    compute = Counter(imgs)
    good, _ = cache.get_or_compute(imgs, compute)
    key = hog_key(images_digest(imgs))
    path = cache.path(key)
    raw = path.read_bytes()
    if damage == "truncate":
        path.write_bytes(raw[: len(raw) // 2])
    elif damage == "flip":
        # rewrite the maps inside a valid zip: only the checksum can tell
        with np.load(path) as z:
            arrays = {k: z[k] for k in z.files}
        arrays["maps"] = arrays["maps"].copy()
        arrays["maps"].flat[np.argmax(arrays["maps"])] += 0.5
        np.savez(path, **arrays)
    else:
        # another shape's valid entry under this key
        other = images(seed=1)
        cache.get_or_compute(other, Counter(other))
        path.write_bytes(cache.path(hog_key(images_digest(other))).read_bytes())
    assert cache.load(key) is None
    assert not path.exists()                          # the bad entry is gone
    again, cached = cache.get_or_compute(imgs, compute)
    assert not cached and compute.calls == 2
    assert np.array_equal(again, good)


# ---- the whole job, twice on the same shapes -------------------------------------------------

def run(meshes, options):
    from style_coanalysis.blender.job import run_steps
    steps = run_steps(meshes, options)
    while True:
        try:
            next(steps)
        except StopIteration as stop:
            return stop.value


def outcome(result):
    """Everything a run hands on, as plain values."""
    a = result.analysis
    return {"clusters": a.clusters.tolist(), "fused": a.fused.tolist(),
            "confidence": a.confidence.tolist(), "words": a.words.tolist(),
            "word_score": a.word_score.tolist(), "rounds": a.rounds,
            "shapes": [(s.name, s.cluster, s.confidence, s.best_view, s.vertex_weights.tolist())
                       for s in result.shapes],
            "report_shapes": result.report["shapes"], "clusters_report": result.clusters}


@pytest.fixture
def counted(monkeypatch):
    """Counts the job's HOG computations (the job looks `hog_images` up when it runs)."""
    calls = []
    real = features.hog_images

    def hog_images(imgs):
        calls.append(len(imgs))
        return real(imgs)
    monkeypatch.setattr(features, "hog_images", hog_images)
    return calls


@pytest.mark.blender
def test_second_job_reads_the_maps_and_gives_the_same_result(tmp_path, counted):
    pytest.importorskip("bpy")
    from style_coanalysis import sample
    from style_coanalysis.options import build_options
    meshes = sample.generate(size=4, seed=0)
    options = build_options(renderer="zbuffer", jobs=1, cache_dir=tmp_path, clusters=2, rounds=1)
    first = run(meshes, options)
    assert len(counted) == 4                           # one HOG computation per shape
    assert len(list((tmp_path / "hog").rglob("*.npz"))) == 4
    second = run(meshes, options)
    assert len(counted) == 4                           # none more: every shape's maps were read
    assert outcome(second) == outcome(first)

    # a drawing setting that changes the drawings (the up axis) misses and computes again
    other = build_options(renderer="zbuffer", jobs=1, cache_dir=tmp_path, clusters=2, rounds=1,
                          up="y")
    run(meshes, other)
    assert len(counted) == 8

    # no cache asked for: nothing read, nothing written
    before = sorted(tmp_path.rglob("*.npz"))
    run(meshes, build_options(renderer="zbuffer", jobs=1, cache_dir=False, clusters=2, rounds=1))
    assert len(counted) == 12 and sorted(tmp_path.rglob("*.npz")) == before
