"""The benchmark's own pieces (no Blender, no drawings): constraint draws, subsets, summaries."""
from __future__ import annotations

import numpy as np
import pytest

from style_coanalysis.evaluation import benchmark as B


def _styles(counts):
    return np.array([s for s, n in counts.items() for _ in range(n)])


def test_two_labels_per_style():
    styles = _styles({"a": 10, "b": 7, "c": 2, "d": 1})
    for seed in range(5):
        idx = B.pick_labels(styles, np.random.default_rng(seed), per_style=2)
        got = dict(zip(*np.unique(styles[idx], return_counts=True)))
        assert got == {"a": 2, "b": 2, "c": 2, "d": 1}
        assert len(set(idx)) == len(idx)


@pytest.mark.parametrize("fraction", [0.1, 0.2])
def test_fraction_labels_cover_every_style(fraction):
    styles = _styles({"a": 40, "b": 30, "c": 5, "d": 3})
    for seed in range(10):
        idx = B.pick_labels(styles, np.random.default_rng(seed), fraction=fraction)
        assert set(styles[idx]) == set(styles)
        assert len(idx) == max(4, round(fraction * len(styles)))
        assert len(set(idx)) == len(idx)
    # too small a fraction still gives one of each style
    assert len(B.pick_labels(styles, np.random.default_rng(0), fraction=0.01)) == 4


def test_triplets_are_label_consistent_and_distinct():
    styles = _styles({"a": 9, "b": 3, "c": 1})
    t = B.pick_triplets(styles, 300, np.random.default_rng(0))
    assert len(t) == 300 and len(set(t)) == 300
    for a, b, c in t:
        assert a != b and styles[a] == styles[b] != styles[c]


def test_mode_constraints_same_for_every_method_and_seeded():
    styles = _styles({"a": 12, "b": 12, "c": 12})
    names = [f"s{i}" for i in range(len(styles))]
    k, lab, trip, idx = B.constraints_for("labels-2", styles, names, 0)
    assert k is None and trip is None and len(lab) == 6 and sorted(lab.values()) == list("aabbcc")
    assert B.constraints_for("labels-2", styles, names, 0)[1] == lab
    assert B.constraints_for("labels-2", styles, names, 1)[1] != lab
    k, lab, trip, _ = B.constraints_for("triplets-50", styles, names, 0)
    assert k == 3 and lab is None and len(trip) == 50
    assert set(_) == {names.index(x) for abc in trip for x in abc}
    assert B.constraints_for("k", styles, names, 0)[0] == 3
    assert B.constraints_for("auto", styles, names, 0)[0] is None
    with pytest.raises(ValueError):
        B.constraints_for("nonsense", styles, names, 0)


def _pool(per_cell=12, styles=("s0", "s1", "s2", "s3"), cats=("c0", "c1", "c2", "c3", "c4")):
    st, ca = [], []
    for s in styles:
        for c in cats:
            st += [s] * per_cell
            ca += [c] * per_cell
    return np.array(st), np.array(ca)


def test_stratified_subset_balanced_make_up():
    st, ca = _pool()
    idx = B.stratified_subset(st, ca, 60, seed=3)
    assert len(idx) == 60 and len(set(idx)) == 60
    cells = dict(zip(*np.unique([f"{a}/{b}" for a, b in zip(st[idx], ca[idx])], return_counts=True)))
    assert set(cells.values()) == {3} and len(cells) == 20
    assert not np.array_equal(idx, B.stratified_subset(st, ca, 60, seed=4))
    assert np.array_equal(idx, B.stratified_subset(st, ca, 60, seed=3))


def test_stratified_subset_unbalanced_three_to_one():
    st, ca = _pool()
    idx = B.stratified_subset(st, ca, 48, seed=0, keep_styles=2, style_weights=(3, 1))
    got = np.unique(st[idx], return_counts=True)[1]
    assert sorted(got.tolist()) == [12, 36]
    assert len(np.unique(ca[idx])) == 5
    # each style spread evenly over the categories
    for s in np.unique(st[idx]):
        per_cat = np.unique(ca[idx][st[idx] == s], return_counts=True)[1]
        assert per_cat.max() - per_cat.min() <= 1


def test_stratified_subset_styles_and_categories_kept():
    st, ca = _pool()
    idx = B.stratified_subset(st, ca, 48, seed=1, keep_categories=1)
    assert len(np.unique(ca[idx])) == 1 and len(np.unique(st[idx])) == 4
    assert set(np.unique(st[idx], return_counts=True)[1]) == {12}
    idx = B.stratified_subset(st, ca, 48, seed=1, keep_styles=3)
    assert len(np.unique(st[idx])) == 3 and set(np.unique(st[idx], return_counts=True)[1]) == {16}
    with pytest.raises(ValueError):
        B.stratified_subset(st, ca, 49, seed=1, keep_categories=1)   # only 48 there


def test_apportion_respects_capacity():
    got = B.apportion(10, [1, 1, 1], [1, 10, 10], np.random.default_rng(0))
    assert got.tolist()[0] == 1 and got.sum() == 10 and abs(got[1] - got[2]) <= 1


def test_summarise_mean_and_std():
    runs = [{"purity": 0.5, "nmi": 0.1}, {"purity": 0.7, "nmi": None}, {"purity": 0.9, "nmi": 0.3}]
    s = B.summarise(runs)
    assert s["purity"]["mean"] == pytest.approx(0.7)
    assert s["purity"]["std"] == pytest.approx(np.std([0.5, 0.7, 0.9]))
    assert s["purity"]["min"] == 0.5 and s["purity"]["max"] == 0.9
    assert s["nmi"]["mean"] == pytest.approx(0.2)


def _fake_collection():
    """A hand-made Collection of 12 shapes in styles a and b (random drawings, no rendering)."""
    from style_coanalysis.meshes import Mesh
    st, ca = _pool(per_cell=2, styles=("a", "b"), cats=("x", "y", "z"))
    n = len(st)
    rng = np.random.default_rng(0)

    class D:
        def __init__(self, name):
            self.name = name
            self.images = rng.random((2, 16, 16)).astype(np.float32)

    drawings = [D(f"s{i}") for i in range(n)]
    tetra = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])
    meshes = [Mesh(d.name, rng.random((4, 3)), tetra) for d in drawings]
    return B.Collection("fake", "fake", meshes, drawings, np.zeros((n, 1)),
                        {"style": st, "category": ca})


def test_loop_stability_and_table_with_a_stand_in_analysis():
    """The loop end to end on a hand-made Collection with a stand-in analysis (no rendering)."""
    coll = _fake_collection()
    truth_by_name = dict(zip(coll.names, coll.truth["style"]))
    seen = []

    def oracle(ds, params, labels, triplets, maps):
        seen.append((params.method, params.n_clusters, labels, triplets))
        if params.method == "paper":
            raise NotImplementedError("not yet")
        return np.array([0 if truth_by_name[d.name] == "a" else 1 for d in ds])

    res = B.evaluate([coll], modes=["k", "auto", "labels-2", "triplets-50"],
                     methods=["default", "paper"], seeds=2, analyse_fn=oracle,
                     render_stability=(), log=lambda m: None)
    e = res["collections"]["fake"]
    for mode in ("k", "auto", "labels-2", "triplets-50"):
        s = e["modes"][mode]["default"]["summary"]
        assert s["purity"]["mean"] == 1.0 and s["ari"]["mean"] == 1.0
        assert "NotImplementedError" in e["modes"][mode]["paper"]["n/a"]
    assert e["modes"]["labels-2"]["default"]["summary"]["purity_unlabelled"]["mean"] == 1.0
    assert e["chance"] == 0.5 and set(e["baselines"]) == {"line statistics", "global shape"}
    assert e["stability"]["min_auto"] == pytest.approx(1.0)
    assert e["stability"]["min_k"] == pytest.approx(1.0)
    assert len(e["stability"]["variants"]) == B.STABILITY_ORDERS
    # the yardstick: the oracle ignores the seed, so another seed gives the same partition
    assert e["stability"]["another_seed"]["k"]["min"] == pytest.approx(1.0)
    # k given where it should be, labels only in label modes, 2 per style
    assert ("default", 2, None, None) in seen and ("default", None, None, None) in seen
    assert any(lab is not None and len(lab) == 4 for _, _, lab, _ in seen)
    table = B.summary_table(res)
    assert "| fake | 12 | 2 | k | 1.00 ± 0.00 | n/a |" in table
    assert "order-0" in table and "| 1.00 / 1.00 | 1.00 / 1.00 |" in table


def test_stability_in_a_label_mode_gives_every_order_the_same_labels():
    """Stability in a constrained mode: the shuffled orders get the labels the collection's own
    order drew (by name), so the ARI compares the analysis, not two draws of labels."""
    coll = _fake_collection()
    given = []

    def labelled_first(ds, params, labels, triplets, maps):
        given.append((params.random_state, labels))     # the labelled shapes form cluster 0
        return np.array([0 if d.name in labels else 1 for d in ds])

    res = B.evaluate([coll], modes=["labels-2"], methods=["default"], seeds=1,
                     analyse_fn=labelled_first, render_stability=(),
                     stability_modes=["labels-2"], log=lambda m: None)
    stab = res["collections"]["fake"]["stability"]
    assert stab["modes"] == ["labels-2"] and stab["min_labels-2"] == pytest.approx(1.0)
    runs = [lab for seed, lab in given if seed == 0]
    assert len(runs) == 1 + B.STABILITY_ORDERS and all(lab == runs[0] for lab in runs)
    assert "| fake | labels-2 | 1.00 |" in B.summary_table(res)


def test_collection_names_and_prefixes():
    names = B.select_collections(["sample-1", "hu2017-60"])
    assert names == ["sample-120", "hu2017-60-0", "hu2017-60-1", "hu2017-60-2", "hu2017-60-3",
                     "hu2017-60-4"]
    assert set(B.QUICK_COLLECTIONS) <= set(B.select_collections(None))
    assert B.select_collections(["sample-24"]) == ["sample-24"]          # a name, not a prefix
    assert "sample-240" in B.select_collections(["sample-2"])
    with pytest.raises(ValueError):
        B.select_collections(["nope"])


def test_missing_collection_is_skipped_with_a_note(monkeypatch):
    def unavailable():
        raise B.CollectionUnavailable("not written yet")
    monkeypatch.setattr(B, "collection_specs", lambda: {"gone": ("a collection", unavailable)})
    notes = []
    res = B.evaluate(["gone"], modes=["k"], methods=["default"], seeds=1, log=notes.append)
    assert res["collections"] == {} and "not written yet" in res["skipped_collections"]["gone"]
    assert any("skipped gone" in n for n in notes)
    assert "skipped: not written yet" in B.summary_table(res)


def test_a_machine_without_the_voxel_data_skips_the_voxel_collections(monkeypatch, tmp_path):
    from style_coanalysis.evaluation import voxels
    monkeypatch.setattr(voxels, "resolve_root", lambda root: str(tmp_path))   # no labels.csv
    B._voxel_pool.cache_clear()
    try:
        res = B.evaluate(["hu2017-60-0"], modes=["k"], methods=["default"], seeds=1,
                         log=lambda *_: None)
    finally:
        B._voxel_pool.cache_clear()
    assert res["collections"] == {}
    assert str(tmp_path) in res["skipped_collections"]["hu2017-60-0"]


def test_merged_runs_take_each_method_from_the_latest_run_that_has_it():
    def run(method, value, extra=None):
        row = {method: {"summary": {"purity": {"mean": value}}}}
        return {"settings": {"seeds": [0]}, "collections": {
            "c": {"n_shapes": 4, "modes": {"k": row, **(extra or {})}}}}
    old = run("paper", 0.3)
    old["collections"]["c"]["modes"]["k"]["default"] = {"summary": {"purity": {"mean": 0.5}}}
    new = run("default", 0.9, {"auto": {"default": {"n/a": "failed"}}})
    merged = B.merge_results([old, new])["collections"]["c"]["modes"]
    assert merged["k"]["default"]["summary"]["purity"]["mean"] == 0.9      # replaced
    assert merged["k"]["paper"]["summary"]["purity"]["mean"] == 0.3        # kept
    assert merged["auto"]["default"] == {"n/a": "failed"}                  # new mode, as it came


def test_a_one_seed_stability_run_keeps_the_three_seed_figures_and_brings_its_stability():
    def row(value, n):
        stat = {"mean": value, "std": 0.0}
        return {"summary": {"purity": stat, "nmi": stat, "category_purity": stat},
                "runs": [{"n_clusters": 2}] * n}

    def run(value, n, commit, stability=None):
        e = {"n_shapes": 4, "n_styles": 2, "chance": 0.5,
             "baselines": {"line statistics": row(value, n), "global shape": row(value, n)},
             "modes": {"k": {"default": row(value, n)}}}
        if stability:
            e["stability"] = stability
        return {"settings": {"seeds": list(range(n))}, "code": {"commit": commit},
                "collections": {"c": e}}
    quality = run(0.8, 3, "aaa", {"modes": ["k"], "variants": {}})
    stab = run(0.5, 1, "bbb", {"modes": ["k"], "variants": {}, "min_k": 0.9})
    merged = B.merge_results([quality, stab])
    c = merged["collections"]["c"]
    assert c["modes"]["k"]["default"]["summary"]["purity"]["mean"] == 0.8
    assert c["baselines"]["line statistics"]["summary"]["purity"]["mean"] == 0.8
    assert c["stability"]["min_k"] == 0.9 and c["stability"]["commit"] == "bbb"
    assert merged["settings"]["seeds"] == [0, 1, 2]
    assert "| bbb |" in B.summary_table(merged).splitlines()[-1]
    # a later run on as many seeds does replace
    later = B.merge_results([quality, run(0.7, 3, "ccc")])["collections"]["c"]
    assert later["modes"]["k"]["default"]["summary"]["purity"]["mean"] == 0.7


def test_the_goal_report_counts_what_the_issue_asks():
    def row(purity, ari, ks=(2, 2, 2)):
        return {"summary": {"purity": {"mean": purity}, "ari": {"mean": ari}},
                "runs": [{"n_clusters": k} for k in ks]}

    def coll(n_styles, modes, line=0.5, stability=None):
        e = {"n_shapes": 40, "n_styles": n_styles, "modes": modes,
             "baselines": {"line statistics": row(line, 0.1), "global shape": row(0.4, 0.0)}}
        if stability:
            e["stability"] = stability
        return e
    res = {"collections": {
        "two": coll(2, {"k": {"default": row(0.92, 0.6), "paper": row(0.95, 0.7)},
                        "labels-2": {"default": row(0.96, 0.7)},
                        "labels-10%": {"default": row(0.9, 0.5)},
                        "auto": {"default": row(0.9, 0.5, (2, 3, 5)),
                                 "paper": row(0.95, 0.2, (9, 9, 9))}},
                    stability={"modes": ["k"], "variants": {"obj": {}}, "min_k": 0.93,
                               "commit": "abc"}),
        "four": coll(4, {"k": {"default": row(0.7, 0.3)}, "labels-2": {"default": row(0.6, 0.2)},
                         "labels-20%": {"default": row(0.75, 0.4)},
                         "auto": {"default": row(0.45, 0.2, (4, 2, 4))}}, line=0.8,
                     stability={"modes": ["k", "auto"], "variants": {"obj": {}, "blend": {}},
                                "min_k": 0.97, "min_auto": 1.0})}}
    lines = B.goal_report(res).splitlines()
    assert lines[0].startswith("Rows below the paper or a trivial baseline (mean style purity): "
                               "6 of 8")
    assert "four k (line statistics)" in lines[0] and "two auto (paper)" in lines[0]
    # the paper's 9 clusters raise its purity, not its ARI
    assert lines[1] == "  of those, below by ARI too: 1: two k"
    assert lines[2] == "2 labels per style at or above k given: 1 of 2; below: four 0.600 vs 0.700"
    assert lines[3] == ("10% and 20% labels at or above k given: 1 of 2; below: two labels-10% "
                        "0.900 vs 0.920")
    assert lines[4] == ("Automatic k right: 3 of 6 runs; at most N/4 clusters: 6 of 6; two-style "
                        "collections given 2 or 3 clusters: 2 of 3")
    assert lines[5] == "Stability two (obj; abc): below 0.95 in k 0.93"
    assert lines[6] == ("Stability four (blend, obj; this run): at or above 0.95 in every mode "
                        "measured")
    assert lines[7] == "Stability >= 0.95 on every route and mode measured: 1 of 2 collections"
    assert lines[8].endswith("met here on: two")


def test_the_turned_variant_turns_every_shape_a_quarter_about_its_up_axis(tmp_path):
    from style_coanalysis.meshes import Mesh
    v = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.5], [-1.0, -1.0, 1.0]], np.float32)
    (m,) = B.variant_meshes([Mesh("a", v, np.array([[0, 1, 2]]))], "turned", str(tmp_path))
    assert m.name == "a" and np.array_equal(m.faces, [[0, 1, 2]])
    np.testing.assert_array_equal(m.vertices, [[0, 1, 0], [-2, 0, 0.5], [1, -1, 1]])
    assert "turned" in B.RENDER_VARIANTS


def test_hu2017_pairs_are_every_two_style_make_up(monkeypatch):
    """hu2017-styles-2-0..5: each of the six pairs of the four styles once, 60 shapes, 30 per
    style spread evenly over the five categories."""
    from types import SimpleNamespace
    styles, cats = ("Children", "European", "Japanese", "Ming"), ("bed", "cabinet", "chair",
                                                                   "stool", "table")
    pool = tuple(SimpleNamespace(truth={"style": s, "category": c}) for s in styles
                 for c in cats for _ in range(8))
    monkeypatch.setattr(B, "_voxel_pool", lambda: pool)
    names = B.select_collections(["hu2017-styles-2"])
    assert names == [f"hu2017-styles-2-{i}" for i in range(6)]
    specs = B.collection_specs()
    pairs = set()
    for name in names:
        shapes = specs[name][1]()
        st = [m.truth["style"] for m in shapes]
        assert len(shapes) == 60 and len(set(st)) == 2
        assert all(st.count(s) == 30 for s in set(st))
        for s in set(st):
            per_cat = [sum(1 for m in shapes if m.truth["style"] == s and m.truth["category"] == c)
                       for c in cats]
            assert per_cat == [6] * 5
        pairs.add(frozenset(st))
    assert len(pairs) == 6


def test_the_readme_table_is_what_its_results_print():
    # bench/results/table.args lists the runs the README's table merges; the two agree
    import json
    from pathlib import Path
    root = Path(__file__).resolve().parents[1]
    files = (root / "bench/results/table.args").read_text().split()
    assert files[0] == "--table" and len(files) > 1
    merged = B.merge_results([json.loads((root / f).read_text()) for f in files[1:]])
    readme = (root / "README.md").read_text().split("\n")
    start = readme.index("### The table") + 1
    end = next(i for i in range(start, len(readme)) if readme[i].startswith("### "))
    assert "\n".join(readme[start:end]).strip() == B.summary_table(merged).strip()


def test_a_run_records_the_kernels_that_computed_it():
    """Numeric kernels differ between machines (numpy's AVX-512 sorts, OpenBLAS's kernels round
    sums otherwise): a result says which ones measured it."""
    import importlib.util
    from pathlib import Path
    path = Path(__file__).resolve().parent.parent / "bench" / "generalisation.py"
    spec = importlib.util.spec_from_file_location("generalisation_cli", path)
    cli = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(cli)
    kernels = cli.code_state()["kernels"]
    assert any(k.startswith("openblas ") for k in kernels)
    assert any(k.startswith("numpy AVX-512 ") for k in kernels)
