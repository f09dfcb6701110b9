"""The default method's synthetic vocabulary: the same words whatever the collection."""
import numpy as np
import pytest
from conftest import DAMAGES, damage_entry

from style_coanalysis import cache, vocabulary
from style_coanalysis.cache import VocabularyCache
from style_coanalysis.features import patch_blocks


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
