"""Style from 2D drawings: accuracy of `identify` on whole 3D collections.

The labelled drawings are stand-in sketches (`evaluation.sketches`): meshes the 3D collection
does not contain (the same generator with another seed), drawn from views the rig does not use
(5 azimuths, 12 deg up, Line Art), thicker, jittered and broken, 320 px, PNG and inverted JPEG.
Per seed (sketch degradation and the analysis' random state): the 3D collection is analysed
unsupervised for its word dictionary, each shape's 12 views vote for the style of their nearest
drawing. Baseline: the same vote with whole-image orientation statistics (ink density and an
8-bin orientation histogram, `evaluation.baselines.line_statistics`) instead of the words;
chance = the majority style's share.

Style regions: each shape's identified regions (faces with weight > 0.5; `identify.style_regions`,
the windows matching the words characteristic of the identified style back-projected by the
analysis' localisation) scored by area against the generator's true decorative faces, beside as
many random faces per shape (`metrics.region_scores`, as bench/bench_localisation.py), over all
shapes and over the correctly identified ones. A second control, for the words rather than the
back-projection: the same back-projection with as many words per style drawn at random from the
dictionary (seeded), which says how much of the figure the characteristic words earn. Ground
truth is read only here, to score.

    python bench/bench_identify.py --collections sample-120 collection2 --seeds 3
    python bench/bench_identify.py --collections sample-24 --seeds 1 --picture docs/identify_regions.png
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sklearn.preprocessing import StandardScaler  # noqa: E402

from style_coanalysis import identify as I, metrics, pipeline  # noqa: E402
from style_coanalysis.meshes import face_areas, normalise  # noqa: E402
from style_coanalysis.params import LocalisationParams  # noqa: E402
from style_coanalysis.evaluation import baselines  # noqa: E402
from style_coanalysis.evaluation import benchmark as B  # noqa: E402
from style_coanalysis.evaluation.sketches import SKETCH_SETTINGS, write_sketches  # noqa: E402
from style_coanalysis.params import AnalysisParams  # noqa: E402

SKETCH_MESHES = 24          # meshes drawn as sketches (6 per style of 4)


def sketch_meshes(name: str):
    """Meshes of the collection's generator with another seed (not in the 3D set)."""
    if name.startswith("sample"):
        from style_coanalysis.sample import generate
    else:
        from style_coanalysis.evaluation.collection2 import generate
    meshes = list(generate(size=SKETCH_MESHES, seed=1))
    for m in meshes:
        m.name = "sketch_" + m.name
    return meshes


def orientation_vote(view_images, drawings: I.DrawingSet) -> list[str]:
    """The same vote with whole-image orientation statistics; the drawings in the same form."""
    feats = lambda imgs: baselines.line_statistics([im[None] for im in imgs])  # noqa: E731
    all_views = [im for views in view_images for im in views]
    images = drawings.images(all_views[0].shape[-1], I.ink_extent(all_views))
    scaler = StandardScaler().fit(feats(images))
    dcode = scaler.transform(feats(images))
    out = []
    for views in view_images:
        v = scaler.transform(feats(views))
        near = ((v[:, None] - dcode[None]) ** 2).sum(-1).argmin(axis=1)
        styles, counts = np.unique([drawings.styles[j] for j in near], return_counts=True)
        out.append(str(styles[np.argmax(counts)]))
    return out


def picture(coll, found, locs, path, n=3):
    """Correctly identified shapes of different styles, each in its best view: the drawing, the
    identified regions (faces with weight > 0.5, orange) and the true decorative faces."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from style_coanalysis import regions as R
    truth = coll.truth["style"]
    pick = []
    for i, r in enumerate(found):
        if r.style == truth[i] and truth[i] not in [truth[j] for j in pick]:
            pick.append(i)
    pick = pick[:n]
    fig, axes = plt.subplots(len(pick), 3, figsize=(7.5, 2.6 * len(pick)), squeeze=False)
    for row, i in enumerate(pick):
        d, m, loc = coll.drawings[i], normalise(coll.meshes[i]), locs[i]
        v = loc.best_view
        buf = R.face_buffers(m.vertices, m.faces, d.cameras[v:v + 1], d.images.shape[-1])[0][0]
        ink = d.images[v] > 0.5

        def paint(mask):
            img = np.ones(buf.shape + (3,))
            img[buf >= 0] = (0.85, 0.85, 0.85)
            img[(buf >= 0) & mask[np.maximum(buf, 0)]] = (1.0, 0.55, 0.1)
            img[ink] = 0
            return img
        axes[row, 0].imshow(1 - ink, cmap="gray")
        axes[row, 0].set_title(f"{coll.meshes[i].name}\nview {v}", fontsize=8)
        axes[row, 1].imshow(paint(loc.face_weights > 0.5))
        axes[row, 1].set_title(f"identified '{found[i].style}': regions", fontsize=8)
        axes[row, 2].imshow(paint(np.asarray(coll.meshes[i].truth["face_mask"], bool)))
        axes[row, 2].set_title("true decorative faces", fontsize=8)
        for a in axes[row]:
            a.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def run(name, seeds, jobs, log, picture_path=None) -> dict:
    from style_coanalysis.blender.batch import draw_collection
    coll = B.load_collection(name, jobs=jobs, log=log)
    meshes = sketch_meshes(name)
    sk, skipped = draw_collection(meshes, SKETCH_SETTINGS, None, jobs=jobs)
    styles = {m.name: m.truth["style"] for m in meshes}
    truth = coll.truth["style"]
    views = [d.images for d in coll.drawings]
    normal = [normalise(m) for m in coll.meshes]
    areas = [face_areas(m.vertices, m.faces) for m in normal]
    masks = [np.asarray(m.truth["face_mask"], bool) for m in coll.meshes]
    lp = LocalisationParams()
    rows = []
    for seed in seeds:
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            write_sketches(sk, [styles[d.name] for d in sk], tmp, seed=seed)
            drawings = I.load_drawings(tmp)
        params = AnalysisParams(random_state=seed)
        res = pipeline.analyse(coll.drawings, params, maps=coll.maps)
        codes = I.encode_drawings(views, drawings, res.words)
        found = I.identify(views, drawings, res.words, maps=coll.maps, codes=codes)
        pred = [r.style for r in found]
        base = orientation_vote(views, drawings)
        t1 = time.perf_counter()
        word_style, names = I.characteristic_words(codes, drawings.styles, lp.words_per_cluster)
        locs = I.style_regions(coll.drawings, normal, found, word_style, names, res.words,
                               params.patch_size, lp.match_threshold, maps=coll.maps)
        preds = [loc.face_weights > 0.5 for loc in locs]
        rng = np.random.default_rng(seed)
        random_style = np.full(len(res.words), -1)
        picked = rng.permutation(len(res.words))[:len(names) * lp.words_per_cluster]
        random_style[picked] = np.arange(len(picked)) % len(names)
        rand_locs = I.style_regions(coll.drawings, normal, found, random_style, names, res.words,
                                    params.patch_size, lp.match_threshold, maps=coll.maps)
        random_words = metrics.region_scores([loc.face_weights > 0.5 for loc in rand_locs], masks,
                                             areas, seed=seed)
        right = np.flatnonzero(np.array(pred) == truth)
        regions = metrics.region_scores(preds, masks, areas, seed=seed)
        regions_right = metrics.region_scores([preds[i] for i in right], [masks[i] for i in right],
                                              [areas[i] for i in right], seed=seed)
        t_reg = time.perf_counter() - t1
        if picture_path and seed == seeds[0]:
            picture(coll, found, locs, picture_path)
        row = {"seed": seed, "n_drawings": len(drawings.styles),
               "identify": float(np.mean(np.array(pred) == truth)),
               "orientation statistics": float(np.mean(np.array(base) == truth)),
               "chance": B.majority_share(truth), "seconds": time.perf_counter() - t0,
               "regions": {k: regions[k] for k in ("area", "random_area")}
               | {"random_words_area": random_words["area"]},
               "regions_correct_shapes": {k: regions_right[k] for k in ("area", "random_area")},
               "shapes_with_region": int(sum(p.any() for p in preds)),
               "region_seconds": t_reg}
        rows.append(row)
        log(f"  {name} seed {seed}: identify {row['identify']:.3f}, orientation statistics "
            f"{row['orientation statistics']:.3f}, chance {row['chance']:.3f} "
            f"({row['n_drawings']} drawings) [{row['seconds']:.0f} s]")
        a, ra = regions["area"], regions["random_area"]
        log(f"    regions by area: P {a['precision']:.3f} R {a['recall']:.3f} IoU {a['iou']:.3f} "
            f"(random faces {ra['precision']:.3f} / {ra['recall']:.3f} / {ra['iou']:.3f}); "
            f"{row['shapes_with_region']} of {len(preds)} shapes with a region [{t_reg:.0f} s]")
        rw = random_words["area"]
        log(f"    random words' regions by area: P {rw['precision']:.3f} R {rw['recall']:.3f} "
            f"IoU {rw['iou']:.3f}")
    return {"n": len(truth), "sketch_meshes": len(sk), "runs": rows}


def table(results) -> str:
    lines = ["| collection | N | drawings | identify | orientation statistics | chance |",
             "|---|---:|---:|---|---|---:|"]
    for name, r in results.items():
        cell = lambda k: (f"{np.mean([x[k] for x in r['runs']]):.3f} ± "  # noqa: E731
                          f"{np.std([x[k] for x in r['runs']]):.3f}")
        lines.append(f"| {name} | {r['n']} | {r['runs'][0]['n_drawings']} | {cell('identify')} | "
                     f"{cell('orientation statistics')} | {r['runs'][0]['chance']:.3f} |")
    return "\n".join(lines)


def region_table(results) -> str:
    """Area precision / recall / IoU of the identified regions and of random faces."""
    lines = ["| collection | shapes | regions | precision | recall | IoU |", "|---|---|---|---|---|---|"]
    for name, r in results.items():
        for which, label, kinds in (
                ("regions", "all", (("area", "identified"), ("random_area", "random faces"),
                                    ("random_words_area", "random words"))),
                ("regions_correct_shapes", "correctly identified",
                 (("area", "identified"), ("random_area", "random faces")))):
            for k, what in kinds:
                def cell(m):
                    v = np.array([x[which][k][m] for x in r["runs"]])
                    return f"{v.mean():.3f} ± {v.std():.3f}"
                lines.append(f"| {name} | {label} | {what} | "
                             + " | ".join(cell(m) for m in ("precision", "recall", "iou")) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--collections", nargs="+", default=["sample-120", "collection2"])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--json", default=str(ROOT / "bench" / "results" / "identify.json"))
    ap.add_argument("--picture", help="PNG of a few shapes' regions (first collection, first seed)")
    args = ap.parse_args(argv)

    def log(msg):
        print(msg, file=sys.stderr, flush=True)
    results = {}
    for name in args.collections:
        results[name] = run(name, range(args.seeds), args.jobs, log,
                            args.picture if name == args.collections[0] else None)
        print(table({name: results[name]}), flush=True)
        print(region_table({name: results[name]}), flush=True)
    print(f"\naccuracy, mean ± std over seeds {', '.join(map(str, range(args.seeds)))}")
    print(table(results))
    print("\nstyle regions by area against the true decorative faces, beside as many random faces")
    print(region_table(results))
    Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
