"""Speckle (clsolid.metrics.speckle): labels no face neighbour shares, and grey voxels unlike all
their neighbours by more than the exemplar's neighbour steps."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi

from clsolid.errors import InputError
from clsolid.metrics import (contrast_threshold, isolated_contrast_fraction, isolated_fraction,
                             isolated_fraction_by_slice)


def _smooth(shape: tuple[int, ...], seed: int) -> np.ndarray:
    """A smooth grey field around 100 with unit spread."""
    field = ndi.gaussian_filter(np.random.default_rng(seed).standard_normal(shape), 3.0, mode="wrap")
    return 100.0 + field / field.std()


def _with_spikes(values: np.ndarray, share: float, height: float, seed: int) -> tuple[np.ndarray, int]:
    """Add +-height to a random subset of the voxels on a grid of stride 3, so no two spikes
    are neighbours; return the spiked copy and the number of spikes."""
    rng = np.random.default_rng(seed)
    grid = np.zeros(values.shape, bool)
    grid[tuple(slice(1, None, 3) for _ in values.shape)] = True
    spots = np.flatnonzero(grid)
    chosen = rng.choice(spots, size=int(share * values.size), replace=False)
    out = values.copy().ravel()
    out[chosen] += height * rng.choice([-1.0, 1.0], size=chosen.size)
    return out.reshape(values.shape), chosen.size


# -- labels ------------------------------------------------------------------------------------

def test_a_checkerboard_is_all_isolated():
    assert isolated_fraction(np.indices((5, 6, 7)).sum(axis=0) % 2) == 1.0
    assert isolated_fraction(np.indices((4, 9)).sum(axis=0) % 2) == 1.0


def test_one_odd_voxel_in_a_block_is_one_voxel_in_n():
    vol = np.zeros((5, 6, 7), np.uint8)
    vol[2, 3, 4] = 3
    assert isolated_fraction(vol) == 1 / vol.size
    vol[2, 3, 4], vol[0, 0, 0] = 0, 3  # in a corner, with 3 neighbours inside
    assert isolated_fraction(vol) == 1 / vol.size
    vol[0, 0, 1] = 3  # a pair shares its label: neither is isolated
    assert isolated_fraction(vol) == 0.0


def test_a_thin_layer_is_not_speckle():
    vol = np.zeros((6, 6, 6), np.int32)
    vol[3] = 1  # one voxel thick, but every voxel has neighbours alike within the layer
    assert isolated_fraction(vol) == 0.0
    assert isolated_fraction(np.zeros((4, 4))) == 0.0


def test_only_neighbours_inside_the_array_count():
    assert isolated_fraction(np.array([[[0, 1, 0, 1, 0]]])) == 1.0  # neighbours along x only
    assert isolated_fraction(np.array([[[5]]])) == 0.0  # no neighbour: nothing to be unlike


def test_random_labels_match_the_expected_isolated_share():
    """Voxel with k neighbours inside, each in the phase with probability p independently:
    isolated with probability p (1 - p)^k + (1 - p) p^k."""
    p, shape = 0.4, (30, 30, 30)
    vol = (np.random.default_rng(0).random(shape) < p).astype(np.uint8)
    k = sum(np.minimum(np.indices(shape)[a], shape[a] - 1 - np.indices(shape)[a]).clip(max=1) + 1
            for a in range(3))  # neighbours inside: 2 per axis, 1 on a face
    want = np.mean(p * (1 - p) ** k + (1 - p) * p ** k)
    sd = np.sqrt(want * (1 - want) / vol.size)  # an upper bound of sorts: the voxels are nearly independent
    assert isolated_fraction(vol) == pytest.approx(want, abs=5 * sd)


# -- grey levels -------------------------------------------------------------------------------

def test_the_threshold_is_the_exemplar_s_quantile_of_neighbour_steps():
    exemplar = np.array([[0.0, 1.0, 3.0]])
    assert contrast_threshold(exemplar, quantile=1.0) == 2.0
    assert contrast_threshold(exemplar, quantile=0.5) == 1.5
    steps = np.concatenate([np.abs(np.diff(_smooth((20, 30), 1), axis=a)).ravel() for a in (0, 1)])
    assert contrast_threshold(_smooth((20, 30), 1)) == np.quantile(steps, 0.99)


def test_a_clean_smooth_image_has_no_isolated_pixels():
    exemplar = _smooth((128, 128), seed=2)
    assert isolated_contrast_fraction(_smooth((128, 128), seed=3), exemplar) == 0.0
    assert isolated_contrast_fraction(_smooth((32, 32, 32), seed=4), exemplar) == 0.0


@pytest.mark.parametrize("shape", [(96, 96), (24, 24, 24)])
def test_injected_spikes_score_their_share(shape):
    exemplar = _smooth((128, 128), seed=5)
    spiked, n = _with_spikes(_smooth(shape, seed=6), 0.02, height=5.0, seed=7)
    assert n > 0
    assert isolated_contrast_fraction(spiked, exemplar) == n / spiked.size


def test_a_sharp_edge_is_not_speckle():
    """With a constant exemplar the threshold is 0: any step counts, yet the voxels on either
    side of an edge each have a neighbour alike."""
    flat = np.full((16, 16), 7.0)
    step = np.zeros((16, 16))
    step[:, 8:] = 50.0
    assert isolated_contrast_fraction(step, flat) == 0.0
    step[4, 2] = 50.0  # a lone spike in the low half
    assert isolated_contrast_fraction(step, flat) == 1 / step.size


# -- slice by slice ----------------------------------------------------------------------------

def test_one_speckled_slice_stands_out_in_its_view():
    vol = np.zeros((6, 8, 8), np.uint8)
    vol[3] = np.indices((8, 8)).sum(axis=0) % 2  # a checkerboard slice in a constant block
    front = isolated_fraction_by_slice(vol, "front")
    np.testing.assert_array_equal(front, [0, 0, 0, 1, 0, 0])
    # Across it, each slice sees one row of alternating labels; only its ones are alone.
    right = isolated_fraction_by_slice(vol, "right")
    assert right.shape == (8,) and np.all(right == 4 / 48)


def test_grey_slices_are_measured_against_the_exemplar():
    exemplar = _smooth((64, 64), seed=8)
    vol = _smooth((8, 32, 32), seed=9)
    vol[5], n = _with_spikes(vol[5], 0.03, height=5.0, seed=10)
    got = isolated_fraction_by_slice(vol, "front", exemplar=exemplar)
    want = np.zeros(8)
    want[5] = n / (32 * 32)
    np.testing.assert_array_equal(got, want)


# -- validation --------------------------------------------------------------------------------

def test_bad_arguments_are_refused_with_their_name():
    with pytest.raises(InputError, match="quantile=0"):
        isolated_contrast_fraction(np.zeros((4, 4)), np.zeros((4, 4)), quantile=0)
    with pytest.raises(InputError, match="no pair of neighbours"):
        contrast_threshold(np.zeros((1, 1)))
    with pytest.raises(InputError, match="labels"):
        isolated_fraction(np.zeros((2, 2, 2, 2)))
    with pytest.raises(InputError, match="NaN"):
        isolated_fraction(np.array([[0.0, np.nan]]))
    with pytest.raises(InputError, match="view='side'"):
        isolated_fraction_by_slice(np.zeros((3, 3, 3)), "side")


def test_a_periodic_volume_has_its_neighbours_across_the_faces():
    from clsolid.metrics import isolated_contrast_fraction, isolated_fraction

    labels = np.zeros((4, 5, 6), int)
    labels[0, 2, 2] = labels[3, 2, 2] = 1  # a pair across the z faces: alike only if the block wraps
    assert isolated_fraction(labels) == pytest.approx(2 / labels.size)
    assert isolated_fraction(labels, periodic=True) == 0.0
    grey = labels * 100.0
    assert isolated_contrast_fraction(grey, grey[0], periodic=True) == 0.0
    assert isolated_contrast_fraction(grey, np.arange(16.0).reshape(4, 4)) == pytest.approx(2 / labels.size)
