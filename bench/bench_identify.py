"""Style from 2D drawings: accuracy of `identify` on whole 3D collections.

The labelled drawings are stand-in sketches (`evaluation.sketches`): meshes the 3D collection
does not contain (the same generator with another seed), drawn from views the rig does not use
(5 azimuths, 12 deg up, Line Art), thicker, jittered and broken, 320 px, PNG and inverted JPEG.
Per seed (sketch degradation and the analysis' random state): the 3D collection is analysed
unsupervised for its word dictionary, each shape's 12 views vote for the style of their nearest
drawing. Baseline: the same vote with whole-image orientation statistics (ink density and an
8-bin orientation histogram, `evaluation.baselines.line_statistics`) instead of the words;
chance = the majority style's share.

    python bench/bench_identify.py --collections sample-120 collection2 --seeds 3
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

from style_coanalysis import identify as I, pipeline  # noqa: E402
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


def run(name, seeds, jobs, log) -> dict:
    from style_coanalysis.blender.batch import draw_collection
    coll = B.load_collection(name, jobs=jobs, log=log)
    meshes = sketch_meshes(name)
    sk, skipped = draw_collection(meshes, SKETCH_SETTINGS, None, jobs=jobs)
    styles = {m.name: m.truth["style"] for m in meshes}
    truth = coll.truth["style"]
    views = [d.images for d in coll.drawings]
    rows = []
    for seed in seeds:
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            write_sketches(sk, [styles[d.name] for d in sk], tmp, seed=seed)
            drawings = I.load_drawings(tmp)
        res = pipeline.analyse(coll.drawings, AnalysisParams(random_state=seed), maps=coll.maps)
        pred = [r.style for r in I.identify(views, drawings, res.words)]
        base = orientation_vote(views, drawings)
        row = {"seed": seed, "n_drawings": len(drawings.styles),
               "identify": float(np.mean(np.array(pred) == truth)),
               "orientation statistics": float(np.mean(np.array(base) == truth)),
               "chance": B.majority_share(truth), "seconds": time.perf_counter() - t0}
        rows.append(row)
        log(f"  {name} seed {seed}: identify {row['identify']:.3f}, orientation statistics "
            f"{row['orientation statistics']:.3f}, chance {row['chance']:.3f} "
            f"({row['n_drawings']} drawings) [{row['seconds']:.0f} s]")
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--collections", nargs="+", default=["sample-120", "collection2"])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--json", default=str(ROOT / "bench" / "results" / "identify.json"))
    args = ap.parse_args(argv)

    def log(msg):
        print(msg, file=sys.stderr, flush=True)
    results = {}
    for name in args.collections:
        results[name] = run(name, range(args.seeds), args.jobs, log)
        print(table({name: results[name]}), flush=True)
    print(f"\naccuracy, mean ± std over seeds {', '.join(map(str, range(args.seeds)))}")
    print(table(results))
    Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
