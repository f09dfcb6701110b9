"""Style regions against the true decorative faces, on the sample, collection2 and collection3.

For each collection and seed: the analysis as `make demo` runs it (20% of the shapes labelled,
at least one per style, drawn with the seed; `random_state` = seed), then every shape's style
regions (faces with style weight > 0.5, `regions.face_weights`) scored by area (the main
figure) and by face count against the generator's per-face truth, beside as many random faces
per shape (same seed). Ground truth is read only here, to pick the labels and to score.

    python bench/bench_localisation.py [--collections sample collection2 collection3] [--seeds 3]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from style_coanalysis import localisation, metrics, pipeline  # noqa: E402
from style_coanalysis.blender.batch import draw_collection  # noqa: E402
from style_coanalysis.blender.job import seed_subset  # noqa: E402
from style_coanalysis.evaluation.benchmark import pick_labels  # noqa: E402
from style_coanalysis.features import hog_images  # noqa: E402
from style_coanalysis.meshes import face_areas, normalise  # noqa: E402
from style_coanalysis.params import AnalysisParams, DrawingSettings, LocalisationParams  # noqa: E402

KEYS = ("area", "random_area", "count", "random_count")


def collection(name: str):
    if name == "sample":
        from style_coanalysis.sample import generate
        return generate(120, 0), "sample.generate(120, seed=0) (the make demo sample)"
    if name == "collection2":
        from style_coanalysis.evaluation.collection2 import generate
        return generate(size=120, seed=0), "collection2.generate(size=120, seed=0)"
    if name == "collection3":
        from style_coanalysis.evaluation.collection3 import generate
        return generate(size=60, seed=0), "collection3.generate(size=60, seed=0)"
    raise SystemExit(f"unknown collection '{name}' (sample, collection2, collection3)")


def run_collection(name: str, seeds: int, renderer: str):
    meshes, desc = collection(name)
    t = time.perf_counter()
    drawings, bad = draw_collection(meshes, DrawingSettings(renderer=renderer, n_seeds=90), None, jobs=0)
    if bad:
        raise SystemExit(f"{name}: shapes failed to draw: {bad}")
    maps = np.stack([hog_images(d.images) for d in drawings])
    normal = [normalise(m) for m in meshes]
    areas = [face_areas(m.vertices, m.faces) for m in normal]
    truth = [np.asarray(m.truth["face_mask"], bool) for m in meshes]
    styles = [str(m.truth["style"]) for m in meshes]
    print(f"\n{name}: {desc}, {len(meshes)} shapes, drawings and maps {time.perf_counter() - t:.0f} s",
          flush=True)
    lp = LocalisationParams()
    rows = []
    for seed in range(seeds):
        rng = np.random.default_rng(seed)
        labels = {meshes[i].name: styles[i] for i in pick_labels(styles, rng, fraction=0.2)}
        params = AnalysisParams(random_state=seed)
        t = time.perf_counter()
        res = pipeline.analyse([seed_subset(d, 30) for d in drawings], params, labels=labels, maps=maps)
        t_an = time.perf_counter() - t
        marked = localisation.top_words(res.word_cluster, res.word_score, lp.words_per_cluster)
        t = time.perf_counter()
        preds = []
        for i, (m, d) in enumerate(zip(normal, drawings)):
            loc = localisation.localise_shape(d, m.vertices, m.faces, res.words, marked,
                                              int(res.clusters[i]), params.patch_size,
                                              lp.match_threshold, maps=maps[i])
            preds.append(loc.face_weights > 0.5)
        t_loc = time.perf_counter() - t
        s = metrics.region_scores(preds, truth, areas, seed=seed)
        rows.append(s)
        a, ra = s["area"], s["random_area"]
        print(f"  seed {seed}: style purity {metrics.purity(res.clusters, styles):.3f}; by area P "
              f"{a['precision']:.3f} R {a['recall']:.3f} IoU {a['iou']:.3f} (random {ra['precision']:.3f} / "
              f"{ra['recall']:.3f} / {ra['iou']:.3f}); analysis {t_an:.0f} s, regions {t_loc:.0f} s "
              f"({1e3 * t_loc / len(meshes):.0f} ms a shape)", flush=True)
    print(f"  mean ± std over {seeds} seeds           precision      recall         IoU")
    for key in KEYS:
        vals = {m: np.array([r[key][m] for r in rows]) for m in ("precision", "recall", "iou")}
        print(f"  {key:<36}" + "".join(f"{v.mean():.3f} ± {v.std():.3f}   " for v in vals.values()))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--collections", nargs="+", default=["sample", "collection2"])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--renderer", default="freestyle")
    args = ap.parse_args()
    for name in args.collections:
        run_collection(name, args.seeds, args.renderer)


if __name__ == "__main__":
    main()
