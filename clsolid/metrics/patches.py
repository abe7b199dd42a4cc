"""A label-free texture distance: sliced Wasserstein distance between patch distributions.

Images are standardised with the exemplar's mean and standard deviation, reduced by block
averaging at several scales, and cut into all k x k patches (vectors of k*k values). The
patch sets are projected on a fixed set of random unit directions (drawn once from a fixed
seed, identical for every call), and the 1D Wasserstein-2 distance between the projected
samples is computed from their quantile functions. The result is the root-mean-square over
directions and quantiles, in units of the exemplar's standard deviation.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from ..errors import InputError
from ._common import as_image, as_stack, check_int

PATCH_SIZE = 5
#: Block-averaging factors (1: full resolution, 2: half, 4: quarter).
SCALES = (1, 2, 4)
N_PROJECTIONS = 64
N_QUANTILES = 128
#: Patches per side and scale; more are subsampled at random (rng) to bound the cost.
MAX_PATCHES = 8192
_PROJECTION_SEED = 20240917


def projections(dim: int, n: int = N_PROJECTIONS) -> np.ndarray:
    """``(dim, n)`` unit directions, the same for every call (fixed seed)."""
    d = np.random.default_rng(_PROJECTION_SEED).standard_normal((dim, n))
    return d / np.linalg.norm(d, axis=0, keepdims=True)


def usable_scales(shape: tuple[int, int], patch: int = PATCH_SIZE,
                  scales: tuple[int, ...] = SCALES) -> tuple[int, ...]:
    """Scales at which an image of ``shape`` still holds at least 2 patches per side."""
    return tuple(s for s in scales if min(shape) // s >= patch + 1)


def shared_scales(exemplar_shape: tuple[int, int], slice_shape: tuple[int, int], patch: int = PATCH_SIZE,
                  scales: tuple[int, ...] = SCALES) -> tuple[int, ...]:
    """The *scales* usable (:func:`usable_scales`) on the exemplar and on the slices alike."""
    both = set(usable_scales(slice_shape, patch, scales))
    return tuple(s for s in usable_scales(exemplar_shape, patch, scales) if s in both)


def _downsample(stack: np.ndarray, factor: int) -> np.ndarray:
    n, h, w = stack.shape
    h2, w2 = h // factor, w // factor
    blocks = stack[:, :h2 * factor, :w2 * factor].reshape(n, h2, factor, w2, factor)
    return blocks.mean(axis=(2, 4))


def patch_quantiles(stack: np.ndarray, scales: tuple[int, ...], rng: np.random.Generator,
                    mean: float, std: float, patch: int = PATCH_SIZE) -> list[np.ndarray]:
    """Per scale, the ``(N_QUANTILES, N_PROJECTIONS)`` quantiles of the projected patches."""
    z = (stack - mean) / (std if std > 0 else 1.0)
    proj = projections(patch * patch)
    levels = (np.arange(N_QUANTILES) + 0.5) / N_QUANTILES
    out = []
    for s in scales:
        small = _downsample(z, s) if s > 1 else z
        windows = sliding_window_view(small, (patch, patch), axis=(1, 2))
        n, a, b = windows.shape[:3]
        total = n * a * b
        pick = rng.choice(total, MAX_PATCHES, replace=False) if total > MAX_PATCHES else np.arange(total)
        i, rem = np.divmod(pick, a * b)
        j, k = np.divmod(rem, b)
        vectors = windows[i, j, k].reshape(len(pick), patch * patch)
        projected = np.sort(vectors @ proj, axis=0)
        out.append(_quantiles(projected, levels))
    return out


def _quantiles(sorted_cols: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """Linear-interpolation quantiles of each column of an already sorted array."""
    pos = levels * (len(sorted_cols) - 1)
    lo = np.floor(pos).astype(np.intp)
    hi = np.minimum(lo + 1, len(sorted_cols) - 1)
    frac = (pos - lo)[:, None]
    return sorted_cols[lo] * (1.0 - frac) + sorted_cols[hi] * frac


def quantile_distances(a: list[np.ndarray], b: list[np.ndarray]) -> list[float]:
    """Sliced Wasserstein-2 distance per scale between two patch quantile sets."""
    return [float(np.sqrt(np.mean((qa - qb) ** 2))) for qa, qb in zip(a, b)]


def patch_distance(exemplar: Any, slices: Any, *, scales: tuple[int, ...] = SCALES,
                   patch: int = PATCH_SIZE, rng: Any = 0) -> float:
    """Sliced Wasserstein distance between the k x k patches of the exemplar and of the slices.

    Parameters
    ----------
    exemplar : array_like, 2D
        The exemplar.
    slices : array_like, (n, rows, cols) or 2D
        Slices of the volume, pooled.
    scales : tuple of int
        Block-averaging factors; those too coarse for the exemplar or the slices (fewer
        than ``patch + 1`` pixels per side) are skipped.
    patch : int
        Patch side k.
    rng : int or numpy.random.Generator
        Seeds the subsampling of patches (at most 8192 per side and scale).

    Returns
    -------
    float
        Mean over the usable scales of the sliced Wasserstein-2 distance (64 fixed
        directions, 128 quantiles), in units of the exemplar's standard deviation.
    """
    ex = as_image(exemplar, "exemplar")
    sl = as_stack(slices, "slices")
    patch = check_int(patch, "patch", 1)
    use = shared_scales(ex.shape, sl.shape[1:], patch, scales)
    if not use:
        raise InputError(f"no scale in scales={scales!r} leaves {patch + 1} pixels per side of "
                         f"exemplar {ex.shape} and slices {sl.shape[1:]}")
    gen = np.random.default_rng(rng)
    mean, std = float(ex.mean()), float(ex.std())
    qa = patch_quantiles(ex[None], use, gen, mean, std, patch)
    qb = patch_quantiles(sl, use, gen, mean, std, patch)
    return float(np.mean(quantile_distances(qa, qb)))


def patch_distance_by_slice(exemplar: Any, slices: Any, *, scales: tuple[int, ...] = SCALES,
                            patch: int = PATCH_SIZE, rng: Any = 0) -> np.ndarray:
    """:func:`patch_distance` of every slice on its own, the exemplar's quantiles taken once.

    Returns
    -------
    numpy.ndarray
        ``(n,)`` float64 in slice order; NaN for every slice where no scale fits both.
    """
    ex = as_image(exemplar, "exemplar").astype(np.float64, copy=False)
    sl = as_stack(slices, "slices")
    patch = check_int(patch, "patch", 1)
    use = shared_scales(ex.shape, sl.shape[1:], patch, scales)
    if not use:
        return np.full(sl.shape[0], np.nan)
    gen = np.random.default_rng(rng)
    mean, std = float(ex.mean()), float(ex.std())
    ref = patch_quantiles(ex[None], use, gen, mean, std, patch)
    return np.array([np.mean(quantile_distances(ref, patch_quantiles(one[None], use, gen, mean, std, patch)))
                     for one in sl])
