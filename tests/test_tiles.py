"""Tiles (issue 12, point 2): the tile geometry."""

import numpy as np
import pytest

from clsolid.core.tiles import Tiling, gather, split_axis
from clsolid.ml.opencl import CLBackend

SHAPE = (20, 16, 18)  # no two axes alike; tiles of 8: 7, 7, 6 by 8, 8 by 6, 6, 6


# -- geometry ------------------------------------------------------------------------


@pytest.mark.parametrize("size, edge, lengths", [(20, 8, [7, 7, 6]), (16, 8, [8, 8]), (5, 8, [5]), (7, 1, [1] * 7)])
def test_split_axis_is_even_and_covers_the_axis(size, edge, lengths):
    cuts = split_axis(size, edge)
    assert [n for _, n in cuts] == lengths
    assert [s for s, _ in cuts] == list(np.cumsum([0] + lengths[:-1]))


@pytest.mark.parametrize("shape, edge, halo", [((20, 18, 22), 8, 2), ((9, 16, 5), 4, 3), ((6, 6, 6), 6, 2),
                                               ((12, 7, 10), 5, 4)])
def test_tiles_gather_with_wrap_and_give_their_cores_back(shape, edge, halo):
    a = np.random.default_rng(0).random((2,) + shape)  # a leading axis (views) comes along
    tiling = Tiling(shape, edge, halo)
    cover = np.zeros(shape, int)
    out = np.zeros_like(a)
    padded = np.pad(a, [(0, 0)] + [(halo, halo)] * 3, mode="wrap")
    for tile in tiling.tiles:
        cover[tile.core()] += 1
        block = gather(a, tile)
        assert block.shape == (2,) + tile.block_shape
        for axis, (s, n, lead, b, size) in enumerate(zip(tile.start, tile.size, tile.lead, tile.block_shape, shape)):
            if b == size:  # the whole axis, as the block has it: the tile's wrap is the block's
                assert lead == s and tile.origin[axis] == 0
            else:  # the core with a halo on both sides, wrapped round the block's edges
                assert lead == halo and b == n + 2 * halo < size
        whole = tuple(slice(None) if b == n else slice(s, s + b)
                      for s, b, n in zip(tile.start, tile.block_shape, shape))
        if all(b < n for b, n in zip(tile.block_shape, shape)):
            np.testing.assert_array_equal(block, padded[(...,) + whole])
        np.testing.assert_array_equal(block[(...,) + tile.inner()], a[(...,) + tile.core()])
        out[(...,) + tile.core()] = block[(...,) + tile.inner()]
        core = np.ravel_multi_index(np.indices(tile.size).reshape(3, -1) + np.array(tile.start)[:, None], shape)
        np.testing.assert_array_equal(block[0].ravel()[tile.local(core)], a[0].ravel()[core])
    assert (cover == 1).all()  # the cores partition the block
    np.testing.assert_array_equal(out, a)
    assert tiling.largest_block == tuple(max(t.block_shape[i] for t in tiling.tiles) for i in range(3))


def test_group_finds_each_voxels_tile():
    tiling = Tiling(SHAPE, 8, 2)
    voxels = np.random.default_rng(1).choice(np.prod(SHAPE), 500, replace=False)
    seen = []
    for tile, part in tiling.group(voxels):
        coords = np.unravel_index(part, SHAPE)
        assert all(((c >= s) & (c < s + n)).all() for c, s, n in zip(coords, tile.start, tile.size))
        seen.extend(part)
    assert sorted(seen) == sorted(voxels)


def test_random_start_in_runs_is_the_same(device, monkeypatch):
    pixels = np.arange(40.0).reshape(5, 8)
    whole = CLBackend(device).init_volume(SHAPE, 3, pixels)
    monkeypatch.setattr(type(device), "max_alloc", property(lambda self: 1000))  # 250 voxels a run
    np.testing.assert_array_equal(CLBackend(device).init_volume(SHAPE, 3, pixels), whole)
