"""Local orientation from the structure tensor and coherence-weighted orientation histograms."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from scipy import ndimage as ndi

from .axes import correlation_length
from ._common import as_image, as_stack, check_int, smoothed_probabilities, symmetric_kl

#: Gaussian window of the structure tensor: sigma 1 truncated at 3 sigma = 7x7 (thesis).
TENSOR_SIGMA = 1.0
TENSOR_TRUNCATE = 3.0
#: Pixels dropped at each border of a non-periodic image (Sobel 1 + Gaussian radius 3).
BORDER = 4
#: Orientation bins over [-90, 90) degrees: 5 degrees each.
ORIENTATION_BINS = 36


class OrientationField(NamedTuple):
    """Per-pixel orientation (radians, in [-pi/2, pi/2)) and coherence (in [0, 1])."""

    theta: np.ndarray
    coherence: np.ndarray


def structure_tensor_orientation(image: Any, *, periodic: bool = False) -> OrientationField:
    """Orientation and coherence of the structure tensor of an image or stack of slices.

    Gradients are Sobel derivatives with the y axis pointing *up* (``gx = dI/dcol``,
    ``gy = -dI/drow``), so angles are counter-clockwise as the image is displayed. The
    tensor ``T = G * [[gx^2, gx gy], [gx gy, gy^2]]`` is smoothed by a Gaussian of sigma 1
    truncated to a 7x7 window. ``theta = 0.5 * atan2(2 T12, T11 - T22)`` is the dominant
    *gradient* direction; stripes and fringes run at ``theta + 90`` degrees. Coherence is
    ``(l1 - l2) / (l1 + l2)`` from the tensor's eigenvalues (0 where the image is flat).

    Parameters
    ----------
    image : array_like, 2D or (n, rows, cols)
        Image(s).
    periodic : bool
        Wrap around the borders; otherwise borders are reflected and the :data:`BORDER`
        pixels nearest each border are dropped from the result.

    Returns
    -------
    OrientationField
        ``theta`` and ``coherence`` arrays of shape ``(n, rows', cols')``.
    """
    stack = as_stack(image, "image", min_side=2 * BORDER + 1 if not periodic else 3)
    mode = "wrap" if periodic else "reflect"
    deriv, smooth = np.array([-1.0, 0.0, 1.0]), np.array([1.0, 2.0, 1.0])
    gx = ndi.correlate1d(ndi.correlate1d(stack, deriv, axis=2, mode=mode), smooth, axis=1, mode=mode)
    gy = -ndi.correlate1d(ndi.correlate1d(stack, deriv, axis=1, mode=mode), smooth, axis=2, mode=mode)
    sigma = (0.0, TENSOR_SIGMA, TENSOR_SIGMA)

    def window(a: np.ndarray) -> np.ndarray:
        return ndi.gaussian_filter(a, sigma, mode=mode, truncate=TENSOR_TRUNCATE)

    t11, t22, t12 = window(gx * gx), window(gy * gy), window(gx * gy)
    if not periodic:
        crop = (slice(None), slice(BORDER, -BORDER), slice(BORDER, -BORDER))
        t11, t22, t12 = t11[crop], t22[crop], t12[crop]
    theta = 0.5 * np.arctan2(2.0 * t12, t11 - t22)
    theta = np.where(theta >= np.pi / 2, theta - np.pi, theta)  # +90 deg is the same as -90 deg
    trace = t11 + t22
    spread = np.sqrt((t11 - t22) ** 2 + 4.0 * t12 * t12)
    scale = max(float(trace.max(initial=0.0)), 1e-300)
    safe = trace > 1e-12 * scale
    coherence = np.where(safe, spread / np.where(safe, trace, 1.0), 0.0)
    return OrientationField(theta, np.clip(coherence, 0.0, 1.0))


def orientation_histogram(field: OrientationField, bins: int = ORIENTATION_BINS) -> np.ndarray:
    """Coherence-weighted histogram (sums of coherence, not normalised) over [-90, 90) degrees."""
    bins = check_int(bins, "bins", 2)
    idx = np.floor((field.theta.ravel() + np.pi / 2) / np.pi * bins).astype(np.intp)
    return np.bincount(np.clip(idx, 0, bins - 1), weights=field.coherence.ravel(), minlength=bins)


def bin_centres_deg(bins: int = ORIENTATION_BINS) -> np.ndarray:
    """Centres in degrees of the orientation histogram's bins."""
    return -90.0 + (np.arange(bins) + 0.5) * 180.0 / bins


def dominant_orientation_deg(field: OrientationField) -> float | None:
    """Coherence-weighted mean orientation in degrees (doubled-angle mean), None if flat."""
    w = field.coherence.ravel()
    c = np.sum(w * np.cos(2 * field.theta.ravel()))
    s = np.sum(w * np.sin(2 * field.theta.ravel()))
    if np.hypot(c, s) <= 1e-12 * max(float(w.sum()), 1e-300):
        return None
    deg = float(np.degrees(0.5 * np.arctan2(s, c)))
    return deg - 180.0 if deg >= 90.0 else deg


def orientation_kl(hist_a: np.ndarray, hist_b: np.ndarray) -> float:
    """Symmetric KL between two coherence-weighted orientation histograms (pseudo-count 0.5)."""
    return symmetric_kl(smoothed_probabilities(hist_a), smoothed_probabilities(hist_b))


def orientation_distance(exemplar: Any, slices: Any, *, periodic: bool = False,
                         bins: int = ORIENTATION_BINS) -> float:
    """Symmetric KL divergence between coherence-weighted orientation histograms.

    Parameters
    ----------
    exemplar : array_like, 2D
        The exemplar (treated as non-periodic).
    slices : array_like, (n, rows, cols) or 2D
        Slices of the volume, pooled.
    periodic : bool
        Whether the slices wrap around (synthesised volumes usually do).
    bins : int
        Orientation bins over [-90, 90) degrees.

    Returns
    -------
    float
        ``sum_i (P_i - Q_i) ln(P_i / Q_i)`` where each bin holds the sum of the coherences of
        the pixels whose orientation falls in it, plus 0.5, normalised to one.
    """
    ha = orientation_histogram(structure_tensor_orientation(as_image(exemplar, "exemplar")), bins)
    hb = orientation_histogram(structure_tensor_orientation(slices, periodic=periodic), bins)
    return orientation_kl(ha, hb)


def orientation_correlation(field: OrientationField, axis: int, max_lag: int, periodic: bool = False) -> np.ndarray:
    """The orientation field's own autocorrelation along *axis* (1: rows, y; 2: columns, x)
    of a field ``(n, rows, cols)``, lags 0 to *max_lag*, pooled over the n slices.

    The field is the coherence-weighted doubled angle ``z = C exp(2 i theta)`` (orientations
    pi apart are one), less its mean over all slices, so that it measures how orientation
    *varies*: ``rho(d) = Re sum z(p) conj z(p + d) / sum |z|^2`` over the pairs inside the
    image (or, *periodic*, around it). NaN where the orientation does not vary.
    """
    z = field.coherence * np.exp(2j * field.theta)
    z = z - z.mean()
    power = float(np.mean(np.abs(z) ** 2))
    if power <= 1e-24:
        return np.full(max_lag + 1, np.nan)
    n = z.shape[axis]
    rho = [1.0]
    for lag in range(1, max_lag + 1):
        if periodic:
            a, b = z, np.roll(z, -lag, axis=axis)
        else:
            a, b = np.take(z, range(n - lag), axis=axis), np.take(z, range(lag, n), axis=axis)
        rho.append(float(np.mean((a * np.conj(b)).real)) / power)
    return np.array(rho)


def orientation_correlation_lengths(images: Any, *, periodic: bool = False) -> tuple[float, float]:
    """How far the local orientation stays alike, along y (rows) and x (columns), in pixels.

    The lag at which :func:`orientation_correlation` falls to one half
    (:func:`clsolid.metrics.axes.correlation_length`), lags up to half of each side; ``inf``
    where it stays above. Long, straight fringes give long lengths; fringes whose direction
    wanders give short ones, so the ratio of a volume's slices' lengths to the exemplar's
    says whether synthesis made the layers longer and straighter than the material's
    (Urs thesis, §6.3.3).

    Parameters
    ----------
    images : array_like, 2D or (n, rows, cols)
        An image, or slices pooled.
    periodic : bool
        Whether the images wrap around (a synthesised volume's slices do).

    Returns
    -------
    tuple of float
        ``(length along y, length along x)``.
    """
    field = structure_tensor_orientation(images, periodic=periodic)
    return tuple(correlation_length(orientation_correlation(field, axis, max(1, field.theta.shape[axis] // 2),
                                                            periodic))
                 for axis in (1, 2))
