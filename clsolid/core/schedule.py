"""Conflict-free colour sets of voxels, so that a set can be relaxed in parallel.

Two voxels conflict when one lies in the other's neighbourhood in a constrained view
(wrap-around included). With half-width ``a`` and a period ``k > a``, the colour

    c(z, y, x) = ((y + z) mod k, (x + z) mod k)

separates every such pair in all three views: in the front plane (same z) it reduces to
(y mod k, x mod k); in the right plane (same x) the second component fixes z and then
the first fixes y; in the top plane (same y) likewise. On a torus of size N the period
must also keep apart positions whose *wrapped* distance is at most ``a``, i.e. no
multiple of k may be within ``a`` of 0 modulo N; ``period`` picks the smallest such k
common to the three axes, so every volume size works, not only multiples of k.
The result is k^2 sets (25 for a 9x9 window), whatever the number of views.
"""

from __future__ import annotations

import math

import numpy as np


def _period_ok(k: int, n: int, a: int) -> bool:
    return all(min(j, n - j) > a for j in range(k, n, k))


def period(shape: tuple[int, ...], half_width: int) -> int:
    """Smallest period ``k > half_width`` valid on every axis of the toroidal *shape*."""
    k = half_width + 1
    while not all(_period_ok(k, n, half_width) for n in shape):
        k += 1
    return k


def set_count(shape: tuple[int, int, int], half_width: int) -> int:
    """Number of colour sets of a ``(Z, Y, X)`` block: the square of its :func:`period`."""
    return period(shape, half_width) ** 2


def colour_sets(shape: tuple[int, int, int], half_width: int) -> tuple[np.ndarray, int]:
    """Colour of every voxel of a ``(Z, Y, X)`` block and the number of colours (4 bytes a
    voxel: the drivers generate each set's voxels with :func:`colour_set` instead)."""
    k = period(shape, half_width)
    z, y, x = np.ogrid[: shape[0], : shape[1], : shape[2]]
    colour = ((y + z) % k) * k + (x + z) % k
    return np.broadcast_to(colour, shape).astype(np.int32), k * k


def set_order(n_sets: int, seed: int, scale: int, sweep: int) -> np.ndarray:
    """The order in which one sweep visits the sets, drawn from (seed, scale, sweep)."""
    return np.random.default_rng([seed, scale, sweep]).permutation(n_sets)


def colour_set(shape: tuple[int, int, int], n_sets: int, c: int, active: np.ndarray | None = None,
               box: tuple[tuple[int, int], ...] | None = None) -> np.ndarray:
    """Flat indices, ascending, of the voxels of colour *c* (of :func:`colour_sets`' *n_sets*),
    only the *active* ones if a mask is given, only those in *box* (``(start, stop)`` per
    axis, a region of :func:`regions`) if one is.

    Generated from the colour's formula, plane by plane, so that a sweep never holds more
    than one set's indices: for c = (cy, cx), plane z holds the grid y = cy - z,
    x = cx - z (mod k)."""
    k = math.isqrt(n_sets)
    cy, cx = divmod(int(c), k)
    depth, rows, cols = shape
    (z0, z1), (y0, y1), (x0, x1) = box or ((0, depth), (0, rows), (0, cols))

    def first(lo: int, residue: int) -> int:  # the first index >= lo of that residue mod k
        return lo + (residue - lo) % k

    planes = [((z * rows + np.arange(first(y0, cy - z), y1, k)[:, None]) * cols
               + np.arange(first(x0, cx - z), x1, k)[None, :]).ravel() for z in range(z0, z1)]
    idx = np.concatenate(planes) if planes else np.empty(0, np.intp)
    return idx if active is None else idx[np.ravel(active)[idx]]


def regions(shape: tuple[int, int, int], edge: int) -> list[tuple[tuple[int, int], ...]]:
    """The boxes (``(start, stop)`` per axis) of a region-by-region sweep: the block cut, axis
    by axis, into cubes of at most *edge* (as :func:`clsolid.core.tiles.split_axis` cuts it
    into tiles, so that regions of a tile's edge are its cores), in raster order; 0: the
    whole block."""
    from .tiles import split_axis

    if not edge:
        return [tuple((0, n) for n in shape)]
    axes = [[(s, s + n) for s, n in split_axis(size, edge)] for size in shape]
    return [(a, b, c) for a in axes[0] for b in axes[1] for c in axes[2]]
