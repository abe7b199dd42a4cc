"""Colour exemplars: their label set (a palette) and the space their distances are taken in.

A colour exemplar is treated jointly, as Urs et al. (TIP 2014, §V) do: each pixel is one
three-value feature, never one channel at a time. The engine works on labels, so a colour
image becomes a palette of at most ``levels`` colours and an image of palette indices; the
Parzen distances between two labels are then squared distances between their colours in
CIELAB, where equal distances look about equally different (docs/design.md#colour).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .errors import InputError

#: Channels of a colour exemplar (RGB). RGBA is refused: a texture's alpha is not its material.
CHANNELS = 3
#: Lloyd iterations of the palette's k-means at most; it stops earlier once no pixel moves.
KMEANS_ITERATIONS = 50
#: Most pixels the palette's k-means is fitted on (a fixed sample of a larger exemplar); every
#: pixel then takes its nearest palette colour.
KMEANS_SAMPLE = 1 << 17


def as_colour(image: np.ndarray, channel_axis: int | None) -> np.ndarray:
    """*image* with its channels last, ``(H, W, 3)``; a grey image given as three equal
    channels comes back ``(H, W)``. Only the shape is checked here (values: the caller).

    Raises
    ------
    InputError
        *channel_axis* out of range, or a channel count other than 3 (RGBA named).
    """
    if channel_axis is None:
        return image
    if isinstance(channel_axis, bool) or not isinstance(channel_axis, (int, np.integer)):
        raise InputError(f"channel_axis={channel_axis!r} must be an integer axis (e.g. -1) or None")
    if image.ndim != 3 or not -3 <= int(channel_axis) < 3:
        raise InputError(f"channel_axis={channel_axis!r} needs a 2D image with a channel axis, an array of 3 "
                         f"dimensions; got shape {image.shape}")
    image = np.moveaxis(image, int(channel_axis), -1)
    check_channels(image.shape)
    return grey_if_equal(image)


def check_channels(shape: tuple[int, ...]) -> None:
    """Refuse a channel count other than RGB's three, saying what to do."""
    n = shape[-1]
    if n == 4:
        raise InputError(f"exemplar has shape {shape}, an RGBA image; colour exemplars are RGB: drop the alpha "
                         "channel (image[..., :3])")
    if n != CHANNELS:
        raise InputError(f"exemplar has shape {shape}: {n} channels; a colour exemplar has 3 (RGB), a grey one none")


def grey_if_equal(image: np.ndarray) -> np.ndarray:
    """A ``(H, W, 3)`` image whose three channels are equal is grey: its first channel."""
    if image.ndim == 3 and np.array_equal(image[..., 0], image[..., 1]) and np.array_equal(image[..., 0],
                                                                                          image[..., 2]):
        return np.ascontiguousarray(image[..., 0])
    return image


def full_scale(dtype: Any, top: float) -> float:
    """The value that stands for a full channel: an integer type's maximum, a float's *top*
    (:func:`float_top`)."""
    return float(np.iinfo(dtype).max) if np.dtype(dtype).kind in "iu" else top


def _unit_rgb(values: np.ndarray, dtype: np.dtype, top: float) -> np.ndarray:
    """RGB values scaled to 0..1 (:func:`full_scale`)."""
    return np.clip(np.asarray(values, np.float64) / full_scale(dtype, top), 0.0, 1.0)


def float_top(image: np.ndarray) -> float:
    """What 1.0 stands for in a float RGB image: 1 where it lies in 0..1, else its maximum."""
    if image.dtype.kind != "f":
        return 1.0
    m = float(np.max(image)) if image.size else 1.0
    return 1.0 if m <= 1.0 else m


def lab(values: np.ndarray, dtype: Any, top: float = 1.0) -> np.ndarray:
    """CIELAB coordinates ``(..., 3)``, float64, of RGB *values* of *dtype* (sRGB, D65;
    floats read as 0..*top*)."""
    from skimage.color import rgb2lab

    rgb = _unit_rgb(values, np.dtype(dtype), top)
    return rgb2lab(rgb.reshape(-1, 1, 3)).reshape(rgb.shape)


def kmeans(points: np.ndarray, k: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Lloyd's k-means of *points* ``(n, d)`` into at most *k* clusters, started by k-means++
    with a fixed *seed* (the palette is part of the exemplar, not of the run's randomness).

    Returns
    -------
    centres : numpy.ndarray
        ``(m, d)``, ``m <= k`` (a cluster left empty is dropped).
    labels : numpy.ndarray
        ``(n,)`` int32, the nearest centre of each point.
    """
    rng = np.random.default_rng(seed)
    pts = np.asarray(points, np.float64)
    centres = [pts[rng.integers(pts.shape[0])]]
    closest = np.sum((pts - centres[0]) ** 2, axis=1)  # each point's squared distance to the centres so far
    for _ in range(1, k):
        total = closest.sum()
        if total <= 0:
            break
        pick = pts[rng.choice(pts.shape[0], p=closest / total)]
        centres.append(pick)
        closest = np.minimum(closest, np.sum((pts - pick) ** 2, axis=1))
    c = np.array(centres)
    labels = np.full(pts.shape[0], -1)
    for _ in range(KMEANS_ITERATIONS):
        new = nearest(pts, c)
        if np.array_equal(new, labels):
            break
        c, labels = cluster_means(pts, new, c.shape[0])
    return c, labels.astype(np.int32)


def cluster_means(points: np.ndarray, labels: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The mean of *points* ``(n, d)`` in each of the *k* clusters *labels* names that holds
    any, and the labels renumbered past the empty ones."""
    counts = np.bincount(labels, minlength=k)
    kept = counts > 0
    sums = np.stack([np.bincount(labels, weights=points[:, j], minlength=k) for j in range(points.shape[1])], 1)
    return sums[kept] / counts[kept, None], np.cumsum(kept)[labels] - 1


def nearest(points: np.ndarray, centres: np.ndarray, chunk: int = 1 << 16) -> np.ndarray:
    """The index of the nearest of *centres* ``(k, d)`` to each of *points* ``(n, d)`` (the
    lower on a tie), a chunk of points at a time so that no ``(n, k)`` table is made."""
    out = np.empty(points.shape[0], np.intp)
    for lo in range(0, points.shape[0], chunk):
        part = points[lo: lo + chunk]
        d = np.sum(part**2, axis=1)[:, None] - 2.0 * part @ centres.T + np.sum(centres**2, axis=1)[None, :]
        out[lo: lo + chunk] = np.argmin(d, axis=1)
    return out


def palette(image: np.ndarray, levels: int) -> tuple[np.ndarray, np.ndarray, bool]:
    """The label set of a colour *image* ``(..., 3)``.

    Returns
    -------
    labels : numpy.ndarray
        int32 palette index of each pixel, ``image.shape[:-1]``.
    values : numpy.ndarray
        ``(L, 3)`` the palette, in the image's dtype, ordered by CIELAB lightness.
    exact : bool
        True when the palette is the image's own colours (at most *levels* of them); else
        each entry is the mean colour of one k-means cluster in CIELAB.
    """
    pixels = image.reshape(-1, CHANNELS)
    distinct, index = np.unique(pixels, axis=0, return_inverse=True)
    index = index.ravel()
    top = float_top(image)
    if distinct.shape[0] <= levels:
        values, labels, exact = distinct, index, True
    else:  # k-means on the pixels (a fixed sample of a large exemplar), then each its nearest
        feats = lab(pixels, image.dtype, top)
        fit = feats
        if feats.shape[0] > KMEANS_SAMPLE:
            fit = feats[np.random.default_rng(0).choice(feats.shape[0], KMEANS_SAMPLE, replace=False)]
        centres, _ = kmeans(fit, levels)
        # each colour the mean of the pixels nearest its centre (a centre none is nearest to goes)
        means, labels = cluster_means(pixels.astype(np.float64), nearest(feats, centres), centres.shape[0])
        if image.dtype.kind in "iu":
            info = np.iinfo(image.dtype)
            means = np.clip(np.rint(means), info.min, info.max)
        values, exact = means.astype(image.dtype), False
    order = np.argsort(lab(values, image.dtype, top)[:, 0], kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return rank[labels].reshape(image.shape[:-1]).astype(np.int32), values[order], exact


def luminance(values: np.ndarray) -> np.ndarray:
    """Rec. 709 luma ``0.2126 R + 0.7152 G + 0.0722 B`` of ``(..., 3)`` values, float64 in
    their own units: the structural metrics' grey image of a colour volume."""
    return np.asarray(values, np.float64) @ np.array([0.2126, 0.7152, 0.0722])
