"""Descriptors of binary or few-phase images: volume fractions, S2, the two-point cluster
function C2, lineal path, chord lengths.

Every function takes a label image (2D) or a stack of label images ``(n, rows, cols)`` whose
values are phase indices ``0 .. n_phases - 1``. ``axis=0`` measures along the image rows'
direction (vertical displacements), ``axis=1`` along the columns' direction (horizontal).
Estimates use only the pixels inside each image (no wrap-around), whether or not it is
periodic, so the exemplar and the slices are measured the same way.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import ndimage

from ..errors import InputError
from ..phases import MAX_PHASES
from ._common import as_stack, check_int


def phase_values(image: np.ndarray, max_phases: int = MAX_PHASES) -> np.ndarray | None:
    """The sorted distinct values of an image if there are 2 .. ``max_phases`` of them, else None."""
    values = np.unique(image)
    return values if 2 <= len(values) <= max_phases else None


def to_labels(data: np.ndarray, phases: np.ndarray) -> np.ndarray:
    """Index of the nearest phase value for every pixel (values between phases snap to one)."""
    mids = 0.5 * (phases[1:] + phases[:-1])
    return np.searchsorted(mids, np.asarray(data, dtype=np.float64)).astype(np.int8)


def _stack_along(labels: Any, axis: int) -> np.ndarray:
    """Integer label stack with the measured direction moved to the last axis."""
    stack = as_stack(labels, "labels", min_side=1)
    if axis not in (0, 1):
        raise InputError(f"axis={axis!r} must be 0 (along rows) or 1 (along columns)")
    stack = np.rint(stack).astype(np.int64)
    return stack if axis == 1 else np.swapaxes(stack, 1, 2)


def volume_fractions(labels: Any, n_phases: int) -> np.ndarray:
    """Fraction of the pixels in each phase ``0 .. n_phases - 1``."""
    stack = np.rint(as_stack(labels, "labels", min_side=1)).astype(np.int64)
    n_phases = check_int(n_phases, "n_phases", 1)
    return np.bincount(np.clip(stack.ravel(), 0, n_phases - 1), minlength=n_phases) / stack.size


def two_point_correlation(labels: Any, phase: int, axis: int, max_lag: int) -> np.ndarray:
    """Two-point probability ``S2(r) = P(x in phase and x + r e_axis in phase)``, r = 0 .. max_lag.

    ``S2(0)`` is the phase's fraction; for a structure without long-range order S2 tends
    to the fraction squared. Each lag averages over the pairs inside the image, and
    ``max_lag`` is clipped to the image length minus one.
    """
    stack = _stack_along(labels, axis) == phase
    max_lag = min(check_int(max_lag, "max_lag", 0), stack.shape[2] - 1)
    return np.array([np.mean(stack[:, :, :stack.shape[2] - r] & stack[:, :, r:])
                     for r in range(max_lag + 1)])


def two_point_cluster(labels: Any, phase: int, axis: int, max_lag: int) -> np.ndarray:
    """Two-point cluster function ``C2(r)``: probability that x and x + r e_axis lie in the
    same connected cluster of ``phase`` (8-connected within each image), r = 0 .. max_lag.

    ``C2 <= S2``: the two agree where the phase is one connected network, and C2 falls to 0
    within a few pixels where the phase is scattered specks or small grains (Torquato,
    *Random Heterogeneous Materials*). So it tells a thin connected network from a
    broken one with the same fraction and much the same S2. Clusters are cut by the image's
    edges (no wrap-around), in the exemplar and the slices alike.
    """
    stack = _stack_along(labels, axis) == phase
    within_image = np.zeros((3, 3, 3), bool)
    within_image[1] = True  # 8-connected in each image, never across images
    cluster, _ = ndimage.label(stack, structure=within_image)
    max_lag = min(check_int(max_lag, "max_lag", 0), stack.shape[2] - 1)
    return np.array([np.mean((cluster[:, :, :stack.shape[2] - r] == cluster[:, :, r:]) & stack[:, :, r:])
                     for r in range(max_lag + 1)])


def _runs(stack: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lengths of the runs of True along the last axis and whether each touches an end."""
    n_lines, w = stack.shape[0] * stack.shape[1], stack.shape[2]
    padded = np.zeros((n_lines, w + 2), dtype=np.int8)
    padded[:, 1:-1] = stack.reshape(n_lines, w)
    step = np.diff(padded.ravel())
    starts = np.flatnonzero(step == 1) + 1
    ends = np.flatnonzero(step == -1) + 1
    col_start, col_end = starts % (w + 2), ends % (w + 2)  # 1-based position in the line
    touches = (col_start == 1) | (col_end == w + 1)
    return ends - starts, touches


def lineal_path(labels: Any, phase: int, axis: int, max_lag: int) -> np.ndarray:
    """Lineal path ``L(r)``: probability that a segment of r + 1 pixels lies wholly in ``phase``.

    ``L(0)`` is the phase's fraction; L decreases with r. Segments are placed only inside
    the image (a run of length l holds ``max(0, l - r)`` of them).
    """
    stack = _stack_along(labels, axis) == phase
    w = stack.shape[2]
    max_lag = min(check_int(max_lag, "max_lag", 0), w - 1)
    lengths, _ = _runs(stack)
    counts = np.bincount(lengths, minlength=w + 1).astype(np.float64)
    ell = np.arange(len(counts))
    n_lines = stack.shape[0] * stack.shape[1]
    return np.array([np.sum(counts[r + 1:] * (ell[r + 1:] - r)) / (n_lines * (w - r))
                     for r in range(max_lag + 1)])


def chord_lengths(labels: Any, phase: int, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Chords of ``phase`` along ``axis``: lengths and edge-correction weights.

    Chords are the runs of the phase bounded by other phases on both sides; runs that
    touch the image's ends are cut and dropped. A chord of length l is wholly seen in a
    line of W pixels for ``W - l - 1`` of the W possible placements, so it is weighted
    by ``W / (W - l - 1)`` (the 1D Miles-Lantuejoul correction).
    """
    stack = _stack_along(labels, axis) == phase
    w = stack.shape[2]
    lengths, touches = _runs(stack)
    lengths = lengths[~touches]
    return lengths.astype(np.float64), w / (w - lengths - 1.0)
