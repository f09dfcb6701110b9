"""Counter-based random numbers: the same inputs give the same number, whatever else changed.

A draw from a generator's stream or from a running sum over items depends on every item before
it, so one item more, less or slightly changed (a mesh read back from OBJ, a line redrawn by a
pixel) changes the draws of all that follow. A hash of an item's own identity does not
(issue 11). SplitMix64's finaliser mixes the parts."""
from __future__ import annotations

import numpy as np

_GOLDEN = (0x9E3779B97F4A7C15, 0xD1B54A32D192ED03, 0xBF58476D1CE4E5B9, 0x94D049BB133111EB)


def mix64(x: np.ndarray) -> np.ndarray:
    """SplitMix64's finaliser on uint64s."""
    x = np.asarray(x, np.uint64)
    with np.errstate(over="ignore"):
        x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        return x ^ (x >> np.uint64(31))


def uniform(*parts) -> np.ndarray:
    """A uniform number in [0, 1) per element of the broadcast non-negative integer `parts`
    (at most four): each part times its own odd constant, xor-ed, then mixed."""
    x = np.uint64(0)
    with np.errstate(over="ignore"):
        for p, g in zip(parts, _GOLDEN):
            x = x ^ (np.asarray(p).astype(np.uint64) * np.uint64(g))
    return (mix64(x) >> np.uint64(11)).astype(np.float64) / float(1 << 53)

