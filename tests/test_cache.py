"""The per-shape drawing cache: hits, misses on changed geometry, damaged entries recomputed."""
import numpy as np
import pytest

from conftest import DAMAGES, damage_entry
from style_coanalysis.cache import DrawingCache, cache_key, default_cache_dir
from style_coanalysis.drawings import ShapeDrawings
from style_coanalysis.meshes import Mesh, normalise
from style_coanalysis.params import DrawingSettings


def tetra(name="tet", shift=0.0):
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1 + shift]], float)
    return Mesh(name, v, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def fake_drawings(mesh, rng):
    return ShapeDrawings(mesh.name, rng.random((12, 20, 20)).astype(np.float32),
                         rng.random((12, 3, 4)), rng.random((5, 3)).astype(np.float32),
                         np.arange(5, dtype=np.int32), rng.random((12, 5)) > 0.5,
                         rng.random((12, 5, 2)).astype(np.float32))


class Counter:
    def __init__(self, mesh):
        self.mesh, self.calls, self.rng = mesh, 0, np.random.default_rng(0)

    def __call__(self):
        self.calls += 1
        return fake_drawings(self.mesh, self.rng)


def test_second_lookup_hits_and_round_trips(tmp_path):
    cache, mesh, s = DrawingCache(tmp_path), tetra(), DrawingSettings()
    compute = Counter(mesh)
    first, cached = cache.get_or_compute(mesh, s, compute)
    assert not cached
    again, cached = cache.get_or_compute(mesh, s, compute)
    assert cached and compute.calls == 1
    for k, v in first.to_arrays().items():
        assert np.array_equal(v, again.to_arrays()[k]), k
    # same geometry under another name shares the entry and takes the caller's name
    renamed, cached = cache.get_or_compute(tetra("other"), s, compute)
    assert cached and renamed.name == "other"
    files = [p for p in tmp_path.rglob("*") if p.is_file()]
    assert files and all(p.suffix == ".npz" and not p.name.startswith(".") for p in files)  # no temporaries


def test_entry_with_the_former_vertex_visibility_still_loads(tmp_path):
    """Entries written before the drawings stopped holding each vertex's visibility (nothing
    read it) are served as they are: the user's cache is not rendered again."""
    cache, mesh, s = DrawingCache(tmp_path), tetra(), DrawingSettings()
    d = fake_drawings(mesh, np.random.default_rng(1))
    key = cache_key(mesh, s)
    cache.store_arrays(key, d.to_arrays() | {"vertex_visible": np.ones((12, 4), bool)})
    again, cached = cache.get_or_compute(mesh, s, Counter(mesh))
    assert cached
    for k, v in d.to_arrays().items():
        assert np.array_equal(v, again.to_arrays()[k]), k


def test_moved_vertex_or_other_settings_miss(tmp_path):
    cache, s = DrawingCache(tmp_path), DrawingSettings()
    compute = Counter(tetra())
    cache.get_or_compute(tetra(), s, compute)
    cache.get_or_compute(tetra(shift=1e-4), s, compute)
    cache.get_or_compute(tetra(), DrawingSettings(renderer="lineart"), compute)
    cache.get_or_compute(tetra(), s, compute, version="another")
    assert compute.calls == 4
    assert len({cache_key(tetra(), s), cache_key(tetra(shift=1e-4), s),
                cache_key(tetra(), DrawingSettings(seed=1))}) == 3


@pytest.mark.parametrize("damage", DAMAGES)
def test_damaged_entry_is_recomputed(tmp_path, damage):
    cache, mesh, s = DrawingCache(tmp_path), tetra(), DrawingSettings()
    compute = Counter(mesh)
    good, _ = cache.get_or_compute(mesh, s, compute)
    path = cache.path(cache_key(mesh, s))
    other = tetra(shift=0.5)                          # another shape's valid entry
    cache.get_or_compute(other, s, Counter(other))
    damage_entry(path, damage, "images", cache.path(cache_key(other, s)))
    assert cache.load(cache_key(mesh, s)) is None
    assert not path.exists()                          # the bad entry is gone
    again, cached = cache.get_or_compute(mesh, s, compute)
    assert not cached and compute.calls == 2
    assert cache.load(cache_key(mesh, s)) is not None


def test_default_dir_follows_xdg(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert default_cache_dir() == tmp_path / "style_coanalysis"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path))
    assert default_cache_dir() == tmp_path / ".cache" / "style_coanalysis"


# ---------------------------------------------------------------- with Blender: draw_collection
def box(name, sx=1.0):
    v = np.array([[x * sx, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return Mesh(name, v, [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])


@pytest.mark.blender
def test_collection_second_run_renders_nothing(tmp_path, monkeypatch):
    pytest.importorskip("bpy")
    import bpy

    from style_coanalysis.blender import batch, render
    bpy.ops.wm.read_factory_settings(use_empty=True)
    calls = []
    real = render.draw_shape_steps
    monkeypatch.setattr(render, "draw_shape_steps",
                        lambda m, s, **kw: calls.append(m.name) or real(m, s, **kw))
    shapes = [box("a"), box("b", 2.0), Mesh("empty", np.zeros((3, 3)), np.zeros((0, 3)))]
    s = DrawingSettings(renderer="lineart")
    events = []
    first, skipped = batch.draw_collection(shapes, s, cache_dir=tmp_path, jobs=1,
                                           progress=lambda *e: events.append(e))
    assert [d.name for d in first] == ["a", "b"] and calls == ["a", "b"]
    assert skipped == [("empty", "'empty' has no faces")]
    assert ("render", 2, 2) in events
    second, _ = batch.draw_collection(shapes, s, cache_dir=tmp_path, jobs=1)
    assert calls == ["a", "b"]                        # nothing rendered the second time
    assert np.array_equal(first[1].images, second[1].images)
    with pytest.raises(batch.Cancelled):
        batch.draw_collection(shapes, DrawingSettings(renderer="lineart", seed=9),
                              cache_dir=tmp_path, jobs=1, cancel=lambda: True)


@pytest.mark.blender
@pytest.mark.slow
def test_collection_in_worker_processes_matches_in_process(tmp_path):
    pytest.importorskip("bpy")
    from style_coanalysis.blender import batch
    shapes = [box("a"), box("b", 1.5)]
    s = DrawingSettings(renderer="lineart")
    par, skipped = batch.draw_collection(shapes, s, cache_dir=False, jobs=2)
    seq, _ = batch.draw_collection(shapes, s, cache_dir=False, jobs=1)
    assert not skipped and [d.name for d in par] == ["a", "b"]
    for p, q in zip(par, seq):
        assert np.array_equal(p.images, q.images) and np.array_equal(p.seed_visible, q.seed_visible)
        assert np.array_equal(p.seeds, q.seeds)
    # the seeds lie on the normalised mesh's faces
    assert par[0].seed_faces.max() < len(normalise(shapes[0]).faces)


def test_ctrl_c_while_writing_leaves_nothing_and_reports_nothing(tmp_path, monkeypatch):
    """Ctrl-C in the middle of writing an entry (CI once caught it there): no entry, no
    temporary, and no zip writer left on a closed file to print a traceback when collected."""
    import gc
    import sys
    cache, mesh = DrawingCache(tmp_path), tetra()
    drawings = fake_drawings(mesh, np.random.default_rng(0))
    calls, write_array = [], np.lib.format.write_array

    def interrupted(*args, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return write_array(*args, **kwargs)

    monkeypatch.setattr(np.lib.format, "write_array", interrupted)
    unraisable = []
    monkeypatch.setattr(sys, "unraisablehook", unraisable.append)
    with pytest.raises(KeyboardInterrupt):
        cache.store(cache_key(mesh, DrawingSettings()), drawings)
    gc.collect()
    assert len(calls) == 3 and not unraisable
    assert not [p for p in tmp_path.rglob("*") if p.is_file()]
