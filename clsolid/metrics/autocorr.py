"""Normalised autocorrelation maps and the L2 distance between them (Urs et al., TIP 2014, §VI)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._common import as_image, as_stack, check_int

DEFAULT_LAGS = 32


def max_lags(rows: int, cols: int, lags: int) -> tuple[int, int]:
    """Lags actually used for an image: ``min(lags, rows // 2)`` and ``min(lags, cols // 2)``.

    Beyond half the image fewer than half of the pixels overlap, so estimates get noisy.
    """
    return min(lags, rows // 2), min(lags, cols // 2)


def autocorrelation_stack(stack: np.ndarray, lags: int = DEFAULT_LAGS) -> np.ndarray:
    """Mean over an ``(n, rows, cols)`` stack of the slices' autocorrelation maps."""
    n, h, w = stack.shape
    ly, lx = max_lags(h, w, lags)
    x = stack - stack.mean(axis=(1, 2), keepdims=True)
    var = np.mean(x * x, axis=(1, 2))
    # Zero padding by the largest lag makes the circular FFT correlation a linear one.
    shape = (h + ly, w + lx)
    spec = np.fft.rfft2(x, s=shape)
    corr = np.fft.irfft2(spec * np.conj(spec), s=shape)
    rows = np.r_[shape[0] - ly:shape[0], 0:ly + 1]
    cols = np.r_[shape[1] - lx:shape[1], 0:lx + 1]
    corr = corr[:, rows][:, :, cols]
    # Unbiased estimate: divide each lag by its number of overlapping pixel pairs.
    overlap = np.outer(h - np.abs(np.arange(-ly, ly + 1)), w - np.abs(np.arange(-lx, lx + 1)))
    flat = var <= 1e-12 * np.maximum(1.0, stack.mean(axis=(1, 2)) ** 2)
    maps = corr / overlap / np.where(flat, 1.0, var)[:, None, None]
    # A constant slice is perfectly predictable at every lag: define its map as all ones.
    maps[flat] = 1.0
    return maps.mean(axis=0)


def autocorrelation(image2d: Any, lags: int = DEFAULT_LAGS) -> np.ndarray:
    """Normalised autocorrelation map of a 2D image.

    ``r(dy, dx) = mean_p[(I(p) - m)(I(p + d) - m)] / s**2`` with m, s the image's mean and
    standard deviation; each lag is averaged over the pixel pairs that lie inside the image
    (no wrap-around), so ``r(0, 0) = 1``. A constant image gives a map of ones.

    Parameters
    ----------
    image2d : array_like, 2D
        The image.
    lags : int
        Largest lag. It is clipped per axis to half the image size (see :func:`max_lags`).

    Returns
    -------
    numpy.ndarray
        ``(2 * ly + 1, 2 * lx + 1)`` map, centre ``[ly, lx]`` is lag (0, 0); row ``ly + dy``,
        column ``lx + dx`` holds lag (dy, dx). With the default 32 and images >= 64 pixels
        this is 65 x 65 (lags -32 .. 32 on each axis).
    """
    image = as_image(image2d, "image2d", min_side=1)
    lags = check_int(lags, "lags", 0)
    return autocorrelation_stack(image[None], lags)


def crop_map(acf: np.ndarray, ly: int, lx: int) -> np.ndarray:
    """The central ``(2 ly + 1, 2 lx + 1)`` part of an autocorrelation map."""
    cy, cx = acf.shape[0] // 2, acf.shape[1] // 2
    return acf[cy - ly:cy + ly + 1, cx - lx:cx + lx + 1]


def map_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Root-mean-square difference of two maps over the lags both of them have."""
    ly = min(a.shape[0], b.shape[0]) // 2
    lx = min(a.shape[1], b.shape[1]) // 2
    d = crop_map(a, ly, lx) - crop_map(b, ly, lx)
    return float(np.sqrt(np.mean(d * d)))


def autocorrelation_distance(exemplar: Any, slices: Any, lags: int = DEFAULT_LAGS) -> float:
    """L2 distance between the exemplar's autocorrelation and the slices' mean autocorrelation.

    Parameters
    ----------
    exemplar : array_like, 2D
        The exemplar.
    slices : array_like, (n, rows, cols) or 2D
        Slices of the volume; they may be larger or smaller than the exemplar.
    lags : int
        Largest lag; clipped per axis to half of the smaller of the exemplar and the
        slices, so both maps cover the same lags.

    Returns
    -------
    float
        Root-mean-square difference over the ``(2 ly + 1) (2 lx + 1)`` lags (the Euclidean
        norm divided by the square root of the number of lags, so that the value does not
        grow with the window). Correlations lie in [-1, 1], so does this distance's scale.
    """
    ex = as_image(exemplar, "exemplar", min_side=1)
    sl = as_stack(slices, "slices", min_side=1)
    lags = check_int(lags, "lags", 0)
    ly = min(max_lags(*ex.shape, lags)[0], max_lags(*sl.shape[1:], lags)[0])
    lx = min(max_lags(*ex.shape, lags)[1], max_lags(*sl.shape[1:], lags)[1])
    lags_common = max(ly, lx)
    a = crop_map(autocorrelation_stack(ex[None], lags_common), ly, lx)
    b = crop_map(autocorrelation_stack(sl, lags_common), ly, lx)
    return map_distance(a, b)
