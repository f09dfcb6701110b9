"""The default method's synthetic vocabulary: the same words whatever the collection."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import DAMAGES, damage_entry

from style_coanalysis import cache, vocabulary
from style_coanalysis.cache import VocabularyCache
from style_coanalysis.features import patch_blocks

ROOT = Path(__file__).resolve().parent.parent


def test_synthetic_descriptors_are_inked_and_a_function_of_the_seed():
    a = vocabulary.synthetic_descriptors(24, 3, n=300)
    assert a.shape == (300, patch_blocks(24), patch_blocks(24), 36)
    assert (a.reshape(300, -1).max(axis=1) > 0).all()               # no blank paper
    np.testing.assert_array_equal(a, vocabulary.synthetic_descriptors(24, 3, n=300))
    assert not np.array_equal(a, vocabulary.synthetic_descriptors(24, 4, n=300))


def test_a_canvas_is_a_line_drawing():
    img = vocabulary.synthetic_canvas(np.random.default_rng(0))
    assert img.shape == (200, 200) and set(np.unique(img)) <= {0.0, 1.0}
    assert 0.005 < img.mean() < 0.2                                 # thin lines on paper


def test_words_are_unit_and_kept_on_disk(tmp_path, monkeypatch):
    w = vocabulary.words(16, 12, 5, tmp_path)
    assert w.shape == (12, 1, 1, 36) and w.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(w.reshape(12, -1), axis=1), 1, atol=1e-5)
    assert len(np.unique(w.reshape(12, -1), axis=0)) == 12
    # another process: read from the disk, not computed again
    vocabulary.words.cache_clear()
    monkeypatch.setattr(vocabulary, "compute_words", lambda *a: pytest.fail("recomputed"))
    np.testing.assert_array_equal(vocabulary.words(16, 12, 5, tmp_path), w)


@pytest.mark.parametrize("how", DAMAGES)
def test_a_damaged_vocabulary_file_is_computed_again(tmp_path, how):
    w = vocabulary.words(16, 10, 6, tmp_path)
    other = vocabulary.words(16, 9, 6, tmp_path)
    assert len(other) == 9
    store = VocabularyCache(tmp_path)
    path = store.path(VocabularyCache.key(16, 10, 6))
    damage_entry(path, how, "words", store.path(VocabularyCache.key(16, 9, 6)))
    assert store.load(VocabularyCache.key(16, 10, 6)) is None
    vocabulary.words.cache_clear()
    np.testing.assert_array_equal(vocabulary.words(16, 10, 6, tmp_path), w)


def test_no_cache_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    vocabulary.words.cache_clear()
    vocabulary.words(16, 8, 7, False)
    assert not any(tmp_path.rglob("*"))


def test_a_dictionary_made_by_other_code_is_not_served(tmp_path, monkeypatch):
    # an edit to the canvases, the HOG maps or the k-means changes the key: made anew, not read
    w = vocabulary.words(16, 10, 7, tmp_path)
    assert VocabularyCache(tmp_path).load(VocabularyCache.key(16, 10, 7)) is not None  # kept
    vocabulary.words.cache_clear()
    monkeypatch.setattr(cache, "vocabulary_version", lambda: "edited")
    made = []
    compute = vocabulary.compute_words
    monkeypatch.setattr(vocabulary, "compute_words", lambda *a: made.append(a) or compute(*a))
    np.testing.assert_array_equal(vocabulary.words(16, 10, 7, tmp_path), w)
    assert made == [(16, 10, 7)]
    vocabulary.words.cache_clear()


def test_the_shipped_words_are_what_the_code_makes_for_the_default_seed(monkeypatch):
    # the default analysis reads every one of them, and each is what computing it gives: a change
    # to the canvases, HOG maps, k-means or defaults fails here until tools/make_vocabularies.py
    from style_coanalysis.params import AnalysisParams
    from style_coanalysis.pipeline import vocabulary_specs
    specs = vocabulary_specs(AnalysisParams())
    shipped = vocabulary._shipped()
    assert sorted(shipped) == sorted(vocabulary.shipped_name(*s) for s in specs)
    for spec in specs:
        np.testing.assert_array_equal(shipped[vocabulary.shipped_name(*spec)],
                                      vocabulary.compute_words(*spec))
    # and a run reads them without computing or caching anything
    vocabulary.words.cache_clear()
    monkeypatch.setattr(vocabulary, "compute_words", lambda *a: pytest.fail("computed"))
    for spec in specs:
        assert vocabulary.words(*spec, False) is shipped[vocabulary.shipped_name(*spec)]
    vocabulary.words.cache_clear()


def test_the_same_words_under_other_numeric_kernels():
    """A seed's words are computed where they are used, so every machine must draw the same
    ones: here once as this machine runs, once with OpenBLAS's oldest x86 kernels and numpy's
    AVX-512 ones off. With scikit-learn's k-means the words of this dictionary (an analysis
    seed 2 draws it) differed between OpenBLAS's Haswell, SkylakeX and Prescott kernels."""
    from numpy.core._multiarray_umath import __cpu_features__
    script = ("import hashlib; from style_coanalysis.vocabulary import compute_words; "
              "print(hashlib.sha1(compute_words(16, 200, 63048422).tobytes()).hexdigest())")
    avx512 = " ".join(k for k, on in __cpu_features__.items() if on and k.startswith("AVX512"))

    def run(**env):
        return subprocess.run([sys.executable, "-c", script], env={**os.environ, **env},
                              cwd=ROOT, capture_output=True, text=True, check=True).stdout

    native = run()
    assert len(native.strip()) == 40
    assert native == run(OPENBLAS_CORETYPE="Prescott", NPY_DISABLE_CPU_FEATURES=avx512)


def test_exact_kmeans_is_a_partition_into_nearest_centres():
    rng = np.random.default_rng(0)
    x = np.concatenate([np.eye(6)[i] + rng.normal(0, 0.05, (40, 6)) for i in range(3)])
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    labels, centres = vocabulary.exact_kmeans(x, 3, random_state=0)
    assert sorted(np.bincount(labels)) == [40, 40, 40]
    # every row at its nearest centre, every centre on the grid and the mean of its rows
    xg = vocabulary._on_grid(x)
    d = ((xg[:, None, :] - centres[None]) ** 2).sum(axis=2)
    assert np.array_equal(labels, d.argmin(axis=1))
    np.testing.assert_array_equal(centres, vocabulary._on_grid(centres))
    for c in range(3):
        np.testing.assert_allclose(centres[c], xg[labels == c].mean(axis=0),
                                   atol=vocabulary.GRID)
    # the rows in another order: the same groups
    order = rng.permutation(len(x))
    again, _ = vocabulary.exact_kmeans(x[order], 3, random_state=0)
    assert len({(a, b) for a, b in zip(labels[order], again)}) == 3
