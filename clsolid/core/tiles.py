"""Tiles of a toroidal block: where each lies, its halo, and moving its data in and out.

A block of shape ``(Z, Y, X)`` is cut, axis by axis, into cores of at most a given edge
(their lengths within one voxel of each other). A tile is its core plus a *halo* on every
side, wide enough that whatever a core voxel reads lies in the tile; the block wraps around,
so the halo of a tile at the block's edge comes from the other side. Along an axis where the
core and its halo would reach all the way round, the tile takes the whole axis instead, as
the block has it: there the tile's own wrap-around is the block's.

Everything here is plain NumPy and knows nothing of what the block holds.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np


def split_axis(size: int, edge: int) -> list[tuple[int, int]]:
    """``(start, length)`` of the cores along an axis of *size* voxels, each at most *edge* long.

    As few cores as fit, their lengths within one of each other (the longer ones first).
    """
    count = -(-size // edge)
    lengths = np.full(count, size // count)
    lengths[: size % count] += 1
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    return [(int(s), int(n)) for s, n in zip(starts, lengths)]


@dataclass(frozen=True)
class Tile:
    """One tile of a block.

    Attributes
    ----------
    start : tuple of 3 ints
        The core's first voxel in the block.
    size : tuple of 3 ints
        The core's shape.
    lead : tuple of 3 ints
        The core's first voxel in the tile: the halo before it (all of the block before
        it along an axis the tile takes whole).
    block_shape : tuple of 3 ints
        The tile's shape, halo included.
    shape : tuple of 3 ints
        The whole block's shape.
    """

    start: tuple[int, int, int]
    size: tuple[int, int, int]
    lead: tuple[int, int, int]
    block_shape: tuple[int, int, int]
    shape: tuple[int, int, int]

    @property
    def origin(self) -> tuple[int, int, int]:
        """Where the tile's first voxel lies in the block (on the torus)."""
        return tuple((s - d) % n for s, d, n in zip(self.start, self.lead, self.shape))

    def core(self) -> tuple[slice, ...]:
        """The core's place in the block."""
        return tuple(slice(s, s + n) for s, n in zip(self.start, self.size))

    def inner(self) -> tuple[slice, ...]:
        """The core's place in the tile."""
        return tuple(slice(d, d + n) for d, n in zip(self.lead, self.size))

    def local(self, voxels: np.ndarray) -> np.ndarray:
        """The tile's flat indices of the block's flat *voxels*, which must lie in the core."""
        coords = [c - s + d for c, s, d in zip(np.unravel_index(voxels, self.shape), self.start, self.lead)]
        return np.ravel_multi_index(coords, self.block_shape)


def _tile_axis(start: int, size: int, halo: int, n: int) -> tuple[int, int]:
    """``(lead, length)`` of a tile along an axis of *n* voxels: the core and *halo* on both
    sides, or the whole axis where that would reach round it."""
    if size + 2 * halo >= n:
        return start, n
    return halo, size + 2 * halo


class Tiling:
    """The tiles of a block of *shape*: cores at most *edge* on a side, each with a *halo*.

    Attributes
    ----------
    shape : tuple of 3 ints
    tiles : list of Tile
        In raster order (z slowest).
    """

    def __init__(self, shape: tuple[int, int, int], edge: int, halo: int) -> None:
        self.shape = tuple(int(n) for n in shape)
        cuts = [split_axis(n, edge) for n in self.shape]
        self._starts = [np.array([s for s, _ in c]) for c in cuts]
        self.tiles = []
        for cut in itertools.product(*cuts):
            placed = [_tile_axis(s, size, halo, n) for (s, size), n in zip(cut, self.shape)]
            self.tiles.append(Tile(start=tuple(s for s, _ in cut), size=tuple(size for _, size in cut),
                                   lead=tuple(d for d, _ in placed), block_shape=tuple(b for _, b in placed),
                                   shape=self.shape))

    @property
    def largest_block(self) -> tuple[int, int, int]:
        """The largest tile, halo included, along each axis: a shape that holds any tile."""
        return tuple(max(t.block_shape[a] for t in self.tiles) for a in range(3))

    def which(self, voxels: np.ndarray) -> np.ndarray:
        """The number of the tile whose core holds each of the block's flat *voxels*."""
        number = np.zeros(np.shape(voxels), np.int64)
        for c, starts in zip(np.unravel_index(voxels, self.shape), self._starts):
            number = number * starts.size + np.searchsorted(starts, c, side="right") - 1
        return number

    def group(self, voxels: np.ndarray) -> list[tuple[Tile, np.ndarray]]:
        """The tiles whose cores hold some of the flat *voxels*, in tile order, each with
        those voxels (in their given order)."""
        voxels = np.asarray(voxels)
        number = self.which(voxels)
        order = np.argsort(number, kind="stable")
        found, first = np.unique(number[order], return_index=True)
        return [(self.tiles[t], part) for t, part in zip(found, np.split(voxels[order], first[1:]))]


def _runs(first: int, length: int, n: int) -> list[tuple[slice, slice]]:
    """``(source, destination)`` slices of *length* voxels from *first* on, along an axis of
    *n* voxels that wraps round."""
    out, done = [], 0
    while done < length:
        src = (first + done) % n
        count = min(length - done, n - src)
        out.append((slice(src, src + count), slice(done, done + count)))
        done += count
    return out


def gather(array: np.ndarray, tile: Tile) -> np.ndarray:
    """The tile, halo included, of *array*, whose last three axes are the block's (any before
    them come along), wrapping round the block's edges: a copy, made of at most 8 slabs."""
    out = np.empty(array.shape[:-3] + tile.block_shape, array.dtype)
    for parts in itertools.product(*map(_runs, tile.origin, tile.block_shape, tile.shape)):
        out[(...,) + tuple(d for _, d in parts)] = array[(...,) + tuple(s for s, _ in parts)]
    return out
