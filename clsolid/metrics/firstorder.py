"""First-order statistics, grey-level histograms and their symmetric Kullback-Leibler divergence."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError
from ._common import as_image, as_stack, check_int, is_integer_valued, smoothed_probabilities, symmetric_kl

#: Most histogram bins used by default (a 64x64 exemplar gives ~64 pixels per bin).
MAX_DEFAULT_BINS = 64


def first_order_stats(values: Any) -> dict[str, float | None]:
    """Mean, mean absolute deviation, standard deviation, variance, skewness and kurtosis.

    Parameters
    ----------
    values : array_like
        Any array of grey levels; all of its elements are pooled.

    Returns
    -------
    dict
        ``mean``; ``mad``: mean absolute deviation about the mean; ``std`` and ``variance``:
        population moments (ddof=0); ``skewness``: Fisher-Pearson ``m3 / m2**1.5``;
        ``kurtosis``: *excess* kurtosis ``m4 / m2**2 - 3`` (0 for a Gaussian). Skewness
        and kurtosis are None for a constant image, where they are undefined.
    """
    x = np.asarray(values, dtype=np.float64).ravel()
    if x.size == 0:
        raise InputError("values is empty; first-order statistics need at least one value")
    mean = float(x.mean())
    d = x - mean
    m2 = float(np.mean(d * d))
    # Relative threshold: a constant image has m2 at rounding level, not exactly 0.
    degenerate = m2 <= (1e-12 * max(1.0, mean * mean))
    return {
        "mean": mean,
        "mad": float(np.mean(np.abs(d))),
        "std": float(np.sqrt(m2)),
        "variance": m2,
        "skewness": None if degenerate else float(np.mean(d**3) / m2**1.5),
        "kurtosis": None if degenerate else float(np.mean(d**4) / m2**2 - 3.0),
    }


def quantise(values: Any, levels: int, lo: float, hi: float) -> np.ndarray:
    """Map grey levels to ``levels`` equal-width classes ``0 .. levels-1`` over ``[lo, hi]``.

    Values outside ``[lo, hi]`` go to the end classes. ``lo == hi`` maps everything to 0.
    """
    levels = check_int(levels, "levels", 2)
    x = np.asarray(values, dtype=np.float64)
    if hi <= lo:
        return np.zeros(x.shape, dtype=np.float64)
    q = np.floor((x - lo) / (hi - lo) * levels)
    return np.clip(q, 0, levels - 1)


def histogram_edges(values: np.ndarray, bins: int | None = None,
                    value_range: tuple[float, float] | None = None) -> np.ndarray:
    """Bin edges for grey-level histograms.

    Default range: the data's min and max. Default bins: integer-valued data get bins of a
    whole number of grey levels, centred on the levels (one level per bin when there are at
    most 64 levels); other data get 64 equal bins.
    """
    lo, hi = _range(values, value_range)
    if bins is not None:
        bins = check_int(bins, "bins", 1)
        return np.linspace(lo, hi if hi > lo else lo + 1.0, bins + 1)
    if value_range is None and is_integer_valued(values):
        n_levels = int(round(hi - lo)) + 1
        width = -(-n_levels // MAX_DEFAULT_BINS)  # ceil: every bin holds the same number of levels
        n_bins = -(-n_levels // width)
        return lo - 0.5 + width * np.arange(n_bins + 1, dtype=np.float64)
    return np.linspace(lo, hi if hi > lo else lo + 1.0, MAX_DEFAULT_BINS + 1)


def _range(values: np.ndarray, value_range: Any) -> tuple[float, float]:
    if value_range is None:
        return float(np.min(values)), float(np.max(values))
    try:
        lo, hi = (float(v) for v in value_range)
    except (TypeError, ValueError):
        raise InputError(f"value_range={value_range!r} must be a pair (low, high)") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
        raise InputError(f"value_range={value_range!r} must be finite with low < high")
    return lo, hi


def histogram_counts(values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Counts per bin; values outside the edges are counted in the end bins (clipped)."""
    x = np.clip(np.asarray(values, dtype=np.float64).ravel(), edges[0], edges[-1])
    return np.histogram(x, bins=edges)[0].astype(np.float64)


def histogram_kl(counts_a: np.ndarray, counts_b: np.ndarray) -> float:
    """Symmetric KL (Urs thesis, eq. 6.1) between two count vectors, with the stated pseudo-count."""
    return symmetric_kl(smoothed_probabilities(counts_a), smoothed_probabilities(counts_b))


def histogram_distance(exemplar: Any, slices: Any, bins: int | None = None,
                       value_range: tuple[float, float] | None = None) -> float:
    """Symmetric Kullback-Leibler divergence between grey-level histograms (Urs thesis, eq. 6.1).

    ``D = sum_i (P_i - Q_i) ln(P_i / Q_i) = KL(P||Q) + KL(Q||P)``, P from the exemplar and Q
    from all slices pooled.

    Parameters
    ----------
    exemplar : array_like, 2D
        The exemplar image.
    slices : array_like, (n, rows, cols) or 2D
        Slices of the volume (any size).
    bins : int or None
        Number of equal bins over ``value_range``; None chooses as in :func:`histogram_edges`
        (one bin per grey level for integer data with <= 64 levels, else <= 64 bins).
    value_range : (low, high) or None
        Histogram range; None: the min and max of exemplar and slices together. Values
        outside it are counted in the end bins.

    Returns
    -------
    float
        The divergence in nats. Empty bins are smoothed by adding 0.5 to every bin's count
        (Jeffreys prior) before normalising, so D is finite; two identical histograms give 0.
    """
    ex = as_image(exemplar, "exemplar", min_side=1)
    sl = as_stack(slices, "slices", min_side=1)
    both = np.concatenate([ex.ravel(), sl.ravel()])
    edges = histogram_edges(both, bins, value_range)
    return histogram_kl(histogram_counts(ex, edges), histogram_counts(sl, edges))
