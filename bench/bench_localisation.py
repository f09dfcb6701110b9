"""Style localisation against the sample collection's true decorative faces (issue: style patches).

Runs the analysis once on the sample (drawings from the cache), then back-projects the style
filters with several match thresholds and prints precision / recall / IoU of the faces with
style weight > 0.5, by face count and by area, beside a random choice of as many faces, for several numbers of
style words marked per cluster.

    python bench/bench_localisation.py [--size 120] [--renderer freestyle] [--words 3 10 20]
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
from style_coanalysis.meshes import face_areas, normalise  # noqa: E402
from style_coanalysis.params import AnalysisParams, DrawingSettings, LocalisationParams  # noqa: E402
from style_coanalysis.sample import generate  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=120)
    ap.add_argument("--renderer", default="freestyle")
    ap.add_argument("--words", type=int, nargs="+", default=[3, 5, 10, 20, 1000],
                    help="style words marked per cluster (LocalisationParams.words_per_cluster)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    meshes = generate(args.size, 0)
    drawings, _ = draw_collection(meshes, DrawingSettings(renderer=args.renderer, n_seeds=90), None, jobs=0)
    params = AnalysisParams(random_state=args.seed)
    t = time.perf_counter()
    res = pipeline.analyse([seed_subset(d, 30) for d in drawings], params)
    print(f"analysis {time.perf_counter() - t:.1f} s: {res.n_clusters} clusters, style purity "
          f"{metrics.purity(res.clusters, [m.truth['style'] for m in meshes]):.3f}, "
          f"{len(res.style_filters)} style filters")
    normal = [normalise(m) for m in meshes]
    areas = [face_areas(m.vertices, m.faces) for m in meshes]
    truth = [m.truth["face_mask"] for m in meshes]
    print(f"{'words':>9s} {'area P':>7s} {'area R':>7s} {'area IoU':>8s} {'rand P':>7s} {'rand IoU':>8s}"
          f" {'count P':>8s} {'count IoU':>9s} {'rand P':>7s} {'styled':>7s}")
    thr = LocalisationParams().match_threshold
    for top in args.words:
        marked = localisation.top_words(res.word_cluster, res.word_score, top)
        preds = []
        for i, (m, d) in enumerate(zip(normal, drawings)):
            loc = localisation.localise_shape(d, m.vertices, res.words, marked,
                                              int(res.clusters[i]), params.patch_size, thr)
            preds.append(localisation.face_weights(loc.weights, m.faces) > 0.5)
        s = metrics.region_scores(preds, truth, areas)
        frac = np.mean([p.mean() for p in preds])
        a, ra, c, rc = s["area"], s["random_area"], s["count"], s["random_count"]
        print(f"{top:9d} {a['precision']:7.3f} {a['recall']:7.3f} {a['iou']:8.3f} {ra['precision']:7.3f}"
              f" {ra['iou']:8.3f} {c['precision']:8.3f} {c['iou']:9.3f} {rc['precision']:7.3f} {frac:7.3f}",
              flush=True)


if __name__ == "__main__":
    main()
