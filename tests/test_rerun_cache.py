"""Issue 15: a second run on unchanged shapes reads what the first computed (HOG maps, the
analysis, the style regions) instead of redoing it, gives the identical result, and never trusts a damaged or
foreign entry; a changed drawing, parameter or label computes again."""
import numpy as np
import pytest

from conftest import DAMAGES, damage_entry
from style_coanalysis import features, localisation, pipeline
from style_coanalysis.cache import (AnalysisCache, HogCache, RegionCache, analysis_key, hog_key,
                                    images_digest, result_from_arrays, result_to_arrays)


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


def get_or_compute(cache, imgs, compute):
    """(maps, was_cached) of `imgs` as the job reads and fills the HOG cache."""
    key = hog_key(images_digest(imgs))
    hit = cache.load(key)
    if hit is not None:
        return hit, True
    maps = compute()
    cache.store(key, maps)
    return maps, False


def test_hog_maps_round_trip_exactly(tmp_path):
    cache, imgs = HogCache(tmp_path), images()
    compute = Counter(imgs)
    first, cached = get_or_compute(cache, imgs, compute)
    assert not cached and first.any()
    again, cached = get_or_compute(cache, imgs.copy(), compute)
    assert cached and compute.calls == 1
    assert again.dtype == np.float32 and np.array_equal(again, first)
    assert (tmp_path / "hog").is_dir()               # its own subfolder of the cache root
    files = [p for p in tmp_path.rglob("*") if p.is_file()]
    assert files and all(p.suffix == ".npz" and not p.name.startswith(".") for p in files)  # no temporaries


def test_other_images_or_version_miss(tmp_path):
    cache, imgs = HogCache(tmp_path), images()
    get_or_compute(cache, imgs, Counter(imgs))
    moved = imgs.copy()
    moved[0, 0, 0] = 1.0 - moved[0, 0, 0]             # one pixel of one view
    compute = Counter(moved)
    get_or_compute(cache, moved, compute)
    assert compute.calls == 1
    assert hog_key(images_digest(imgs)) != hog_key(images_digest(imgs), version="hog-other")
    assert hog_key(images_digest(imgs)) != hog_key(images_digest(imgs.astype(np.float64)))


@pytest.mark.parametrize("damage", DAMAGES)
def test_damaged_hog_entry_is_recomputed(tmp_path, damage):
    cache, imgs = HogCache(tmp_path), images()
    compute = Counter(imgs)
    good, _ = get_or_compute(cache, imgs, compute)
    key = hog_key(images_digest(imgs))
    path = cache.path(key)
    other = images(seed=1)                            # another shape's valid entry
    get_or_compute(cache, other, Counter(other))
    damage_entry(path, damage, "maps", cache.path(hog_key(images_digest(other))))
    assert cache.load(key) is None
    assert not path.exists()                          # the bad entry is gone
    again, cached = get_or_compute(cache, imgs, compute)
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


def same_result(a, b):
    """Every field of two AnalysisResults equal (arrays exactly, dtype included)."""
    from dataclasses import fields
    for f in fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if f.name == "style_filters":
            assert len(x) == len(y)
            for p, q in zip(x, y):
                assert np.array_equal(p.hog, q.hog) and p.hog.dtype == q.hog.dtype
                for g in fields(p):
                    if g.name != "hog":
                        assert getattr(p, g.name) == getattr(q, g.name), g.name
        elif isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            assert np.array_equal(x, y) and np.asarray(x).dtype == np.asarray(y).dtype, f.name
        else:
            assert x == y, f.name


@pytest.fixture
def counted(monkeypatch):
    """Counts the job's HOG computations, analyses and style regions (the job looks them up when
    it runs)."""
    calls = {"hog": 0, "analyse": 0, "localise": 0}
    real_hog, real_analyse = features.hog_images, pipeline.analyse
    real_localise = localisation.localise_shape

    def hog_images(images):
        calls["hog"] += 1
        return real_hog(images)

    def analyse(*a, **k):
        calls["analyse"] += 1
        return real_analyse(*a, **k)
    def localise_shape(*a, **k):
        calls["localise"] += 1
        return real_localise(*a, **k)
    monkeypatch.setattr(features, "hog_images", hog_images)
    monkeypatch.setattr(pipeline, "analyse", analyse)
    monkeypatch.setattr(localisation, "localise_shape", localise_shape)
    return calls


@pytest.mark.blender
def test_second_job_reads_maps_analysis_and_regions_and_gives_the_same_result(tmp_path, counted):
    pytest.importorskip("bpy")
    from style_coanalysis import sample
    from style_coanalysis.options import build_options

    def opts(**kw):
        return build_options(**{"renderer": "zbuffer", "jobs": 1, "cache_dir": tmp_path,
                                "clusters": 2, "rounds": 1} | kw)
    meshes = sample.generate(size=4, seed=0)
    first = run(meshes, opts())
    assert counted == {"hog": 4, "analyse": 1, "localise": 4}     # once per shape
    assert len(list((tmp_path / "hog").rglob("*.npz"))) == 4
    assert len(list((tmp_path / "analysis").rglob("*.npz"))) == 1
    assert len(list((tmp_path / "regions").rglob("*.npz"))) == 4
    second = run(meshes, opts())
    assert counted == {"hog": 4, "analyse": 1, "localise": 4}     # nothing computed again
    assert outcome(second) == outcome(first)
    same_result(second.analysis, first.analysis)
    for a, b in zip(second.localisations, first.localisations):
        assert a.best_view == b.best_view and a.matches == b.matches
        for f in ("weights", "face_weights", "view_scores"):
            x, y = getattr(a, f), getattr(b, f)
            assert np.array_equal(x, y) and x.dtype == y.dtype, f

    # a changed analysis parameter, label or order re-runs the analysis on the cached maps, and
    # the regions of its result
    run(meshes, opts(rounds=2))
    assert counted == {"hog": 4, "analyse": 2, "localise": 8}
    run(meshes, opts(labels={meshes[0].name: "a", meshes[1].name: "b"}))
    run(meshes, opts(labels={meshes[0].name: "a", meshes[1].name: "c"}))
    run(meshes[::-1], opts())
    assert counted == {"hog": 4, "analyse": 5, "localise": 20}
    run(meshes, opts(rounds=2))                         # and that one was cached too
    assert counted == {"hog": 4, "analyse": 5, "localise": 20}

    # damaged analysis and region entries are not trusted: removed, computed again, same result
    for path in (tmp_path / "analysis").rglob("*.npz"):
        path.write_bytes(path.read_bytes()[:100])
    third = run(meshes, opts())
    assert counted == {"hog": 4, "analyse": 6, "localise": 20}   # the same analysis: its regions
    assert outcome(third) == outcome(first)
    for path in (tmp_path / "regions").rglob("*.npz"):
        path.write_bytes(path.read_bytes()[:100])
    fourth = run(meshes, opts())
    assert counted == {"hog": 4, "analyse": 6, "localise": 24}   # this run's regions redone
    assert outcome(fourth) == outcome(first)

    # a damaged HOG entry is computed again (the same maps: the analysis and regions are read)
    damaged = sorted((tmp_path / "hog").rglob("*.npz"))[0]
    damaged.write_bytes(damaged.read_bytes()[:100])
    fifth = run(meshes, opts())
    assert counted == {"hog": 5, "analyse": 6, "localise": 24}
    assert outcome(fifth) == outcome(first)

    # a drawing setting that changes the drawings (the up axis) misses all three
    run(meshes, opts(up="y"))
    assert counted == {"hog": 9, "analyse": 7, "localise": 28}

    # no cache asked for: nothing read, nothing written
    before = sorted(tmp_path.rglob("*.npz"))
    run(meshes, opts(cache_dir=False))
    assert counted == {"hog": 13, "analyse": 8, "localise": 32}
    assert sorted(tmp_path.rglob("*.npz")) == before


@pytest.mark.blender
def test_maps_and_regions_in_two_processes_are_those_of_one(tmp_path):
    """The HOG maps and the style regions not cached are computed in `jobs` processes: the
    result is the serial one, in input order, and every map is cached once."""
    pytest.importorskip("bpy")
    from style_coanalysis import sample
    from style_coanalysis.options import build_options

    meshes = sample.generate(size=5, seed=1)
    one, two = (run(meshes, build_options(renderer="zbuffer", jobs=jobs, clusters=2, rounds=1,
                                          cache_dir=tmp_path / f"c{jobs}")) for jobs in (1, 2))
    assert outcome(two) == outcome(one)
    for a, b in zip(two.localisations, one.localisations):
        assert a.best_view == b.best_view and a.matches == b.matches
        assert np.array_equal(a.face_weights, b.face_weights)
    assert len(list((tmp_path / "c2" / "hog").rglob("*.npz"))) == 5
    assert len(list((tmp_path / "c2" / "regions").rglob("*.npz"))) == 5


def analysed(labels=None, clusters=2):
    """A real analysis of four small synthetic shapes (no Blender)."""
    from style_coanalysis.drawings import ShapeDrawings
    from style_coanalysis.options import build_options
    rng = np.random.default_rng(0)
    shapes = []
    for i in range(4):
        imgs = images(seed=i, n=2, size=64)
        px = rng.uniform(12, 52, (2, 6, 2)).astype(np.float32)
        shapes.append(ShapeDrawings(f"s{i}", imgs, rng.random((2, 3, 4)),
                                    rng.random((6, 3)).astype(np.float32),
                                    np.arange(6, dtype=np.int32), np.ones((2, 6), bool), px))
    params = build_options(clusters=clusters, rounds=2).params
    return shapes, params, pipeline.analyse(shapes, params, labels=labels)


@pytest.mark.parametrize("labels, clusters", [(None, 2), ({"s0": "x", "s3": "y"}, 2),
                                              (None, "auto")])
def test_analysis_result_round_trips_exactly(tmp_path, labels, clusters):
    shapes, params, result = analysed(labels, clusters)
    assert (result.k_gaps is None) == (clusters != "auto")
    assert (result.dictionary_agreement is None) == (labels is not None)
    same_result(result_from_arrays(result_to_arrays(result)), result)
    cache = AnalysisCache(tmp_path)
    key = analysis_key(["d0", "d1", "d2", "d3"], params.as_dict(), labels, None)
    cache.store(key, result)
    same_result(cache.load(key, [d.name for d in shapes]), result)
    assert cache.load(key, ["s0", "s1", "s2", "other"]) is None     # not this collection's
    assert not cache.path(key).exists()


def test_analysis_key_sees_every_input():
    params = pipeline.AnalysisParams().as_dict()
    base = analysis_key(["a", "b"], params, {"x": "1"}, None)
    assert base == analysis_key(["a", "b"], dict(params), {"x": "1"}, None)
    others = [analysis_key(["b", "a"], params, {"x": "1"}, None),
              analysis_key(["a", "c"], params, {"x": "1"}, None),
              analysis_key(["a", "b"], params | {"mu": params["mu"] + 1e-9}, {"x": "1"}, None),
              analysis_key(["a", "b"], params, {"x": "2"}, None),
              analysis_key(["a", "b"], params, None, None),
              analysis_key(["a", "b"], params, None, [("a", "b", "c")]),
              analysis_key(["a", "b"], params, {"x": "1"}, None, version="analysis-other")]
    assert len({base, *others}) == 1 + len(others)


def test_region_entry_round_trips_exactly_and_a_damaged_one_is_dropped(tmp_path):
    from style_coanalysis.localisation import ShapeLocalisation
    rng = np.random.default_rng(0)
    loc = ShapeLocalisation(rng.random(7).astype(np.float32), rng.random(9).astype(np.float32),
                            3, [(0, 12.5, 40.0, 0.71), (3, 100.0, 8.25, 0.6)],
                            np.array([0, 2, 0, 5]))
    cache = RegionCache(tmp_path)
    cache.store("ab" * 32, loc)
    back = cache.load("ab" * 32)
    assert back.best_view == 3 and back.matches == loc.matches
    for f in ("weights", "face_weights", "view_scores"):
        assert np.array_equal(getattr(back, f), getattr(loc, f))
        assert getattr(back, f).dtype == getattr(loc, f).dtype
    empty = ShapeLocalisation(loc.weights, loc.face_weights, 0, [], loc.view_scores)
    cache.store("cd" * 32, empty)
    assert cache.load("cd" * 32).matches == []
    path = cache.path("ab" * 32)
    path.write_bytes(path.read_bytes()[:50])
    assert cache.load("ab" * 32) is None and not path.exists()
