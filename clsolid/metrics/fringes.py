"""Fringe analysis for lattice-fringe (laminar) images: length and tortuosity of level curves.

A fringe is traced as a closed level curve of the (lightly smoothed) image: the outline of
a dark or a bright fringe. Its two sides run between its two tips, the extreme points
along its principal axis; the fringe's centre line is the point-wise mean of the two sides
(each resampled by arc length). Length is the centre line's arc length, tortuosity is that
length over the tip-to-tip distance (1 for a straight fringe). Averaging the two sides cuts
the corners of thick bent fringes a little: a 4-pixel-thick half ring of radius 30 measures
89 pixels instead of 94, and tortuosity 1.41 instead of pi/2.

Edge effects: in a non-periodic image, curves cut by the border are discarded and every
kept fringe is weighted by the inverse probability of being wholly inside the window
(Miles-Lantuejoul correction, ``H W / ((H - a)(W - b))`` for a bounding box ``a x b``), so
that long fringes are not under-counted. A periodic image is wrap-padded by more than the
largest fringe measured, and each fringe is kept once: the copy whose first vertex (least
row, then least column) lies in the original tile.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from scipy import ndimage as ndi
from skimage.measure import find_contours

from ..errors import InputError
from ._common import as_image, as_stack, wasserstein_1d

#: Gaussian pre-smoothing (pixels) so that pixel noise does not break fringes into specks.
SMOOTH_SIGMA = 1.0
#: Fringes whose tip-to-tip distance is below this (pixels) are specks, not fringes.
MIN_EXTENT = 3.0
#: Fewer fringes than this on either side make a distribution too poor to compare.
MIN_COUNT = 10


class Fringes(NamedTuple):
    """Measured fringes: lengths (pixels), tortuosities (>= 1) and edge-correction weights."""

    lengths: np.ndarray
    tortuosities: np.ndarray
    weights: np.ndarray

    @classmethod
    def empty(cls) -> Fringes:
        """No fringes."""
        z = np.zeros(0)
        return cls(z, z.copy(), z.copy())

    @classmethod
    def concatenate(cls, parts: list[Fringes]) -> Fringes:
        """Pool several images' fringes."""
        if not parts:
            return cls.empty()
        return cls(*(np.concatenate([getattr(p, f) for p in parts]) for f in cls._fields))


def trace_fringes(image: Any, *, level: float | None = None, periodic: bool = False,
                  max_extent: float | None = None, smooth: float = SMOOTH_SIGMA,
                  min_extent: float = MIN_EXTENT) -> Fringes:
    """Trace the fringes of a 2D image as closed level curves and measure them.

    Parameters
    ----------
    image : array_like, 2D
        The image.
    level : float or None
        Grey level of the curves; None: the image's mean.
    periodic : bool
        Whether the image wraps around. Non-periodic: curves cut by the border are dropped
        and the rest weighted by the Miles-Lantuejoul correction (see the module doc).
    max_extent : float or None
        Fringes whose bounding box is longer than this (pixels) are not measured; it must
        be less than the image's smaller side. None: half the smaller side.
    smooth : float
        Sigma (pixels) of the Gaussian applied before tracing; 0 for none.
    min_extent : float
        Fringes whose tips are closer than this (pixels) are ignored as specks.

    Returns
    -------
    Fringes
        Lengths, tortuosities and weights of the kept fringes.
    """
    img = as_image(image, "image", min_side=4)
    side = min(img.shape)
    cap = side / 2 if max_extent is None else float(max_extent)
    if not 0 < cap < side:
        raise InputError(f"max_extent={max_extent!r} must be in (0, {side}) for an image of "
                         f"shape {img.shape}")
    if smooth > 0:
        img = ndi.gaussian_filter(img, smooth, mode="wrap" if periodic else "reflect")
    level = float(img.mean()) if level is None else float(level)
    # A kept copy starts (least row) in the original tile and spans at most ``cap``: it
    # needs wrapped rows below and columns on both sides, and 2 rows above to clear the border.
    pad = int(np.ceil(cap)) + 2 if periodic else 0
    padded = np.pad(img, ((2, pad), (pad, pad)), mode="wrap") if periodic else img
    found = []
    for curve in find_contours(padded, level):
        kept = _keep(curve, padded.shape, img.shape, (2, pad), cap, min_extent, periodic)
        if kept is not None:
            found.append(kept)
    if not found:
        return Fringes.empty()
    curves, weights = zip(*found)
    measured = [_measure(c) for c in curves]
    lengths = np.array([m[0] for m in measured])
    chords = np.array([m[1] for m in measured])
    ok = chords >= min_extent
    return Fringes(lengths[ok], lengths[ok] / chords[ok], np.asarray(weights)[ok])


def _keep(curve: np.ndarray, padded_shape: tuple[int, int], shape: tuple[int, int], origin: tuple[int, int],
          cap: float, min_extent: float, periodic: bool) -> tuple[np.ndarray, float] | None:
    """The curve and its weight if it is a whole fringe to measure, else None."""
    if len(curve) < 4 or not np.array_equal(curve[0], curve[-1]):
        return None  # open: cut by the border
    lo, hi = curve.min(axis=0), curve.max(axis=0)
    if lo.min() <= 0 or hi[0] >= padded_shape[0] - 1 or hi[1] >= padded_shape[1] - 1:
        return None  # runs along the border row or column: possibly cut
    extent = hi - lo
    # The tips are no farther apart than the bounding box's diagonal: drop specks early.
    if extent.max() > cap or extent[0] ** 2 + extent[1] ** 2 < min_extent**2:
        return None
    if periodic:
        rows = curve[:, 0]
        top = curve[rows == lo[0]]
        first = (lo[0], top[:, 1].min())
        inside = origin[0] <= first[0] < origin[0] + shape[0] and origin[1] <= first[1] < origin[1] + shape[1]
        return (curve, 1.0) if inside else None
    # The fringe's top-left corner could have fallen anywhere in a window (H - a) x (W - b).
    weight = shape[0] * shape[1] / ((shape[0] - extent[0]) * (shape[1] - extent[1]))
    return curve, float(weight)


def _measure(curve: np.ndarray) -> tuple[float, float]:
    """Centre-line length and tip-to-tip distance of a closed curve (first point == last)."""
    y, x = curve[:-1, 0], curve[:-1, 1]
    yc, xc = y - y.mean(), x - x.mean()
    # Principal axis of the 2x2 scatter matrix, in closed form (cheaper than an SVD per curve).
    angle = 0.5 * np.arctan2(2.0 * np.dot(yc, xc), np.dot(yc, yc) - np.dot(xc, xc))
    proj = yc * np.cos(angle) + xc * np.sin(angle)
    i, j = int(np.argmin(proj)), int(np.argmax(proj))
    # Walk the closed curve from tip i: arc length s, with tip j at s_j and the loop at s_total.
    ring = np.roll(curve[:-1], -i, axis=0)
    ring = np.vstack([ring, ring[:1]])
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(ring[:, 0]), np.diff(ring[:, 1])))])
    jj = (j - i) % (len(ring) - 1)
    n = max(jj + 1, len(ring) - jj, 8)
    t = np.linspace(0.0, 1.0, n)
    along_a = t * s[jj]  # side a: forwards from tip i to tip j
    along_b = s[-1] - t * (s[-1] - s[jj])  # side b: backwards from tip i (end of loop) to tip j
    mid_y = 0.5 * (np.interp(along_a, s, ring[:, 0]) + np.interp(along_b, s, ring[:, 0]))
    mid_x = 0.5 * (np.interp(along_a, s, ring[:, 1]) + np.interp(along_b, s, ring[:, 1]))
    length = float(np.sum(np.hypot(np.diff(mid_y), np.diff(mid_x))))
    chord = float(np.hypot(ring[jj, 0] - ring[0, 0], ring[jj, 1] - ring[0, 1]))
    return max(length, chord), chord


def trace_stack(stack: Any, *, level: float, periodic: bool, max_extent: float) -> Fringes:
    """Fringes of every slice of an ``(n, rows, cols)`` stack, pooled."""
    sl = as_stack(stack, "stack", min_side=4)
    return Fringes.concatenate([trace_fringes(s, level=level, periodic=periodic,
                                              max_extent=max_extent) for s in sl])


def fringe_distances(a: Fringes, b: Fringes) -> dict[str, float | None]:
    """Wasserstein-1 distances between two fringe sets' length and tortuosity distributions.

    ``fringe_length_w1`` compares lengths (pixels); ``fringe_straightness_w1`` compares
    straightness = 1 / tortuosity (dimensionless, in [0, 1]). Both use the weighted
    (edge-corrected) number distributions; None when either set has fewer than
    :data:`MIN_COUNT` fringes.
    """
    if min(len(a.lengths), len(b.lengths)) < MIN_COUNT:
        return {"fringe_length_w1": None, "fringe_straightness_w1": None}
    # Tortuosity has a long tail that a few dozen fringes sample badly; its inverse, the
    # straightness chord/length in (0, 1], carries the same ordering and is bounded.
    return {
        "fringe_length_w1": wasserstein_1d(a.lengths, b.lengths, a.weights, b.weights),
        "fringe_straightness_w1": wasserstein_1d(1.0 / a.tortuosities, 1.0 / b.tortuosities,
                                                 a.weights, b.weights),
    }


def fringe_summary(f: Fringes) -> dict[str, Any]:
    """Count and weighted mean/median length and tortuosity (None when there are none)."""
    if len(f.lengths) == 0:
        return {"count": 0, "length_mean": None, "length_median": None,
                "tortuosity_mean": None, "tortuosity_median": None}
    return {
        "count": int(len(f.lengths)),
        "length_mean": float(np.average(f.lengths, weights=f.weights)),
        "length_median": _weighted_median(f.lengths, f.weights),
        "tortuosity_mean": float(np.average(f.tortuosities, weights=f.weights)),
        "tortuosity_median": _weighted_median(f.tortuosities, f.weights),
    }


def _weighted_median(x: np.ndarray, w: np.ndarray) -> float:
    order = np.argsort(x)
    cw = np.cumsum(w[order])
    return float(x[order][np.searchsorted(cw, 0.5 * cw[-1])])
