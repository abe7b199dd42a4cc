"""Two failure modes of solid textures that slice statistics miss: mirroring and copying.

* :func:`mirror_correlation`: with two views sharing the y axis, a volume can satisfy both
  by being (nearly) symmetric under x <-> z, which no real material is. It is measured as
  the Pearson correlation between the volume and its transposition, once the mean of
  every plane of the kept axis is removed (layers stacked along the kept axis are rightly
  symmetric and must not count).
* :func:`max_copy_fraction`: a slice may be a verbatim copy of the exemplar (the ``+in``
  slices start as one). It is measured as the largest fraction of a slice's pixels equal
  to the exemplar's, over every shift of the exemplar.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations
from typing import Any

import numpy as np

from ..errors import InputError
from ._common import VIEWS, as_volume, check_views, view_slices

#: Every pair of axes of a (Z, Y, X) volume.
AXIS_PAIRS = tuple(combinations(range(3), 2))


def _check_axes(axes: Any) -> tuple[int, int]:
    try:
        a, b = (int(v) for v in axes)
    except (TypeError, ValueError):
        raise InputError(f"axes={axes!r} must be two distinct axes among 0, 1, 2") from None
    if {a, b} - {0, 1, 2} or a == b:
        raise InputError(f"axes={axes!r} must be two distinct axes among 0, 1, 2")
    return a, b


def mirror_correlation(volume: Any, axes: tuple[int, int] = (0, 2)) -> float:
    """Pearson correlation between a volume and its mirror that swaps two axes.

    Parameters
    ----------
    volume : array_like, (Z, Y, X)
        The volume; it must be as long along both ``axes`` (e.g. ``Z == X`` for (0, 2)).
    axes : tuple of two ints, default (0, 2)
        The axes swapped: (0, 2) is z <-> x, the mirror two views sharing y invite.

    Returns
    -------
    float
        ``r = sum(a * a') / sum(a * a)`` in float64, where ``a`` is the volume minus the
        mean of each of its planes perpendicular to the kept axis (for (0, 2): each
        y-plane ``volume[:, y, :]``) and ``a'`` is ``a`` with the two axes swapped. This
        is Pearson's r, as ``a`` and ``a'`` hold the same values, with zero mean. 1: the
        volume is symmetric under the swap (up to layers along the kept axis); about
        ``1 / N`` (N the length of the swapped axes) for unrelated content, because the
        voxels of the diagonal plane (z = x for (0, 2)) are their own mirror; NaN when
        every plane is constant (nothing left to correlate).

    Raises
    ------
    InputError
        Not a 3D real array, bad ``axes``, or the two axes of different lengths.
    """
    vol = as_volume(volume, "volume", min_side=1)
    a, b = _check_axes(axes)
    if vol.shape[a] != vol.shape[b]:
        raise InputError(f"volume has shape {vol.shape}: axes {a} and {b} have different lengths "
                         f"({vol.shape[a]} and {vol.shape[b]}); the mirror that swaps them needs a "
                         "volume as long along both")
    x = vol.astype(np.float64)
    x = x - x.mean(axis=(a, b), keepdims=True)  # the mean of every plane of the kept axis
    energy = float(np.sum(x * x))
    # Constant planes leave only rounding residue of the means: treat that as nothing.
    if energy <= x.size * (1e-12 * max(1.0, float(np.abs(vol).max()))) ** 2:
        return float("nan")
    return float(np.sum(x * np.swapaxes(x, a, b)) / energy)


def mirror_correlations(volume: Any, pairs: Any = AXIS_PAIRS) -> dict[str, float]:
    """:func:`mirror_correlation` for several pairs of axes (by default all three).

    Returns
    -------
    dict
        ``{"zx": r, ...}``: the swapped axes' names (in ``"zyx"``) and each correlation.
    """
    return {"zyx"[a] + "zyx"[b]: mirror_correlation(volume, (a, b))
            for a, b in (_check_axes(p) for p in pairs)}


def mirror_chance(exemplar: Any, side: int) -> float:
    """The x <-> z mirror correlation an isotropic material like the exemplar would give.

    A real material is not its own mirror image, but its mirror correlation is not 0
    either: a voxel near the diagonal plane z = x lies close to its own mirror voxel, and
    close voxels are correlated. This is the expected :func:`mirror_correlation` of a
    ``side``-cube (toroidal) of a material whose correlation in the (z, x) planes is
    isotropic and equal to the exemplar's, the level a volume cannot be expected to beat.

    Parameters
    ----------
    exemplar : array_like, (H, W)
        The exemplar (any real values), taken as periodic.
    side : int
        The length of the volume along the swapped axes.

    Returns
    -------
    float
        ``sum_d (side - |d|) * rho(d) / side**2`` over ``d = x - z`` in
        ``(-side, side)``, where ``rho(d)`` is the exemplar's periodic autocorrelation at
        the diagonal lags ``(d', d')`` and ``(d', -d')`` (averaged; both are at distance
        ``sqrt(2) * d'``, which is how far apart the voxel and its mirror are) and ``d'``
        the toroidal length ``min(|d|, side - |d|)``. About ``1 / side`` for white noise;
        0.1-0.2 for textures whose features span a tenth of the block.

    Raises
    ------
    InputError
        Not a 2D real image, constant, or ``side`` below 1.
    """
    side = int(side)
    if side < 1:
        raise InputError(f"side={side} must be at least 1")
    acf = periodic_autocorrelation(exemplar)
    d = np.arange(-(side - 1), side)
    lag = np.minimum(np.abs(d), side - np.abs(d))
    h, w = acf.shape
    rho = 0.5 * (acf[lag % h, lag % w] + acf[lag % h, -lag % w])
    return float(np.sum((side - np.abs(d)) * rho) / side**2)


def periodic_autocorrelation(exemplar: Any) -> np.ndarray:
    """The exemplar's autocorrelation with the image taken as periodic.

    Returns an array of the exemplar's shape: ``[dy % H, dx % W]`` holds the correlation at
    the toroidal lag (dy, dx), 1 at (0, 0). Raises :class:`InputError` for anything but a
    finite 2D image, or a constant one (it has no correlation).
    """
    ex = np.asarray(exemplar, dtype=np.float64)
    if ex.ndim != 2 or ex.size == 0 or not np.all(np.isfinite(ex)):
        raise InputError(f"exemplar must be a finite 2D image, got shape {ex.shape}")
    power = np.abs(np.fft.fft2(ex - ex.mean())) ** 2
    if power.sum() <= 0:
        raise InputError("exemplar is constant: it has no correlation to compare with")
    acf = np.real(np.fft.ifft2(power))
    return acf / acf[0, 0]


@dataclass(frozen=True)
class CopyMatch:
    """The slice of a volume most like a shifted exemplar (see :func:`max_copy_fraction`).

    Attributes
    ----------
    fraction : float
        Fraction of that slice's pixels equal to the shifted exemplar's.
    view : str
        Its view (``"front"``, ``"right"`` or ``"top"``).
    index : int
        Its depth along the view's axis (z, x or y).
    shift : tuple of int
        ``(dy, dx)``: slice pixel ``(r, c)`` is compared with exemplar pixel
        ``((r + dy) mod H, (c + dx) mod W)``.
    per_view : dict
        For every view measured, the best fraction of each of its slices (one array).
    """

    fraction: float
    view: str
    index: int
    shift: tuple[int, int]
    per_view: dict[str, np.ndarray]


def match_counts(slices: Any, exemplar: Any) -> np.ndarray:
    """For each slice and each shift, the number of pixels equal to the periodic exemplar.

    Parameters
    ----------
    slices : array_like, (n, h, w)
        Integer-valued slices (e.g. grey-level indices); any ``h``, ``w``.
    exemplar : array_like, (H, W)
        Integer-valued exemplar, extended periodically.

    Returns
    -------
    numpy.ndarray
        ``(n, H, W)`` int64: ``counts[k, dy, dx]`` is the number of pixels ``(r, c)`` with
        ``slices[k, r, c] == exemplar[(r + dy) % H, (c + dx) % W]``.

    Notes
    -----
    Exact, by FFT: for every value v of the exemplar, the slices' indicator of v is folded
    onto the exemplar's period (summing pixels congruent modulo (H, W)) and
    cross-correlated with the exemplar's indicator of v; the sums are whole numbers, so
    rounding the float64 result recovers them exactly.
    """
    stack = np.asarray(slices)
    ex = np.asarray(exemplar)
    if stack.ndim != 3 or ex.ndim != 2:
        raise InputError(f"slices must be (n, h, w) and exemplar (H, W); got shapes {stack.shape} and {ex.shape}")
    n, h, w = stack.shape
    big_h, big_w = ex.shape
    total = np.zeros((n, big_h, big_w))
    for value in np.unique(ex):
        folded = _fold((stack == value).astype(np.float64), big_h, big_w)
        spec = np.conj(np.fft.rfft2(folded)) * np.fft.rfft2((ex == value).astype(np.float64))[None]
        total += np.fft.irfft2(spec, s=(big_h, big_w))
    return np.rint(total).astype(np.int64)


def _fold(stack: np.ndarray, big_h: int, big_w: int) -> np.ndarray:
    """Sum the pixels of each slice that are congruent modulo ``(big_h, big_w)``."""
    n, h, w = stack.shape
    pad = np.zeros((n, -(-h // big_h) * big_h, -(-w // big_w) * big_w))
    pad[:, :h, :w] = stack
    return pad.reshape(n, pad.shape[1] // big_h, big_h, pad.shape[2] // big_w, big_w).sum(axis=(1, 3))


def max_copy_fraction(volume: Any, exemplar: Any, views: Any = VIEWS) -> CopyMatch:
    """The largest fraction of any slice identical to a shifted window of the exemplar.

    Parameters
    ----------
    volume : array_like, (Z, Y, X)
        Integer-valued volume, in the same values as ``exemplar`` (e.g. both grey-level
        indices).
    exemplar : array_like, (H, W)
        The exemplar.
    views : sequence of {"front", "right", "top"}
        Views whose every slice is compared (oriented as :func:`clsolid.metrics.view_slices`
        gives them, which is how the synthesis maps the exemplar onto them).

    Returns
    -------
    CopyMatch
        The best slice: its fraction, view, depth and shift, and every slice's best fraction.

    Notes
    -----
    A *window* here is a slice-sized block of the exemplar repeated periodically, placed
    at any of its H x W shifts: ``window[r, c] = exemplar[(r + dy) % H, (c + dx) % W]``.
    Windows wholly inside the exemplar are among them, and so are the tiled copies the
    ``+in`` start writes when a slice is larger than the exemplar, so the measure catches
    both; a window that straddles the exemplar's edge joins pixels that are not
    neighbours in it, which can only raise the fraction (an upper bound of the copying
    that respects the exemplar's edges). The slice is compared as it lies (not shifted
    around its own wrap), without rotating or flipping the exemplar.
    """
    vol = as_volume(volume, "volume", min_side=1)
    ex = np.asarray(exemplar)
    if ex.ndim != 2 or ex.size == 0:
        raise InputError(f"exemplar must be a non-empty 2D image, got shape {ex.shape}")
    views = check_views(views, "views")
    best: tuple[float, str, int, tuple[int, int]] = (-1.0, views[0], 0, (0, 0))
    per_view = {}
    for view in views:
        stack = view_slices(vol, view)
        counts = match_counts(stack, ex).reshape(len(stack), -1)
        flat = counts.argmax(axis=1)
        fractions = counts[np.arange(len(stack)), flat] / float(stack.shape[1] * stack.shape[2])
        per_view[view] = fractions
        k = int(fractions.argmax())
        if fractions[k] > best[0]:
            dy, dx = np.unravel_index(flat[k], ex.shape)
            best = (float(fractions[k]), view, k, (int(dy), int(dx)))
    return CopyMatch(fraction=best[0], view=best[1], index=best[2], shift=best[3], per_view=per_view)
