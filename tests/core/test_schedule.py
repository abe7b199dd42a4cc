import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from clsolid.ml.model import view_offsets
from clsolid.core.schedule import colour_set, colour_sets, period, regions, set_count, set_order


def union_offsets(half, views):
    return np.unique(np.concatenate([view_offsets(v, half) for v in views]), axis=0)


def assert_conflict_free(shape, half, views):
    colour, n = colour_sets(shape, half)
    assert colour.min() >= 0 and colour.max() < n
    ids = np.arange(np.prod(shape)).reshape(shape)
    for off in union_offsets(half, views):
        # neighbour of every voxel at this offset, wrap-around included
        nb_colour = np.roll(colour, shift=tuple(-off), axis=(0, 1, 2))
        nb_id = np.roll(ids, shift=tuple(-off), axis=(0, 1, 2))
        clash = (nb_colour == colour) & (nb_id != ids)
        assert not clash.any(), f"shape {shape}, half {half}, offset {off}: voxels of one set are neighbours"


@settings(max_examples=60, deadline=None)
@given(shape=st.tuples(*[st.integers(1, 23)] * 3), half=st.integers(1, 5), three=st.booleans())
def test_sets_are_conflict_free_for_every_size(shape, half, three):
    views = ("front", "right", "top") if three else ("front", "right")
    assert_conflict_free(shape, half, views)


def test_period_respects_the_wrap():
    assert period((65, 65, 65), 4) == 5  # 25 sets for a 9x9 window when 5 divides the size
    # on 64, period 5 would put 0 and 60 (wrapped distance 4) in one set; 6 and 7 fail too
    assert period((64, 64, 64), 4) == 8
    assert colour_sets((64, 64, 64), 4)[1] == 64
    assert_conflict_free((64, 64, 64), 4, ("front", "right", "top"))


def test_non_multiple_size_gets_a_longer_period():
    # 66 = 13*5 + 1: positions 0 and 65 are neighbours on the torus and 65 = 13*5
    assert period((66, 64, 64), 4) > 5
    assert_conflict_free((66, 64, 63), 4, ("front", "right", "top"))


def test_set_order_is_a_seeded_permutation():
    a = set_order(25, 7, 0, 1)
    assert sorted(a.tolist()) == list(range(25))
    np.testing.assert_array_equal(a, set_order(25, 7, 0, 1))
    assert not np.array_equal(a, set_order(25, 7, 0, 2))
    assert not np.array_equal(a, set_order(25, 8, 0, 1))


@pytest.mark.parametrize("shape, half", [((6, 7, 8), 2), ((13, 5, 8), 1), ((30, 31, 29), 4), ((1, 9, 9), 3)])
def test_colour_sets_partition_active_voxels(shape, half):
    colour, n = colour_sets(shape, half)
    assert set_count(shape, half) == n
    active = np.random.default_rng(0).random(shape) < 0.5
    sets = [colour_set(shape, n, c, active) for c in range(n)]
    allv = np.concatenate(sets)
    assert allv.tolist() != sorted(allv.tolist()) or n == 1  # grouped by colour, not in flat order
    assert sorted(allv.tolist()) == np.flatnonzero(active).tolist()
    for c, s in enumerate(sets):
        assert (colour.ravel()[s] == c).all()
        assert (np.diff(s) > 0).all()  # ascending within a set
        # each set generated from the formula equals a scan of the colour array
        np.testing.assert_array_equal(colour_set(shape, n, c), np.flatnonzero(colour.ravel() == c))


@pytest.mark.parametrize("shape, half, edge", [((6, 7, 8), 2, 3), ((13, 5, 8), 1, 4), ((9, 9, 9), 3, 9),
                                               ((5, 6, 7), 1, 0)])
def test_regions_split_every_set(shape, half, edge):
    """A region-by-region sweep visits each set's voxels once: the sets cut by the regions'
    boxes (cubes of at most *edge*, 0: the whole block) are the sets, voxel for voxel."""
    n = set_count(shape, half)
    boxes = regions(shape, edge)
    sizes = [np.prod([b - a for a, b in box]) for box in boxes]
    assert sum(sizes) == np.prod(shape) and all(b - a <= (edge or max(shape)) for box in boxes for a, b in box)
    active = np.random.default_rng(1).random(shape) < 0.7
    for c in range(n):
        parts = [colour_set(shape, n, c, active, box) for box in boxes]
        np.testing.assert_array_equal(np.sort(np.concatenate(parts)), colour_set(shape, n, c, active))
        for box, part in zip(boxes, parts):
            coords = np.unravel_index(part, shape)
            assert all(((a <= q) & (q < b)).all() for q, (a, b) in zip(coords, box))
