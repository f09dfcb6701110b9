"""Baseline fusions: shapes, scaling shared with PSLF, and that they carry the cluster signal."""
import numpy as np
import pytest
from sklearn.cluster import KMeans
from sklearn.metrics import adjusted_rand_score
from sklearn.preprocessing import normalize

from style_coanalysis.fusion import CCAFusion, ConcatFusion, PCAFusion
from style_coanalysis.scaling import scale_view


def views_with_clusters(seed=0, n=90, dims=(12, 20, 8), equal=False):
    rng = np.random.RandomState(seed)
    z = rng.randint(3, size=n)
    views = []
    for p, m in enumerate(dims):
        m = dims[0] if equal else m
        X = np.eye(3)[z] @ rng.gamma(0.5, 1, (3, m)) + 0.2 * rng.rand(n, m)
        views.append(X * 10.0 ** p + 7.0)
    views.append(rng.rand(n, views[0].shape[1] if equal else 15))   # a noise view
    return views, z


def ari(V, z):
    return adjusted_rand_score(z, KMeans(3, n_init=10, random_state=0).fit_predict(normalize(V)))


def test_concat_fusion_uses_the_common_scaling():
    views, z = views_with_clusters()
    F = ConcatFusion().fit_transform(views)
    assert F.shape == (90, sum(v.shape[1] for v in views))
    np.testing.assert_allclose(F[:, :12], scale_view(views[0]))
    assert ari(F, z) > 0.9


def test_pca_fusion():
    views, z = views_with_clusters()
    F = PCAFusion(n_components=5, random_state=0).fit_transform(views)
    assert F.shape == (90, 5)
    assert adjusted_rand_score(z, KMeans(3, n_init=10, random_state=0).fit_predict(F)) > 0.9


def test_cca_fusion_picks_a_pair_of_informative_views():
    views, z = views_with_clusters()
    m = CCAFusion(n_components=2, max_pca=5, random_state=0)
    F = m.fit_transform(views)
    assert F.shape == (90, 4)
    assert 3 not in m.best_pair_                       # the noise view correlates with nothing
    assert adjusted_rand_score(z, KMeans(3, n_init=10, random_state=0).fit_predict(F)) > 0.9
    with pytest.raises(ValueError, match="two views"):
        CCAFusion().fit_transform(views[:1])
