"""Write the default analysis seed's synthetic vocabularies into the package
(`style_coanalysis/vocabularies.npz`, `vocabulary.SHIPPED`), so that no run computes them.

Run it after a change to what the words are made of (the canvases, the HOG maps, the k-means, the
default parameters): `tests/test_vocabulary.py` fails until the shipped words are again what the
code makes.

    python tools/make_vocabularies.py
"""
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from style_coanalysis import vocabulary  # noqa: E402
from style_coanalysis.params import AnalysisParams  # noqa: E402
from style_coanalysis.pipeline import vocabulary_specs  # noqa: E402


def main() -> None:
    made = {}
    for size, k, seed in vocabulary_specs(AnalysisParams()):
        t = time.perf_counter()
        made[vocabulary.shipped_name(size, k, seed)] = vocabulary.compute_words(size, k, seed)
        print(f"{size} px, {k} words, seed {seed}: {time.perf_counter() - t:.1f} s", flush=True)
    np.savez_compressed(vocabulary.SHIPPED, **made)
    print(f"wrote {vocabulary.SHIPPED} ({vocabulary.SHIPPED.stat().st_size / 1024:.0f} KiB)")


if __name__ == "__main__":
    main()
