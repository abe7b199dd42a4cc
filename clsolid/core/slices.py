"""``+in`` slices: exemplar slices written into the block at staggered depths of each
constrained view, shared by the likelihood method (Urs thesis, §4.3.1, §4.3.5.1) and, as
an anchor against mirror-image blocks, the search methods (docs/design.md#anchor-slices).

The functions take a *plan*: any parameters object with ``scales``, ``views`` (2 or 3),
``view_names``, ``slice_layout`` (``"aligned"`` or ``"staggered"``), ``insert_slices`` (a
count per view, or None), ``insert_spacing`` (voxels between a view's slices, used when
the count is None), ``insert_piece`` (0: each slice one exemplar window; else the side
of the square pieces, each from its own window, that a slice is made of) and ``seam_gap``
(pixels left unwritten on each side of a seam where a slice tiles the exemplar across its
edge; 0 or None: none):
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
    return plan.view_names.index(view) / len(plan.view_names) if plan.slice_layout == "staggered" else 0.0


#: Voxels between a view's ``+in`` slices when a plan leaves the spacing to its exemplar
#: (``insert_spacing=None``) and nothing resolved it (``MLParams.for_exemplar`` does).
FALLBACK_SPACING = 6.0
#: Where a ``+in`` slice tiles the exemplar across its own edge (a staggered shift, or a slice
#: longer than the exemplar), that many pixels on each side of the seam are left out (at least
#: 1 at coarser scales), on exemplars whose seam shows (:func:`seam_ratio` above SEAM_SHOWS):
#: the seam joins pixels that are not neighbours in the exemplar, and the likelihood sums only
#: windows inside it, so no window supports what the seam shows (docs/design.md#seam-gap).
SEAM_GAP = 2
#: The :func:`seam_ratio` above which an exemplar's seam shows: above what exemplars made to
#: wrap and photographs of fine-grained textures measure, below what photographs of coarse
#: textures do (docs/design.md#seam-gap).
SEAM_SHOWS = 2.0


def seam_ratio(image: np.ndarray) -> float:
    """How much more an image's values differ across its wrap than between neighbours.

    The mean absolute difference between its first and last rows and first and last columns,
    over the mean absolute difference between neighbouring rows and columns inside it: about
    1 for an image that tiles seamlessly (or whose texture is so fine that a seam looks like
    the rest), well above 1 where tiling it shows a seam. 0 for a constant image.
    """
    a = np.asarray(image, np.float64)
    edge = np.abs(a[0] - a[-1]).sum() + np.abs(a[:, 0] - a[:, -1]).sum()
    inner = np.abs(np.diff(a, axis=0)).sum() + np.abs(np.diff(a, axis=1)).sum()
    pairs = a.shape[0] * (a.shape[1] - 1) + a.shape[1] * (a.shape[0] - 1)
    return float(edge / (a.shape[0] + a.shape[1]) / (inner / pairs)) if inner else 0.0


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


def seam_free(n: int, shift: int, size: int, band: int) -> np.ndarray:
    """Which of *n* consecutive pixels, showing exemplar rows (or columns) ``(i + shift) % size``,
    lie at least *band* pixels from a seam where the exemplar wraps onto its own first row."""
    ok = np.ones(n, bool)
    if band:
        for i in np.flatnonzero((np.arange(1, n) + shift) % size == 0) + 1:  # a seam between i - 1 and i
            ok[max(0, i - band): i + band] = False
    return ok


def insert_slices(vol: np.ndarray, labels_img: np.ndarray | dict[str, np.ndarray], plan: Any, level: int, seed: int,
                  full_shape: tuple[int, int, int], mask: np.ndarray | None = None) -> np.ndarray:
    """``+in``: tile the exemplar (each view's own, given a dict by view) onto the ``+in`` slices
    of each constrained view.

    Called at every scale with that scale's exemplar: the depths (:func:`inserted_depths`
    of the full-resolution *full_shape*), the tile shifts and the pieces are the
    full-resolution ones divided by 2^level (all multiples of 2^(scales-1)), so each slice
    persists from the coarsest scale down. With ``slice_layout="staggered"`` the views'
    slices sit at different depths and each shows the exemplar shifted by its own seeded
    offset, so that nothing maps the x axis onto z. With ``insert_piece`` > 0 a slice is a
    mosaic of square pieces of that side, each from its own seeded window of the exemplar,
    so that no slice starts as one window (the relaxation sews the seams). Otherwise, where
    a slice tiles the exemplar across its edge, ``seam_gap`` pixels on each side of the seam
    (at least 1 at coarser scales) are left as they were (:data:`SEAM_GAP`). Staggered, where
    slices of two views cross (a line), slice i of the view written first shows there if
    i + j is even, slice j of the other if it is odd, so that no view's slices carry all the
    foreign lines (written in view order, as aligned slices still are, every front slice
    would hold the right slices' columns, and the front view match the exemplar worse;
    docs/design.md#staggered-slices). Returns the mask
    of inserted voxels (marked in *mask*, an array of False of *vol*'s shape such as a scratch
    file's, if given); they start each scale trusted (t = 0), like inherited voxels: under
    ICM a voxel at t = 1 ignores its neighbours, so untrusted slices would be overwritten
    unseen.
    """
    mask = np.zeros(vol.shape, bool) if mask is None else mask
    step = 2 ** (plan.scales - 1 - level)
    shift_rng = np.random.default_rng([seed, 0x1A5E])  # the same draws at every scale
    piece = int(plan.insert_piece)
    band = max(1, int(plan.seam_gap) >> level) if plan.seam_gap else 0

    def tiled(image: np.ndarray, rows: int, cols: int, full_rows: int, full_cols: int
              ) -> tuple[np.ndarray, np.ndarray]:
        """A slice's pixels of *image*, and which of them to write."""
        ex_slots = np.array([-(-n // step) for n in image.shape])
        if piece:  # one seeded shift per piece, drawn for the full-resolution grid of pieces
            grid = shift_rng.integers(0, ex_slots, size=(-(-full_rows // piece), -(-full_cols // piece), 2))
            cell = piece >> level
            r, c = np.arange(rows)[:, None], np.arange(cols)[None, :]
            shift = grid[r // cell, c // cell] * step
            img = image[(r + shift[..., 0]) % image.shape[0], (c + shift[..., 1]) % image.shape[1]]
            return img, np.ones(img.shape, bool)
        shift = [0, 0]
        if plan.slice_layout == "staggered":
            shift = [int(shift_rng.integers(0, n)) * step for n in ex_slots]
        reps = (-(-(rows + shift[0]) // image.shape[0]), -(-(cols + shift[1]) // image.shape[1]))
        img = np.tile(image, reps)[shift[0]: shift[0] + rows, shift[1]: shift[1] + cols]
        written = (seam_free(rows, shift[0], image.shape[0], band)[:, None]
                   & seam_free(cols, shift[1], image.shape[1], band)[None, :])
        return img, written

    Z, Y, X = vol.shape
    FZ, FY, FX = full_shape
    placed = []  # (axis, depths) of the views written so far, whose crossings are shared
    share = plan.slice_layout == "staggered"
    for view, full_depths in inserted_depths(full_shape, plan).items():
        depths = full_depths // 2**level
        image = labels_img[view] if isinstance(labels_img, dict) else labels_img
        for k, d in enumerate(depths):
            if view == "front":
                plane, (img, written) = np.s_[d, :, :], tiled(image, Y, X, FY, FX)
            elif view == "right":
                plane, (img, written) = np.s_[:, :, d], (a.T for a in tiled(image, Y, Z, FY, FZ))
            else:
                plane, (img, written) = np.s_[:, d, :], tiled(image, Z, X, FZ, FX)
            earlier = np.zeros(written.shape, bool)
            for axis, theirs in placed:  # crossings with an earlier view's slices: it keeps those of even i + k
                at = axis if axis < DEPTH_AXIS[view] else axis - 1
                line = np.zeros(written.shape[at], bool)
                line[[d2 for i, d2 in enumerate(theirs) if (i + k) % 2 == 0]] = True
                earlier |= line[:, None] if at == 0 else line[None, :]
            written = written & ~(earlier & mask[plane])
            vol[plane][written] = img[written]
            mask[plane][written] = True
        if share:
            placed.append((DEPTH_AXIS[view], depths))
    return mask
