"""Bring multi-view feature matrices to a common, non-negative scale.

One place for the per-view scaling that PSLF and every fusion baseline use, so that a comparison
between them is a comparison of the fusion and not of the pre-processing.

Why this matters: per-view features arrive with very different magnitudes and dimensions (UCI
'mor' spans 0..17,000 while 'fou' spans 0..0.8; our convolution responses sit in a narrow band
around 0.7 with sd 0.06). Left as they are, NMF spends its factors on the biggest view and on the
constant offset that every sample shares, and clusters follow whatever dominates that offset
(category) instead of the variation (style).
"""
from __future__ import annotations

import numpy as np

SCALINGS = ("auto", "minmax", "shift", "none")


def check_views(views, *, allow_negative=True, name="views"):
    """Validate a list of 2-D finite arrays with one row per sample; say which view is wrong."""
    if isinstance(views, np.ndarray) and views.ndim == 2:
        raise ValueError(f"{name} must be a list of 2-D arrays (one per view), got a single array")
    try:
        views = list(views)
    except TypeError:
        raise ValueError(f"{name} must be a list of 2-D arrays (one per view)") from None
    if len(views) == 0:
        raise ValueError(f"{name} is empty: give at least one view")
    out = []
    n = None
    for p, X in enumerate(views):
        try:
            X = np.asarray(X, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"view {p} is not numeric: {exc}") from None
        if X.ndim != 2:
            raise ValueError(f"view {p} must be 2-D (n_samples, n_features), got shape {X.shape}")
        if X.shape[0] == 0 or X.shape[1] == 0:
            raise ValueError(f"view {p} is empty (shape {X.shape})")
        if not np.all(np.isfinite(X)):
            bad = int(np.sum(~np.isfinite(X)))
            raise ValueError(f"view {p} contains {bad} NaN or infinite value(s)")
        if not allow_negative and X.min() < 0:
            raise ValueError(
                f"view {p} has negative values (min {X.min():.4g}); NMF needs non-negative input: "
                "use scaling='auto' or shift the view")
        if n is None:
            n = X.shape[0]
        elif X.shape[0] != n:
            raise ValueError(f"view {p} has {X.shape[0]} samples but view 0 has {n}")
        out.append(X)
    return out


def scale_view(X, method="auto"):
    """Scale one view (n_samples, n_features) to non-negative values with unit Frobenius norm.

    method:
      'auto' / 'minmax': every feature to [0, 1] (subtract its minimum, divide by its range;
          constant features become 0). Removes shared offsets and negative values, and gives the
          features of a view equal say.
      'shift': subtract each feature's minimum only (keeps the relative feature scales).
      'none': leave values as they are (must already be non-negative).
    Then, for every method but 'none', the whole view is divided by its Frobenius norm so each view
    carries the same total energy whatever its dimension or units.
    """
    if method not in SCALINGS:
        raise ValueError(f"scaling must be one of {SCALINGS}, got {method!r}")
    X = np.asarray(X, dtype=np.float64)
    if method == "none":
        return X.copy()
    Xs = X - X.min(axis=0, keepdims=True)
    if method in ("auto", "minmax"):
        rng = Xs.max(axis=0, keepdims=True)
        Xs = np.divide(Xs, rng, out=np.zeros_like(Xs), where=rng > 0)
    norm = np.linalg.norm(Xs)
    if norm > 0:
        Xs /= norm
    return Xs


def scale_views(views, method="auto"):
    """Validate and scale every view with :func:`scale_view`; returns a list of arrays."""
    views = check_views(views, allow_negative=(method != "none"))
    return [scale_view(X, method) for X in views]
