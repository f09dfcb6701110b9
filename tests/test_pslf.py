"""PSLF (eq. 1, eq. 2) on small synthetic multi-view data with planted structure."""
import numpy as np
import pytest
from sklearn.cluster import KMeans
from sklearn.metrics import adjusted_rand_score
from sklearn.metrics.cluster import contingency_matrix
from sklearn.preprocessing import normalize

from style_coanalysis.pslf import PSLF, project_simplex
from style_coanalysis.scaling import scale_view


def purity(y, labels):
    c = contingency_matrix(y, labels)
    return c.max(axis=0).sum() / c.sum()


def planted_views(seed, n=90, P=3, n_clusters=3):
    """Views = shared cluster signal + a view-specific nuisance factor + noise, very different
    scales per view and a narrow-range view (big offset, small spread)."""
    rng = np.random.RandomState(seed)
    z = rng.randint(n_clusters, size=n)
    views = []
    for p in range(P):
        m = 15 + 10 * p
        B = rng.gamma(0.5, 1.0, (n_clusters, m))
        nuisance = rng.rand(n, 1) @ rng.rand(1, m)
        X = np.eye(n_clusters)[z] @ B + 0.5 * nuisance + 0.2 * rng.rand(n, m)
        views.append(X * 10.0 ** (2 * p - 2))
    views[1] = 0.7 + 0.05 * views[1] / views[1].max()     # narrow band around 0.7
    return views, z


def competing_views(seed, n=150, P=3, m=30):
    """A strong 'category' structure and a weaker, independent 'style' structure."""
    rng = np.random.RandomState(seed)
    cat, sty = rng.randint(3, size=n), rng.randint(3, size=n)
    views = []
    for _ in range(P):
        Bc, Bs = rng.gamma(0.5, 1, (3, m)), rng.gamma(0.5, 1, (3, m))
        views.append(3.0 * np.eye(3)[cat] @ Bc + np.eye(3)[sty] @ Bs + 0.3 * rng.rand(n, m) + 5.0)
    return views, cat, sty


def kmeans_labels(V, k):
    return KMeans(k, n_init=10, random_state=0).fit_predict(normalize(V))


def test_output_shape_and_attributes():
    views, _ = planted_views(0)
    m = PSLF(n_components=10, eta=0.2, random_state=0)
    V = m.fit_transform(views)
    Kc, Ks = 2, 8
    assert V.shape == (90, Ks * 3 + Kc)
    assert np.all(V >= 0)
    assert len(m.components_) == 3 and m.components_[2].shape == (10, views[2].shape[1])
    assert np.isclose(m.view_weights_.sum(), 1) and np.all(m.view_weights_ >= 0)
    assert m.n_iter_ >= 1 and m.reconstruction_err_ > 0
    assert m.transduction_ is None


@pytest.mark.parametrize("seed", [0, 1])
def test_planted_clusters_recovered(seed):
    views, z = planted_views(seed)
    V = PSLF(n_components=6, random_state=0).fit_transform(views)
    assert adjusted_rand_score(z, kmeans_labels(V, 3)) > 0.9


def test_objective_never_increases_unsupervised_and_supervised():
    views, cat, sty = competing_views(0)
    y = np.where(np.random.RandomState(0).rand(150) < 0.2, sty, -1)
    for yy, lam, rho in ((None, 20.0, 0.0), (y, 20.0, 0.0), (y, 0.01, 0.0), (y, 20.0, 1.0)):
        m = PSLF(n_components=8, lam=lam, tol=1e-7, max_iter=80, random_state=1,
                 unlabelled_weight=rho)
        m.fit_transform(views, yy)
        h = m.objective_history_
        assert len(h) == m.n_iter_ + 1
        assert np.all(np.diff(h) <= 1e-12 * h[0]), np.diff(h).max()
        assert h[-1] < h[0]


def test_small_lambda_makes_view_weights_selective():
    views, _ = planted_views(0)
    views.append(np.random.RandomState(5).rand(90, 20))      # a pure-noise view, worst fit
    w_smooth = PSLF(n_components=6, lam=20.0, random_state=0).fit(views).view_weights_
    w_sharp = PSLF(n_components=6, lam=0.005, random_state=0).fit(views).view_weights_
    assert w_smooth.max() - w_smooth.min() < 0.02
    assert w_sharp[3] < w_smooth[3] - 0.05


def test_deterministic_with_random_state():
    views, _ = planted_views(2)
    a = PSLF(n_components=6, random_state=7).fit_transform(views)
    b = PSLF(n_components=6, random_state=7).fit_transform(views)
    c = PSLF(n_components=6, random_state=8).fit_transform(views)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)


def test_constant_offset_does_not_change_the_clustering():
    views, z = planted_views(3)
    shifted = [v.copy() for v in views]
    shifted[0] = shifted[0] + 1000.0
    shifted[2] = shifted[2] - 3.0          # negative values too: handled by the default scaling
    a = PSLF(n_components=6, random_state=0).fit_transform(views)
    b = PSLF(n_components=6, random_state=0).fit_transform(shifted)
    np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-9)
    assert adjusted_rand_score(kmeans_labels(a, 3), kmeans_labels(b, 3)) == 1.0


def test_scaling_gives_unit_energy_nonnegative_views():
    X = np.random.RandomState(0).randn(40, 7) * 100 + 3
    Xs = scale_view(X)
    assert Xs.min() == 0 and np.isclose(np.linalg.norm(Xs), 1.0)
    np.testing.assert_allclose(scale_view(X + 50.0), Xs)


def test_project_simplex():
    p = project_simplex(np.array([0.3, -2.0, 0.9]))
    assert np.isclose(p.sum(), 1) and np.all(p >= 0) and p[1] == 0
    np.testing.assert_allclose(project_simplex(np.array([0.2, 0.3, 0.5])), [0.2, 0.3, 0.5])


@pytest.mark.parametrize("bad, msg", [
    (lambda v: [v[0], -v[1], v[2]], "view 1 has negative"),
    (lambda v: [v[0], v[1], np.where(np.eye(*v[2].shape, dtype=bool), np.nan, v[2])], "view 2"),
    (lambda v: [v[0], v[1][:-1], v[2]], "view 1 has 89 samples"),
    (lambda v: [v[0], np.zeros((90, 0)), v[2]], "view 1 is empty"),
    (lambda v: [], "empty"),
])
def test_invalid_input_is_refused_with_a_clear_message(bad, msg):
    views, _ = planted_views(0)
    views = [np.abs(v) + 1e-3 for v in views]
    with pytest.raises(ValueError, match=msg):
        PSLF(n_components=4, scaling="none").fit_transform(bad(views))


def test_nan_refused_with_default_scaling_too():
    views, _ = planted_views(0)
    views[0][3, 4] = np.inf
    with pytest.raises(ValueError, match="view 0 contains 1 NaN or infinite"):
        PSLF(n_components=4).fit_transform(views)


def test_labels_raise_style_purity_over_unsupervised():
    """Unsupervised PSLF follows the strong category; 20% style labels must recover style."""
    unsup, sup = [], []
    for seed in range(3):
        views, cat, sty = competing_views(seed)
        rng = np.random.RandomState(100 + seed)
        labelled = rng.rand(sty.size) < 0.2
        y = np.where(labelled, sty, -1)
        V0 = PSLF(n_components=8, random_state=0).fit_transform(views)
        unsup.append(purity(sty[~labelled], kmeans_labels(V0, 3)[~labelled]))
        m = PSLF(n_components=8, random_state=0, tol=1e-6)
        m.fit_transform(views, y)
        sup.append(purity(sty[~labelled], m.transduction_[~labelled]))
        # labelled shapes keep their labels; distributions are distributions
        np.testing.assert_array_equal(m.transduction_[labelled], sty[labelled])
        np.testing.assert_allclose(m.label_distribution_.sum(axis=1), 1.0)
        np.testing.assert_array_equal(m.classes_, [0, 1, 2])
    assert np.mean(unsup) < 0.5                     # the competing structure really competes
    assert np.mean(sup) > np.mean(unsup) + 0.3, (unsup, sup)


def test_labels_may_be_arbitrary_integers():
    views, cat, sty = competing_views(1, n=60)
    y = np.full(60, -1)
    y[:12] = np.array([10, 20, 30])[sty[:12]]
    m = PSLF(n_components=6, random_state=0)
    m.fit_transform(views, y)
    np.testing.assert_array_equal(m.classes_, [10, 20, 30])
    assert set(np.unique(m.transduction_)) <= {10, 20, 30}
    with pytest.raises(ValueError, match="y must have shape"):
        m.fit_transform(views, y[:-1])
