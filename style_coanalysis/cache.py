"""Per-shape on-disk cache of `ShapeDrawings`, so a second run renders nothing.

Key: sha256 of (the normalised mesh's geometry hash, `DrawingSettings.key()`, `CODE_VERSION`).
Each entry is one .npz holding the arrays plus the key and a checksum over every array, written
to a temporary file and moved into place with `os.replace` (readers never see half a file). An
entry that fails to load, has the wrong key, or whose checksum does not match is deleted and
reported as a miss: a damaged cache costs a re-render, never a wrong answer.

Beside it, in the same root, the same kind of store for what a second run would otherwise redo
(issue 15: a rerun on unchanged shapes should cost a small share of the first):
- `HogCache` (`hog/`): a shape's HOG maps, keyed by a digest of its images (all HOG reads) and
  `hog_version()`, so however the drawings arrived, stale maps cannot be served.
- `VocabularyCache` (`vocabulary/`): the default method's synthetic dictionaries of a seed
  other than the default's (those ship in the package, `vocabulary.SHIPPED`), keyed by patch
  size, word count, seed and `vocabulary_version()` (they read no shape).
- `AnalysisCache` (`analysis/`): the whole `pipeline.AnalysisResult`, keyed by every shape's name
  and drawings in input order, the analysis parameters, labels, triplets and `analysis_version()`
  (which covers the package's source), so any change of input or code re-runs the analysis.
"""
from __future__ import annotations

import functools
import hashlib
import json
import os
from pathlib import Path
from typing import Callable

import numpy as np

from . import atomic
from .drawings import ShapeDrawings
from .meshes import Mesh

# Bump when the renderers, seeding or visibility change what they produce for the same input.
CODE_VERSION = "drawings-5"
# Bump when HOG maps, the synthetic dictionaries or the analysis change in a way the source
# digests below would not see.
HOG_VERSION = "hog-1"
ANALYSIS_VERSION = "analysis-1"
VOCABULARY_VERSION = "vocabulary-2"


def default_cache_dir() -> Path:
    """`$XDG_CACHE_HOME/style_coanalysis`, else `~/.cache/style_coanalysis`."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "style_coanalysis"


def cache_key(mesh: Mesh, settings, version: str = CODE_VERSION) -> str:
    """Hex key of a (normalised) mesh's drawings under `settings` (a `DrawingSettings`)."""
    payload = json.dumps({"mesh": mesh.content_hash(), "settings": settings.key(),
                          "version": version}, sort_keys=True, default=str)
    return hashlib.sha256(payload.encode()).hexdigest()


def arrays_checksum(arrays: dict) -> str:
    """sha256 over every array's name, dtype, shape and bytes (sorted by name)."""
    h = hashlib.sha256()
    for k in sorted(arrays):
        a = np.ascontiguousarray(arrays[k])
        h.update(k.encode())
        h.update(str(a.dtype).encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


class _NpzStore:
    """A folder of `<key>.npz` entries of plain arrays: what every cache here shares."""

    def __init__(self, root: Path):
        self.root = root

    def path(self, key: str) -> Path:
        return self.root / key[:2] / f"{key}.npz"

    def load_arrays(self, key: str) -> dict | None:
        """The entry's arrays, or None if absent or not trustworthy (then it is removed)."""
        path = self.path(key)
        if not path.exists():
            return None
        try:
            with np.load(path, allow_pickle=False) as data:
                arrays = {k: data[k] for k in data.files}
            stored_key = str(arrays.pop("_key"))
            stored_sum = str(arrays.pop("_checksum"))
            if stored_key != key or stored_sum != arrays_checksum(arrays):
                raise ValueError("key or checksum mismatch")
            return arrays
        except Exception:  # truncated zip, missing member, bad checksum: never trust it
            self.discard(key)
            return None

    def discard(self, key: str) -> None:
        try:
            self.path(key).unlink()
        except OSError:
            pass

    def store_arrays(self, key: str, arrays: dict, compress: bool = True) -> Path:
        """Whole or not at all (`atomic`), with the key and a checksum beside the arrays."""
        path = self.path(key)
        path.parent.mkdir(parents=True, exist_ok=True)
        arrays = {k: np.asarray(v) for k, v in arrays.items()}
        data = atomic.npz_bytes({"_key": np.array(key), "_checksum": np.array(arrays_checksum(arrays)),
                                 **arrays}, compress)
        atomic.write_bytes(path, data, fsync=True)
        return path


class DrawingCache(_NpzStore):
    """A folder of `<key>.npz` entries."""

    def __init__(self, root: str | os.PathLike | None = None):
        super().__init__(Path(root) if root is not None else default_cache_dir())

    def load(self, key: str) -> ShapeDrawings | None:
        """The entry for `key`, or None if absent or not trustworthy (then it is removed)."""
        arrays = self.load_arrays(key)
        if arrays is None:
            return None
        try:
            return ShapeDrawings.from_arrays(arrays)
        except Exception:  # a member missing: not ours to trust
            self.discard(key)
            return None

    def store(self, key: str, drawings: ShapeDrawings) -> Path:
        return self.store_arrays(key, drawings.to_arrays())

    def get_or_compute(self, mesh: Mesh, settings, compute: Callable[[], ShapeDrawings],
                       version: str = CODE_VERSION) -> tuple[ShapeDrawings, bool]:
        """(drawings, was_cached). The cached entry takes `mesh.name`: equal geometry under
        another name shares the entry."""
        key = cache_key(mesh, settings, version)
        hit = self.load(key)
        if hit is not None:
            hit.name = mesh.name
            return hit, True
        drawings = compute()
        self.store(key, drawings)
        return drawings, False


# ---------------------------------------------------------------- what a rerun would redo
_MODULES = {"scikit-image": "skimage", "scikit-learn": "sklearn"}


def _package_versions(*names: str) -> dict:
    """Distribution versions; the module's `__version__` where there is no metadata (Blender's
    bundled numpy)."""
    from importlib import import_module
    from importlib.metadata import version
    out = {}
    for name in names:
        try:
            out[name] = version(name)
        except Exception:
            module = import_module(_MODULES.get(name, name))
            out[name] = str(getattr(module, "__version__", "?"))
    return out


def _source_digest(paths) -> str:
    h = hashlib.sha256()
    for path in sorted(paths):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


@functools.lru_cache(maxsize=None)
def hog_version() -> str:
    """HOG_VERSION, numpy's and scikit-image's versions and features.py's source: an edit to how
    maps are made never meets maps made before it."""
    here = Path(__file__).resolve().parent
    versions = _package_versions("numpy", "scikit-image")
    return f"{HOG_VERSION}+{json.dumps(versions, sort_keys=True)}+" \
        f"{_source_digest([here / 'features.py'])}"


def images_digest(images: np.ndarray) -> str:
    """sha256 of a shape's images (dtype, shape, bytes): everything its HOG maps depend on."""
    return arrays_checksum({"images": images})


def hog_key(images_sum: str, version: str | None = None) -> str:
    """Key of the HOG maps of images whose `images_digest` is `images_sum`."""
    payload = json.dumps({"images": images_sum, "version": version or hog_version()})
    return hashlib.sha256(payload.encode()).hexdigest()


class _ArrayStore(_NpzStore):
    """One float32 array (`FIELD`) per entry, in `<root>/<FOLDER>/` (root None: the user cache)."""

    FOLDER = ""
    FIELD = ""

    def __init__(self, root: str | os.PathLike | None = None):
        super().__init__((Path(root) if root is not None else default_cache_dir()) / self.FOLDER)

    def load(self, key: str) -> np.ndarray | None:
        arrays = self.load_arrays(key)
        if arrays is None or self.FIELD not in arrays or arrays[self.FIELD].dtype != np.float32:
            if arrays is not None:
                self.discard(key)
            return None
        return arrays[self.FIELD]

    def store(self, key: str, array: np.ndarray) -> Path:
        return self.store_arrays(key, {self.FIELD: np.ascontiguousarray(array, np.float32)})


class HogCache(_ArrayStore):
    """Per-shape HOG maps (`features.hog_images`) in `<root>/hog/`, one entry per shape."""

    FOLDER, FIELD = "hog", "maps"


@functools.lru_cache(maxsize=None)
def vocabulary_version() -> str:
    """VOCABULARY_VERSION, the packages and the sources a synthetic dictionary is made by
    (vocabulary.py draws the canvases, features.py their HOG maps, encoding.py the k-means): an
    edit to any of them never meets dictionaries made before it."""
    here = Path(__file__).resolve().parent
    versions = _package_versions("numpy", "scikit-image", "scikit-learn")
    sources = [here / "vocabulary.py", here / "features.py", here / "encoding.py"]
    return f"{VOCABULARY_VERSION}+{json.dumps(versions, sort_keys=True)}+" \
        f"{_source_digest(sources)}"


class VocabularyCache(_ArrayStore):
    """The synthetic dictionaries `vocabulary.words` computes (a seed whose dictionaries the
    package does not ship) in `<root>/vocabulary/`."""

    FOLDER, FIELD = "vocabulary", "words"

    @staticmethod
    def key(size: int, k: int, seed: int, version: str | None = None) -> str:
        """Key of the dictionary of `k` words of `size` px drawn with `seed`."""
        payload = f"{version or vocabulary_version()}:{size}:{k}:{seed}"
        return hashlib.sha256(payload.encode()).hexdigest()


# ---------------------------------------------------------------- the analysis
@functools.lru_cache(maxsize=None)
def analysis_version() -> str:
    """ANALYSIS_VERSION, the numeric packages' versions and a digest of every source file of the
    package: the analysis reads many modules, and a forgotten version bump must not serve a
    result the current code would not give (an edit anywhere costs one re-analysis)."""
    here = Path(__file__).resolve().parent
    versions = _package_versions("numpy", "scipy", "scikit-learn", "scikit-image")
    return f"{ANALYSIS_VERSION}+{json.dumps(versions, sort_keys=True)}+" \
        f"{_source_digest(list(here.rglob('*.py')))}"


def drawings_digest(drawings: ShapeDrawings, images_sum: str | None = None) -> str:
    """sha256 of everything the analysis reads of one shape (name, images, seeds, cameras...);
    `images_sum`: its `images_digest`, when the caller has it."""
    arrays = drawings.to_arrays()
    arrays.pop("images")
    h = hashlib.sha256()
    h.update((images_sum or images_digest(drawings.images)).encode())
    h.update(arrays_checksum(arrays).encode())
    return h.hexdigest()


def analysis_key(shape_digests: list[str], params: dict, labels: dict | None,
                 triplets: list | None, version: str | None = None) -> str:
    """Key of one analysis: the shapes' `drawings_digest` in input order (the result is per
    position and the analysis is not known to be order-free, so a reordered input misses), the
    analysis parameters, the labels, the triplets (in order) and `analysis_version()`."""
    payload = json.dumps({"shapes": list(shape_digests), "params": params,
                          "labels": sorted((labels or {}).items(), key=lambda kv: str(kv[0])),
                          "triplets": [list(t) for t in (triplets or [])],
                          "version": version or analysis_version()}, sort_keys=True, default=str)
    return hashlib.sha256(payload.encode()).hexdigest()


_RESULT_ARRAYS = ("clusters", "fused", "confidence", "label_given", "view_weights", "words",
                  "word_cluster", "word_score")
_RESULT_JSON = ("names", "n_clusters", "classes", "predicted", "view_names", "rounds", "timings",
                "k_gaps", "dictionary_agreement")
_FILTER_JSON = ("cluster", "view", "source_shape", "source_seed", "source_pixel", "score")


def _plain(x):
    """json's fallback for numpy scalars and arrays."""
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(f"cannot store {type(x).__name__} in the analysis cache")


def result_to_arrays(result) -> dict:
    """A `pipeline.AnalysisResult` as plain arrays and one JSON text (floats round-trip exactly).
    A field this does not know raises: it would otherwise be lost from every cached result."""
    from dataclasses import fields

    from .pipeline import StyleFilter
    unknown = sorted({f.name for f in fields(result)} - set(_RESULT_ARRAYS) - set(_RESULT_JSON)
                     - {"style_filters"})
    unknown += sorted({f.name for f in fields(StyleFilter)} - set(_FILTER_JSON) - {"hog"})
    if unknown:
        raise TypeError(f"AnalysisResult fields {unknown} unknown to the analysis cache")
    arrays = {f: np.asarray(getattr(result, f)) for f in _RESULT_ARRAYS
              if getattr(result, f) is not None}
    for i, sf in enumerate(result.style_filters):
        arrays[f"filter_hog_{i}"] = np.asarray(sf.hog)
    meta = {f: getattr(result, f) for f in _RESULT_JSON}
    meta["none"] = [f for f in _RESULT_ARRAYS if getattr(result, f) is None]
    meta["filters"] = [{f: getattr(sf, f) for f in _FILTER_JSON} for sf in result.style_filters]
    arrays["meta"] = np.array(json.dumps(meta, default=_plain))
    return arrays


def result_from_arrays(arrays: dict):
    """`result_to_arrays`' inverse."""
    from .pipeline import AnalysisResult, StyleFilter
    meta = json.loads(str(arrays["meta"]))
    values = {f: (None if f in meta["none"] else arrays[f]) for f in _RESULT_ARRAYS}
    values.update({f: meta[f] for f in _RESULT_JSON})
    if values["k_gaps"] is not None:                    # JSON keys are text
        values["k_gaps"] = {int(k): g for k, g in values["k_gaps"].items()}
    filters = []
    for i, sf in enumerate(meta["filters"]):
        sf["source_pixel"] = tuple(sf["source_pixel"])
        filters.append(StyleFilter(hog=arrays[f"filter_hog_{i}"], **sf))
    return AnalysisResult(style_filters=filters, **values)


class AnalysisCache(_NpzStore):
    """Whole analysis results in `<root>/analysis/`, keyed by `analysis_key`."""

    def __init__(self, root: str | os.PathLike | None = None):
        super().__init__((Path(root) if root is not None else default_cache_dir()) / "analysis")

    def load(self, key: str, names: list[str]):
        """The result for `key`, or None; an entry that does not read back, or is not about
        `names`, is removed."""
        arrays = self.load_arrays(key)
        if arrays is None:
            return None
        try:
            result = result_from_arrays(arrays)
            if list(result.names) != list(names) or len(result.clusters) != len(names):
                raise ValueError("another collection")
            return result
        except Exception:
            self.discard(key)
            return None

    def store(self, key: str, result) -> Path:
        return self.store_arrays(key, result_to_arrays(result))


# ---------------------------------------------------------------- style regions
def region_key(analysis: str, shape: str, index: int, localisation: dict) -> str:
    """Key of one shape's style regions: the `analysis_key` they come from (it covers every
    shape's drawings, the parameters and the code), the shape's drawing `cache_key` (its
    geometry: the regions are read off the mesh, which its drawings do not describe whole), its
    position in the collection, and the localisation parameters."""
    payload = json.dumps({"analysis": analysis, "shape": shape, "index": int(index),
                          "localisation": localisation}, sort_keys=True, default=str)
    return hashlib.sha256(payload.encode()).hexdigest()


class RegionCache(_NpzStore):
    """Per-shape style regions (`localisation.ShapeLocalisation`) in `<root>/regions/`, keyed by
    `region_key`: after the drawings, HOG maps and analysis, what a second run spent its time
    on (14 of 16 s on 120 shapes, 51 of 59 s on 500)."""

    _FIELDS = {"weights": np.float32, "face_weights": np.float32, "best_view": np.int64,
               "matches": np.float64, "view_scores": None}

    def __init__(self, root: str | os.PathLike | None = None):
        super().__init__((Path(root) if root is not None else default_cache_dir()) / "regions")

    def load(self, key: str):
        """The regions for `key`, or None; an entry that does not read back is removed."""
        from .localisation import ShapeLocalisation
        arrays = self.load_arrays(key)
        if arrays is None:
            return None
        try:
            for name, dtype in self._FIELDS.items():
                if dtype is not None and arrays[name].dtype != dtype:
                    raise ValueError(f"{name}: {arrays[name].dtype}")
            matches = [(int(v), float(x), float(y), float(sim))
                       for v, x, y, sim in arrays["matches"].reshape(-1, 4)]
            return ShapeLocalisation(arrays["weights"], arrays["face_weights"],
                                     int(arrays["best_view"]), matches, arrays["view_scores"])
        except Exception:
            self.discard(key)
            return None

    def store(self, key: str, loc) -> Path:
        return self.store_arrays(key, {
            "weights": np.asarray(loc.weights, np.float32),
            "face_weights": np.asarray(loc.face_weights, np.float32),
            "best_view": np.int64(loc.best_view),
            "matches": np.asarray(loc.matches, np.float64).reshape(-1, 4),
            "view_scores": np.asarray(loc.view_scores)})
