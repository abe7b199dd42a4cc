"""``+in`` slices: exemplar slices written into the block at staggered depths of each
constrained view, shared by the likelihood method (thesis_spec §2.8) and, as an anchor
against mirror-image blocks, the search methods (README, Choices).

The functions take a *plan*: any parameters object with ``scales``, ``views`` (2 or 3),
``view_names``, ``slice_layout`` (``"aligned"`` or ``"staggered"``), ``insert_slices`` (a
count per view, or None), ``insert_spacing`` (voxels between a view's slices, used when
the count is None) and ``insert_piece`` (0: each slice one exemplar window; else the side
of the square pieces, each from its own window, that a slice is made of):
:class:`clsolid.ml.params.MLParams` and :class:`clsolid.search.params.SearchParams` both are.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .views import DEPTH_AXIS


def slice_depths(size: int, count: int, step: int, offset: float = 0.0) -> np.ndarray:
    """*count* evenly spaced depths on multiples of *step* (so they survive decimation).

    *offset* shifts them by that fraction of their spacing (wrapping around).
    """
    slots = max(1, -(-size // step))
    spaced = np.linspace(0, slots, count, endpoint=False) + offset * slots / count
    return np.unique(spaced.astype(int) % slots) * step


def _view_offset(plan: Any, view: str) -> float:
    """Where a view's ``+in`` slices sit between the front view's: staggered, view i of n at i/n."""
    return plan.view_names.index(view) / plan.views if plan.slice_layout == "staggered" else 0.0


#: Voxels between a view's ``+in`` slices when a plan leaves the spacing to its exemplar
#: (``insert_spacing=None``) and nothing resolved it (``MLParams.for_exemplar`` does).
FALLBACK_SPACING = 6.0


def slice_count(size: int, plan: Any) -> int:
    """How many ``+in`` slices a view gets along a depth axis of *size* voxels (full resolution)."""
    if plan.insert_slices is not None:
        return plan.insert_slices
    spacing = FALLBACK_SPACING if plan.insert_spacing is None else plan.insert_spacing
    return max(1, round(size / spacing))


def inserted_depths(shape: tuple[int, int, int], plan: Any) -> dict[str, np.ndarray]:
    """Full-resolution depths of the ``+in`` slices of each constrained view (front: z, right: x, top: y)."""
    step = 2 ** (plan.scales - 1)
    out = {}
    for view in plan.view_names:
        size = shape[DEPTH_AXIS[view]]
        count = slice_count(size, plan)
        out[view] = slice_depths(size, count, step, _view_offset(plan, view)) if count else np.empty(0, int)
    return out


def far_depth(size: int, taken: np.ndarray) -> int:
    """The depth farthest (on the torus) from every *taken* one; the middle one among equals."""
    d = np.arange(size)
    if taken.size == 0:
        return size // 2
    gap = np.abs(d[:, None] - taken[None, :])
    dist = np.minimum(gap, size - gap).min(axis=1)
    best = np.flatnonzero(dist == dist.max())
    return int(best[np.argmin(np.abs(best - size // 2))])


def preview_depths(shape: tuple[int, int, int], plan: Any) -> dict[str, int]:
    """One slice per view to show, away from every ``+in`` slice (which only shows the exemplar)."""
    taken = inserted_depths(shape, plan)
    return {view: far_depth(shape[a], taken.get(view, np.empty(0, int))) for view, a in DEPTH_AXIS.items()}


def insert_slices(vol: np.ndarray, labels_img: np.ndarray, plan: Any, level: int, seed: int,
                  full_shape: tuple[int, int, int]) -> np.ndarray:
    """``+in``: tile the exemplar onto the ``+in`` slices of each constrained view.

    Called at every scale with that scale's exemplar: the depths (:func:`inserted_depths`
    of the full-resolution *full_shape*), the tile shifts and the pieces are the
    full-resolution ones divided by 2^level (all multiples of 2^(scales-1)), so each slice
    persists from the coarsest scale down. With ``slice_layout="staggered"`` the views'
    slices sit at different depths and each shows the exemplar shifted by its own seeded
    offset, so that nothing maps the x axis onto z. With ``insert_piece`` > 0 a slice is a
    mosaic of square pieces of that side, each from its own seeded window of the exemplar,
    so that no slice starts as one window (the relaxation sews the seams). Returns the mask
    of inserted voxels; they start each scale trusted (t = 0), like inherited voxels: under
    ICM a voxel at t = 1 ignores its neighbours, so untrusted slices would be overwritten
    unseen.
    """
    mask = np.zeros(vol.shape, bool)
    step = 2 ** (plan.scales - 1 - level)
    shift_rng = np.random.default_rng([seed, 0x1A5E])  # the same draws at every scale
    ex_slots = np.array([-(-n // step) for n in labels_img.shape])
    piece = int(plan.insert_piece)

    def tiled(rows: int, cols: int, full_rows: int, full_cols: int) -> np.ndarray:
        if piece:  # one seeded shift per piece, drawn for the full-resolution grid of pieces
            grid = shift_rng.integers(0, ex_slots, size=(-(-full_rows // piece), -(-full_cols // piece), 2))
            cell = piece >> level
            r, c = np.arange(rows)[:, None], np.arange(cols)[None, :]
            shift = grid[r // cell, c // cell] * step
            return labels_img[(r + shift[..., 0]) % labels_img.shape[0], (c + shift[..., 1]) % labels_img.shape[1]]
        shift = [0, 0]
        if plan.slice_layout == "staggered":
            shift = [int(shift_rng.integers(0, n)) * step for n in ex_slots]
        reps = (-(-(rows + shift[0]) // labels_img.shape[0]), -(-(cols + shift[1]) // labels_img.shape[1]))
        return np.tile(labels_img, reps)[shift[0]: shift[0] + rows, shift[1]: shift[1] + cols]

    Z, Y, X = vol.shape
    FZ, FY, FX = full_shape
    for view, full_depths in inserted_depths(full_shape, plan).items():
        for d in full_depths // 2**level:
            if view == "front":
                vol[d], mask[d] = tiled(Y, X, FY, FX), True
            elif view == "right":
                vol[:, :, d], mask[:, :, d] = tiled(Y, Z, FY, FZ).T, True
            else:
                vol[:, d, :], mask[:, d, :] = tiled(Z, X, FZ, FX), True
    return mask
