"""Write a labels CSV for a fraction of a collection, as a user who labels a few shapes would.

At least one shape of every style is kept so the label mode always has every class; the rest
are drawn at random (seeded). Input: the sample collection's labels.csv (name, style, category).
"""
import argparse
import csv
import random
from collections import defaultdict


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("labels")
    ap.add_argument("--fraction", type=float, default=0.2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    with open(args.labels, newline="") as fh:
        rows = [(r["name"], r["style"]) for r in csv.DictReader(fh)]
    rng = random.Random(args.seed)
    by_style = defaultdict(list)
    for name, style in rows:
        by_style[style].append(name)
    chosen = {rng.choice(sorted(names)) for names in by_style.values()}
    rest = [name for name, _ in rows if name not in chosen]
    rng.shuffle(rest)
    chosen.update(rest[: max(0, round(args.fraction * len(rows)) - len(chosen))])
    style_of = dict(rows)
    with open(args.out, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["name", "style"])
        for name in sorted(chosen):
            w.writerow([name, style_of[name]])
    print(f"{len(chosen)} of {len(rows)} shapes labelled -> {args.out}")


if __name__ == "__main__":
    main()
