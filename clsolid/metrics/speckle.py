"""Speckle: voxels unlike every one of their face neighbours.

A faithful volume has few of them: a label no neighbour shares, or a grey level further
from all its neighbours than the exemplar's own steps between neighbours, is noise that
slice statistics average away. Neighbours are the face neighbours inside the array (6 in a
volume, 4 in an image; fewer on its faces, edges and corners); nothing wraps around, unless
the volume is said to be periodic (clsolid's volumes tile: a voxel on a face has its
neighbour across the opposite face). A voxel with no neighbour inside the array (a 1-voxel
array) is never isolated, since nothing says it is unlike its surroundings.
"""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np

from ..errors import InputError
from ._common import as_image_or_volume, neighbour_pairs, view_slices

#: Default quantile of the exemplar's neighbour differences a grey voxel must exceed.
DEFAULT_QUANTILE = 0.99


def _isolated_labels(labels: np.ndarray, axes: tuple[int, ...]) -> np.ndarray:
    """Mask of the voxels no face neighbour along ``axes`` shares the label of."""
    shared = np.zeros(labels.shape, dtype=bool)
    for a in axes:
        lo, hi = neighbour_pairs(labels.ndim, a)
        same = labels[lo] == labels[hi]
        shared[lo] |= same
        shared[hi] |= same
    if all(labels.shape[a] == 1 for a in axes):
        return np.zeros(labels.shape, dtype=bool)  # no neighbours at all: none isolated
    return ~shared


def _isolated_contrast(values: np.ndarray, axes: tuple[int, ...], threshold: float) -> np.ndarray:
    """Mask of the voxels whose every face neighbour along ``axes`` differs by more than ``threshold``."""
    values = values.astype(np.float64, copy=False)
    nearest = np.full(values.shape, np.inf)
    for a in axes:
        lo, hi = neighbour_pairs(values.ndim, a)
        step = np.abs(values[hi] - values[lo])
        np.minimum(nearest[lo], step, out=nearest[lo])
        np.minimum(nearest[hi], step, out=nearest[hi])
    if all(values.shape[a] == 1 for a in axes):
        return np.zeros(values.shape, dtype=bool)
    return nearest > threshold


def contrast_threshold(exemplar: Any, *, quantile: float = DEFAULT_QUANTILE) -> float:
    """The ``quantile`` of ``|a - b|`` over every pair of face neighbours of an exemplar.

    Parameters
    ----------
    exemplar : array_like, 2D or 3D
        Grey levels (any real dtype).
    quantile : float, default 0.99
        In (0, 1].

    Returns
    -------
    float
        The threshold :func:`isolated_contrast_fraction` uses, in the exemplar's units.
    """
    ex = as_image_or_volume(exemplar, "exemplar").astype(np.float64, copy=False)
    if isinstance(quantile, bool) or not isinstance(quantile, numbers.Real) or not 0 < quantile <= 1:
        raise InputError(f"quantile={quantile!r} must be a number in (0, 1]")
    steps = [np.abs(np.diff(ex, axis=a)).ravel() for a in range(ex.ndim) if ex.shape[a] > 1]
    if not steps:
        raise InputError(f"exemplar has shape {ex.shape}: it has no pair of neighbours to measure")
    return float(np.quantile(np.concatenate(steps), quantile))


def _wrapped(mask_of: Any, arr: np.ndarray, periodic: bool, *args: Any) -> np.ndarray:
    """``mask_of(arr, axes, *args)``, with every axis wrapping around if *periodic* (the array
    padded by its opposite faces, the mask cut back)."""
    axes = tuple(range(arr.ndim))
    if not periodic:
        return mask_of(arr, axes, *args)
    inner = tuple(slice(1, -1) for _ in axes)
    return mask_of(np.pad(arr, 1, mode="wrap"), axes, *args)[inner]


def isolated_fraction(labels: Any, *, periodic: bool = False) -> float:
    """Fraction of voxels (pixels) whose label none of their face neighbours shares.

    Parameters
    ----------
    labels : array_like, (Z, Y, X) or (rows, cols)
        A label volume (6 face neighbours) or image (4); any real dtype, compared exactly.
    periodic : bool, default False
        Whether the array wraps around (clsolid's volumes do): then every voxel has all its
        face neighbours.

    Returns
    -------
    float
        The share of voxels with at least one neighbour inside the array and none with
        the same label: 1 for a checkerboard, ``1 / labels.size`` for a single voxel of
        another label inside a block.
    """
    arr = as_image_or_volume(labels, "labels")
    return float(np.mean(_wrapped(_isolated_labels, arr, periodic)))


def isolated_contrast_fraction(values: Any, exemplar: Any, *, quantile: float = DEFAULT_QUANTILE,
                               periodic: bool = False) -> float:
    """Fraction of voxels of a grey volume or image unlike every face neighbour.

    A voxel counts when its absolute difference from each of its face neighbours
    (inside the array) exceeds the exemplar's ``quantile`` of absolute differences between
    face neighbours (:func:`contrast_threshold`): a single-voxel spike or pit that stands
    out from its surroundings by more than almost any step in the exemplar does. Edges do
    not count, as the voxels on either side of an edge have a neighbour alike; nor does
    a smooth gradient as steep as the exemplar's steepest.

    Parameters
    ----------
    values : array_like, (Z, Y, X) or (rows, cols)
        The grey volume or image, in the exemplar's units.
    exemplar : array_like, 2D or 3D
        The reference whose neighbour differences set the threshold.
    quantile : float, default 0.99
        In (0, 1]; larger is stricter.
    periodic : bool, default False
        Whether *values* wraps around (as :func:`isolated_fraction`).

    Returns
    -------
    float
        The share of such voxels: about 0 for a volume as smooth as the exemplar, the share
        of spikes for one with isolated spikes above the threshold added.
    """
    arr = as_image_or_volume(values, "values")
    threshold = contrast_threshold(exemplar, quantile=quantile)
    return float(np.mean(_wrapped(_isolated_contrast, arr, periodic, threshold)))


def isolated_fraction_by_slice(volume: Any, view: str, *, exemplar: Any = None,
                               quantile: float = DEFAULT_QUANTILE) -> np.ndarray:
    """The isolated share of every slice of one view, each slice measured as an image.

    Parameters
    ----------
    volume : array_like, (Z, Y, X)
        A label or grey volume.
    view : {"front", "right", "top"}
        The slices (see :func:`clsolid.metrics.view_slices`).
    exemplar : array_like or None
        None: labels, each slice as :func:`isolated_fraction` measures an image (4 in-plane
        neighbours). An exemplar: grey levels, as :func:`isolated_contrast_fraction` with
        this exemplar's threshold.
    quantile : float, default 0.99
        The exemplar's quantile, for grey levels.

    Returns
    -------
    numpy.ndarray
        ``(n_slices,)`` float64 in slice order: a slice that stands out (an inserted
        exemplar copy in a speckled volume, or a speckled slice) shows as an outlier.
    """
    stack = view_slices(volume, view)
    if exemplar is None:
        isolated = _isolated_labels(stack, (1, 2))
    else:
        isolated = _isolated_contrast(stack, (1, 2), contrast_threshold(exemplar, quantile=quantile))
    return isolated.mean(axis=(1, 2))
