"""`similar RESULT_DIR NAME [--top N] [--triplets CSV]`: style ranking and triplet scoring.

Reads only RESULT_DIR/style_space.npz (written by `analyze`), so it needs no Blender and no
re-drawing; it writes nothing. Lives in the adapter layer only because every command does.
"""
from __future__ import annotations

from ..constraints import read_triplets_csv
from ..meshes import InputError
from ..similarity import StyleSpace


def run(args) -> int:
    if args.name is None and args.triplets is None:
        raise InputError("give a shape NAME to rank the others against, or --triplets CSV")
    if args.top < 1:
        raise InputError(f"--top must be at least 1, got {args.top}")
    space = StyleSpace.load(args.result)
    if args.name is not None:
        space.index(args.name)          # an unknown name is refused before any output
    triplets = read_triplets_csv(args.triplets, space.names) if args.triplets else None
    if args.name is not None:
        i = space.index(args.name)
        print(f"closest in style to '{args.name}' (cluster {space.clusters[i]}):")
        print("rank,name,distance,cluster,label")
        for r, (name, d) in enumerate(space.ranking(args.name, args.top), start=1):
            j = space.index(name)
            print(f"{r},{name},{d:.4f},{space.clusters[j]},{space.labels[j]}")
    if triplets is not None:
        acc = space.triplet_accuracy(triplets)
        print(f"triplet accuracy {acc:.3f} ({round(acc * len(triplets))} of {len(triplets)} "
              f"triplets in {args.triplets})")
    return 0
