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

import numpy as np


def _period_ok(k: int, n: int, a: int) -> bool:
    return all(min(j, n - j) > a for j in range(k, n, k))


def period(shape: tuple[int, ...], half_width: int) -> int:
    """Smallest period ``k > half_width`` valid on every axis of the toroidal *shape*."""
    k = half_width + 1
    while not all(_period_ok(k, n, half_width) for n in shape):
        k += 1
    return k


def colour_sets(shape: tuple[int, int, int], half_width: int) -> tuple[np.ndarray, int]:
    """Colour of every voxel of a ``(Z, Y, X)`` block and the number of colours."""
    k = period(shape, half_width)
    z, y, x = np.ogrid[: shape[0], : shape[1], : shape[2]]
    colour = ((y + z) % k) * k + (x + z) % k
    return np.broadcast_to(colour, shape).astype(np.int32), k * k


def set_order(n_sets: int, seed: int, scale: int, sweep: int) -> np.ndarray:
    """The order in which one sweep visits the sets, drawn from (seed, scale, sweep)."""
    return np.random.default_rng([seed, scale, sweep]).permutation(n_sets)


def split_by_colour(active: np.ndarray, colour: np.ndarray, n_sets: int) -> list[np.ndarray]:
    """Flat indices of the active voxels of each colour, ascending within a set."""
    idx = np.flatnonzero(active.ravel())
    col = colour.ravel()[idx]
    order = np.argsort(col, kind="stable")
    bounds = np.searchsorted(col[order], np.arange(n_sets + 1))
    sorted_idx = idx[order]
    return [sorted_idx[bounds[c] : bounds[c + 1]] for c in range(n_sets)]
