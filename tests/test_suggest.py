"""What to label next (pure: no Blender)."""
import numpy as np
import pytest

from style_coanalysis.meshes import InputError
from style_coanalysis.similarity import StyleSpace
from style_coanalysis.suggest import suggest


def three_clusters(given_in_first=True):
    """Clusters of 12, 8 and 5 shapes around three directions; the first one labelled."""
    rng = np.random.default_rng(0)
    sizes, dirs = (12, 8, 5), np.eye(3) + 0.2
    x = np.concatenate([d + 0.05 * rng.standard_normal((s, 3)) for d, s in zip(dirs, sizes)])
    clusters = np.repeat([0, 1, 2], sizes)
    given = np.zeros(len(x), bool)
    if given_in_first:
        given[[0, 1]] = True
    conf = np.clip(1 - np.abs(rng.standard_normal(len(x))) * 0.3, 0, 1)
    return StyleSpace([f"s{i:02d}" for i in range(len(x))], x, clusters, conf, given,
                      ["a" if g else "" for g in given])


def test_unlabelled_clusters_first_by_their_medoid():
    space = three_clusters()
    picks = suggest(space, 2)
    assert [p.cluster for p in picks] == [1, 2]             # the larger unlabelled cluster first
    D = space.distance_matrix()
    for p in picks:
        members = np.flatnonzero(space.clusters == p.cluster)
        medoid = members[np.argmin(D[np.ix_(members, members)].mean(axis=1))]
        assert p.name == space.names[medoid]
        assert "has no label" in p.reason


def test_never_suggests_labelled_shapes_and_no_repeats():
    space = three_clusters()
    labelled = space.label_given.copy()
    labelled[[5, 14]] = True                                 # assigned since the analysis
    picks = suggest(space, 10, labelled=labelled)
    names = [p.name for p in picks]
    assert len(names) == 10 and len(set(names)) == 10
    assert not set(names) & {space.names[i] for i in np.flatnonzero(labelled)}
    assert all("far from every labelled shape" in p.reason for p in picks[2:])


def test_asks_for_everything_left_at_most():
    space = three_clusters(given_in_first=False)
    assert len(suggest(space, 100)) == len(space.names)
    with pytest.raises(InputError, match="at least 1"):
        suggest(space, 0)
    with pytest.raises(InputError, match="labelled already"):
        suggest(space, 1, labelled=np.ones(len(space.names), bool))
