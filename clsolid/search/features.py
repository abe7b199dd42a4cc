"""Neighbourhood features of the search methods: the k x k square of a level, plus the 3 x 3
square of the coarser level around the parent position (the multi-resolution neighbourhood,
Urs thesis, §3.2.3), for exemplar sites and for voxels in one view plane.

Layout of a feature row: the k*k square read row by row (the centre at ``k*k // 2``), then,
with a parent level, its 3 x 3 square read row by row. Exemplar sites count only where both
squares lie inside their images (no wrap-around in the exemplar, Urs thesis, §3.2.4); the
volume wraps on every axis (toroidal output).
"""

from __future__ import annotations

import numpy as np

from ..core.views import VIEW_AXES
from ..errors import InputError
from .match import causal_weights, square_offsets

PARENT_SIDE = 3


def feature_size(k: int, parent: bool) -> int:
    return k * k + (PARENT_SIDE**2 if parent else 0)


def centre_weights(k: int, parent: bool, centre: bool, causal: bool = False) -> np.ndarray:
    """Weights of the squared distance: 1 on every term, the centre's 0 unless *centre*;
    with *causal*, the k x k square's terms are the L-shaped causal neighbourhood's
    (:func:`~clsolid.search.match.causal_weights`: the centre and what follows it are 0),
    and the parent square stays whole."""
    w = np.ones(feature_size(k, parent), np.float32)
    if not centre:
        w[k * k // 2] = 0.0
    if causal:
        w[: k * k] = causal_weights(k)
    return w


def valid_sites(fine_shape: tuple[int, int], coarse_shape: tuple[int, int] | None,
                k: int) -> tuple[np.ndarray, np.ndarray]:
    """Row and column of every exemplar site whose k x k square (and, with a coarser level of
    *coarse_shape*, its parent 3 x 3 square) lies inside the image, row-major."""
    h = k // 2
    rows, cols = np.mgrid[h : max(h, fine_shape[0] - h), h : max(h, fine_shape[1] - h)]
    r, c = rows.ravel(), cols.ravel()
    if coarse_shape is not None:  # the parent square must fit too
        ok = ((r // 2 >= 1) & (r // 2 + 1 < coarse_shape[0]) & (c // 2 >= 1) & (c // 2 + 1 < coarse_shape[1]))
        r, c = r[ok], c[ok]
    return r, c


def exemplar_features(fine: np.ndarray, coarse: np.ndarray | None, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Feature rows ``(n_sites, dim)`` and centre values ``(n_sites,)`` of every valid site of
    the level image *fine* (with *coarse*, the next pyramid level, as parent), row-major."""
    r, c = valid_sites(fine.shape, None if coarse is None else coarse.shape, k)
    if r.size == 0:
        raise InputError(f"a {fine.shape[0]}x{fine.shape[1]} pyramid level has no complete {k}x{k} "
                         "neighbourhood: use fewer scales or a smaller neighborhood")
    off = square_offsets(k)
    parts = [fine[r[:, None] + off[:, 0], c[:, None] + off[:, 1]]]
    if coarse is not None:
        po = square_offsets(PARENT_SIDE)
        parts.append(coarse[r[:, None] // 2 + po[:, 0], c[:, None] // 2 + po[:, 1]])
    return np.ascontiguousarray(np.concatenate(parts, axis=1), np.float32), fine[r, c]


def site_use(fine_shape: tuple[int, int], coarse_shape: tuple[int, int] | None, k: int,
             sites: np.ndarray) -> np.ndarray:
    """The position histogram: how many of *sites* (indices into :func:`valid_sites`) fall
    on each exemplar pixel, ``(H, W)`` int64, and -1 where a pixel is no valid site."""
    r, c = valid_sites(fine_shape, coarse_shape, k)
    use = np.full(fine_shape, -1, np.int64)
    use[r, c] = np.bincount(np.ravel(sites), minlength=r.size)
    return use


def voxel_features(volume: np.ndarray, coarse: np.ndarray | None, voxels: np.ndarray, view: str,
                   k: int) -> np.ndarray:
    """Feature rows ``(m, dim)`` of flat *voxels* of *volume* in *view* (toroidal), with the
    coarser level's volume *coarse* as parent (its square around ``(z//2, y//2, x//2)``)."""
    row_axis, col_axis = VIEW_AXES[view]
    pos = np.stack(np.unravel_index(voxels, volume.shape))  # (3, m)
    parts = [_square(volume, pos, row_axis, col_axis, k)]
    if coarse is not None:
        parts.append(_square(coarse, pos // 2, row_axis, col_axis, PARENT_SIDE))
    return np.concatenate(parts, axis=1)


def square_voxels(shape: tuple[int, int, int], pos: np.ndarray, row_axis: int, col_axis: int,
                  k: int) -> np.ndarray:
    """``(m, k*k)`` flat indices of the k x k squares (toroidal) of a *shape* block around
    the voxels at *pos* ``(3, m)``, in the plane of (*row_axis*, *col_axis*), read row by row
    (as :func:`~clsolid.search.match.square_offsets`)."""
    stride = (shape[1] * shape[2], shape[2], 1)
    r = k // 2
    pos = np.asarray(pos) % np.array(shape)[:, None]
    d = np.arange(k) - r
    delta = (d[:, None] * stride[row_axis] + d[None, :] * stride[col_axis]).ravel()
    out = (pos[0] * stride[0] + pos[1] * stride[1] + pos[2] * stride[2])[:, None] + delta  # no square wraps
    wraps = ((pos[row_axis] < r) | (pos[row_axis] >= shape[row_axis] - r)
             | (pos[col_axis] < r) | (pos[col_axis] >= shape[col_axis] - r))
    if wraps.any():  # near a face the square wraps round: row and column each modulo their axis
        p = pos[:, wraps]
        rows = ((p[row_axis][:, None] + d) % shape[row_axis]) * stride[row_axis]  # (w, k)
        cols = ((p[col_axis][:, None] + d) % shape[col_axis]) * stride[col_axis]
        depth = 3 - row_axis - col_axis
        base = p[depth] * stride[depth]
        out[wraps] = (base[:, None, None] + rows[:, :, None] + cols[:, None, :]).reshape(p.shape[1], k * k)
    return out


def _square(vol: np.ndarray, pos: np.ndarray, row_axis: int, col_axis: int, k: int) -> np.ndarray:
    return np.take(vol, square_voxels(vol.shape, pos, row_axis, col_axis, k))
