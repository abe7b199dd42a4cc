"""Visiting orders of a block's voxels for sequential relaxation (Urs thesis, App. B).

Each function returns the flat indices of a ``(Z, Y, X)`` block in visiting order (a
permutation of ``range(Z * Y * X)``):

* ``lexicographic``: z, then y, then x (raster order, x fastest);
* ``random``: a permutation drawn from a seeded generator;
* ``morton``: the Z-order curve, the bits of (z, y, x) interleaved;
* ``hilbert``: the 3D Hilbert curve, whose consecutive voxels are face neighbours.

Curves are defined on the smallest power-of-two cube holding the block; a block of other
sizes visits its voxels in the order the curve passes them.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError

ORDERS = ("lexicographic", "random", "morton", "hilbert")


def _bits(shape: tuple[int, ...]) -> int:
    return max(1, int(np.ceil(np.log2(max(shape)))))


def _coords(shape: tuple[int, int, int]) -> list[np.ndarray]:
    return [c.ravel().astype(np.int64) for c in np.indices(shape)]


def morton_keys(shape: tuple[int, int, int]) -> np.ndarray:
    """Each voxel's position on the Z-order curve: bits of z, y, x interleaved (z highest)."""
    coords, key = _coords(shape), np.zeros(int(np.prod(shape)), np.int64)
    for bit in range(_bits(shape) - 1, -1, -1):
        for c in coords:
            key = (key << 1) | ((c >> bit) & 1)
    return key


def hilbert_keys(shape: tuple[int, int, int]) -> np.ndarray:
    """Each voxel's position on the 3D Hilbert curve (Skilling's transpose form, 2004)."""
    b = _bits(shape)
    x = _coords(shape)
    # From axes to the "transposed" Hilbert index: undo the excess work, then Gray-encode.
    q = 1 << (b - 1)
    while q > 1:
        p = q - 1
        for i in range(3):
            hit = (x[i] & q) != 0
            x[0] = np.where(hit, x[0] ^ p, x[0])
            t = np.where(hit, 0, (x[0] ^ x[i]) & p)
            x[0], x[i] = x[0] ^ t, x[i] ^ t
        q >>= 1
    for i in range(1, 3):
        x[i] = x[i] ^ x[i - 1]
    t = np.zeros_like(x[0])
    q = 1 << (b - 1)
    while q > 1:
        t = np.where((x[2] & q) != 0, t ^ (q - 1), t)
        q >>= 1
    x = [xi ^ t for xi in x]
    key = np.zeros_like(t)
    for bit in range(b - 1, -1, -1):
        for xi in x:
            key = (key << 1) | ((xi >> bit) & 1)
    return key


def visiting_order(shape: tuple[int, int, int], order: str, rng: np.random.Generator | None = None) -> np.ndarray:
    """Flat voxel indices of a ``shape`` block in the named *order* (see the module docstring).

    ``rng`` draws the ``random`` order (required for it, ignored otherwise).
    """
    n = int(np.prod(shape))
    if order == "lexicographic":
        return np.arange(n)
    if order == "random":
        if rng is None:
            raise InputError("the random order needs a seeded generator")
        return rng.permutation(n)
    if order == "morton":
        return np.argsort(morton_keys(shape), kind="stable")
    if order == "hilbert":
        return np.argsort(hilbert_keys(shape), kind="stable")
    raise InputError(f"order={order!r} must be one of {', '.join(map(repr, ORDERS))}")
