"""The report's pieces (pure core): tables, typical shapes, patch crops, the style map, the summary."""
import numpy as np

from style_coanalysis.report import (FIRM, cluster_count_note, colour, confusion,
                                     firmness_label, firmness_note, map_coordinates,
                                     patch_image, run_notes, style_map, summary_sentence,
                                     typical_order)


def test_confusion_counts_only_shapes_with_a_reference():
    classes, table = confusion([0, 0, 1, 1, 2], ["a", None, "b", "a", None])
    assert classes == ["a", "b"]
    assert table.tolist() == [[1, 0], [1, 1], [0, 0]]


def test_typical_shapes_are_those_nearest_the_cluster_middle():
    coords = np.array([[0.0, 0], [10, 0], [1, 0], [2, 0], [50, 50]])
    # members 0, 1, 2, 3: mean x = 3.25, so 3 then 2 then 0 then 1
    assert typical_order(coords, np.array([0, 1, 2, 3])).tolist() == [3, 2, 0, 1]


def test_patch_crop_is_centred_on_the_source_pixel_and_blank_outside_the_image():
    ink = np.zeros((50, 50), np.float32)
    ink[10, 20] = 1                                  # pixel (x=20, y=10)
    img = np.asarray(patch_image(ink, 20, 10, 8, zoom=1))
    assert img.shape == (8, 8) and img[4, 4] == 0 and (img == 0).sum() == 1
    corner = np.asarray(patch_image(ink, 0, 0, 8, zoom=2))   # mostly outside: white, no error
    assert corner.shape == (16, 16) and corner.min() == 255


def test_style_map_draws_each_cluster_and_rings_given_labels():
    rng = np.random.default_rng(0)
    coords = np.concatenate([rng.normal(0, 0.1, (12, 5)), rng.normal(3, 0.1, (12, 5))])
    xy = map_coordinates(coords)
    # the two groups stay apart on the map
    assert np.linalg.norm(xy[:12].mean(0) - xy[12:].mean(0)) > 3 * xy[:12].std(0).max()
    clusters = [0] * 12 + [1] * 12
    img = np.asarray(style_map(xy, clusters, [False] * 24)).astype(int)
    ringed = np.asarray(style_map(xy, clusters, [True] + [False] * 23)).astype(int)
    for c in (0, 1):
        assert (np.abs(img - colour(c)).sum(axis=2) == 0).sum() > 50
    assert (ringed.sum(axis=2) == 0).sum() > (img.sum(axis=2) == 0).sum()   # black ring pixels
    assert map_coordinates(coords[:4]).shape == (4, 2)                        # small: no t-SNE


def test_the_automatic_number_of_clusters_names_its_runner_up():
    report = {"automatic_k": {"chosen": 3, "gaps": {"2": 0.05, "3": 0.20, "4": 0.15, "5": 0.15}}}
    note = cluster_count_note(report)
    assert "chosen from the data: 3" in note and "next likeliest is 4" in note
    assert "0.75 of 3's" in note
    assert cluster_count_note({}) == ""                                    # k was given
    assert cluster_count_note({"automatic_k": {"chosen": 2, "gaps": {"2": 0.0}}}) == ""
    report |= {"shapes": [{}] * 9, "clusters": [{"size": 3}] * 3,
               "parameters": {"labels": 0, "triplets": 0}}
    assert note in summary_sentence(report, n_skipped=0)


def test_how_firm_the_clusters_are_is_said_and_weak_ones_warn():
    assert firmness_note({}) == "" and run_notes({}) == []              # labels or triplets
    firm, weak = {"dictionary_agreement": FIRM}, {"dictionary_agreement": FIRM - 0.01}
    assert firmness_note(firm).startswith("The clusters are firm") and f"{FIRM:.2f}" in \
        firmness_note(firm)
    assert "not firmly held" in firmness_note(weak) and "labels" in firmness_note(weak)
    assert firmness_label(firm) == f"firm ({FIRM:.2f})" and firmness_label({}) == ""
    assert firmness_label(weak).startswith("not firm")
    assert [lv for lv, _ in run_notes(firm)] == ["INFO"]
    assert [lv for lv, _ in run_notes(weak)] == ["WARNING"]
    both = weak | {"automatic_k": {"chosen": 3, "gaps": {"2": 0.1, "3": 0.2}}}
    assert [lv for lv, _ in run_notes(both)] == ["INFO", "WARNING"]
    both |= {"shapes": [{}] * 9, "clusters": [{"size": 3}] * 3,
             "parameters": {"labels": 0, "triplets": 0}}
    text = summary_sentence(both, n_skipped=0)
    assert all(note in text for _, note in run_notes(both))


def test_summary_says_what_was_run_and_found():
    report = {"shapes": [{}] * 10, "clusters": [{"size": 6}, {"size": 4}],
              "parameters": {"labels": 3, "triplets": 0}, "seconds": {"total": 12.3},
              "scores": {"style": {"purity": 0.9, "majority_share": 0.5}}}
    text = summary_sentence(report, n_skipped=1)
    assert text.startswith("10 shapes, 2 style clusters, 3 labelled.")
    assert "90% pure in style (chance 50%)" in text and "1 shape was skipped" in text
    report["parameters"]["labels"] = 0
    del report["scores"]
    text = summary_sentence(report, n_skipped=0)
    assert "unsupervised" in text and "pure" not in text and "skipped" not in text
