"""The analysis' parameters, with the paper's defaults: the ones a person may set
(`options.PARAMETERS`) and the default method's fixed design numbers that the encoding reads
(patch sizes, words, dictionaries, style dimensions).

Three groups: what changes the drawings (and so the per-shape cache key), what changes only
the global analysis, and the style regions' back-projection. All are frozen dataclasses so they
hash and print cleanly into reports. Other numbers of the default method's design live beside
the code they shape (e.g. `graph.EDGE_LADDER`, `views.LADDER_RUNGS`,
`pipeline.SEEDED_MARGIN`), and the regions' own settings in `regions.RegionParams`.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass


@dataclass(frozen=True)
class DrawingSettings:
    """How each shape is turned into line drawings, seeds and visibility (paper section 3, 4.1)."""

    renderer: str = "freestyle"          # "freestyle" (faithful), "lineart" or "zbuffer" (fast)
    up: str = "z"                        # "z" or "y": the asset's up axis
    n_views: int = 12                    # cameras every 360/n_views degrees of azimuth
    elevation_deg: float = 30.0          # cameras look down at the centroid from this angle
    image_size: int = 200                # square drawings, pixels
    crease_angle_deg: float = 134.0      # Freestyle dihedral crease threshold (Blender's: 134.43)
    suggestive_contours: bool = False    # paper's choice; off by default (see README for why)
    n_seeds: int = 30                    # surface seeds per shape
    seed: int = 0                        # random seed for surface sampling

    def key(self) -> dict:
        """The fields that change a shape's drawings: part of the cache key."""
        return asdict(self)


@dataclass(frozen=True)
class AnalysisParams:
    """The global analysis (paper sections 4.1-4.5) with the paper's parameter values."""

    method: str = "default"              # "default" or "paper" (sections 3-4.5 as written)
    patch_size: int = 24                 # pixels, the first dictionary's style words (the result's)
    other_patch_sizes: tuple[int, ...] = (16, 32)  # pixels, the other dictionaries', in turn
    n_representatives: int = 50          # layout words (the paper: k-means centres per view)
    n_words: int = 200                   # style words of each synthetic vocabulary (all views)
    n_dictionaries: int = 5              # vocabularies of their own seeds; their graphs averaged
    structure_patch_size: int = 48       # pixels, layout patches used to find structural look-alikes
    n_style_dims: int = 10               # principal directions kept per view; spectral coordinates
    min_filters: int = 5                 # reselection keeps at least this many words per dictionary
    n_clusters: int | None = None        # None: chosen from the data (default: the largest
                                         # spectral gap; paper: self-tuning spectral clustering)
    n_components: int = 20               # K latent factors per view in PSLF
    eta: float = 0.2                     # Kc / K, the shared proportion of factors
    lam: float = 20.0                    # lambda, smoothness of the view weights
    beta: float = 0.05                   # label term weight (eq. 2)
    gamma: float = 10.0                  # l2,1 penalty on W (eq. 2)
    mu: float = 0.07                     # reselection threshold (eq. 4)
    max_rounds: int = 5                  # cluster-and-reselect rounds at most
    random_state: int = 0

    def as_dict(self) -> dict:
        return asdict(self)

    def dictionary_patch_size(self, member: int) -> int:
        """The style patch size of the `member`-th dictionary: `patch_size`, then each of
        `other_patch_sizes` in turn, round and round (24, 16, 32, 24, 16 for five)."""
        sizes = (self.patch_size, *self.other_patch_sizes)
        return int(sizes[member % len(sizes)])


@dataclass(frozen=True)
class LocalisationParams:
    """Back-projection of style patches to the surface (paper 4.5 and 5.3)."""

    seed_multiplier: int = 3             # seeds drawn per shape: n_seeds times this; only the
                                         # paper method reads seeds (the first n_seeds), the regions
                                         # match every window, no seed (left at 3: part of the
                                         # drawings' cache key)
    match_threshold: float = 0.6         # HOG similarity a window must reach to count as a style match
    words_per_cluster: int = 10          # the most discriminative style words of a cluster marked
    # (on the sample: 3 words give area precision 0.69 / recall 0.15, 10 give 0.46 / 0.45, all
    # 82 style words 0.34 / 0.58; 10 has the best IoU, see bench/bench_localisation.py)
