"""3D properties of a segmented volume (clsolid.metrics.solid): surface area, S2 along each
axis, spanning clusters and the tortuosity factor, on volumes whose answer is known by hand."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi

from clsolid.errors import InputError
from clsolid.metrics import (connected_fraction, s2_error, specific_surface_area, tortuosity_factor,
                             two_point_correlation_axes, volume_fractions)


def _checkerboard(shape: tuple[int, ...]) -> np.ndarray:
    return (np.indices(shape).sum(axis=0) % 2).astype(np.uint8)


def _serpentine() -> tuple[np.ndarray, int]:
    """A one-voxel path across 5 layers along z that turns sideways for 3 voxels mid-block:
    8 voxels in series, so its resistance is 8 (7 links of 1, two half-voxel ends of 1/2)."""
    vol = np.zeros((5, 3, 5), np.uint8)
    for z, y, x in [(0, 0, 0), (1, 0, 0), (2, 0, 0), (2, 0, 1), (2, 0, 2), (2, 0, 3), (3, 0, 3), (4, 0, 3)]:
        vol[z, y, x] = 1
    return vol, 8


def _gaussian_phases(shape: tuple[int, ...], sigma: float, seed: int) -> np.ndarray:
    """Two phases (0, 255) of a periodic Gaussian field thresholded at its median."""
    field = ndi.gaussian_filter(np.random.default_rng(seed).standard_normal(shape), sigma, mode="wrap")
    return np.where(field > np.median(field), 255, 0).astype(np.uint8)


# -- volume fractions --------------------------------------------------------------------------

def test_volume_fractions_already_measure_volumes():
    vol = np.random.default_rng(0).integers(0, 3, (4, 5, 6))
    want = [np.mean(vol == k) for k in range(3)]
    np.testing.assert_allclose(volume_fractions(vol, 3), want, rtol=0, atol=1e-15)


# -- specific surface area ---------------------------------------------------------------------

def test_a_slab_has_two_faces_of_the_block_s_cross_section():
    vol = np.zeros((8, 8, 8), np.uint8)
    vol[2:5] = 1
    assert specific_surface_area(vol, 1) == 2 * 64 / 512
    assert specific_surface_area(vol, 0) == 2 * 64 / 512
    vol[:] = 0
    vol[:3] = 1  # on the block's face: that face is not an interface
    assert specific_surface_area(vol, 1) == 64 / 512


def test_a_single_voxel_has_six_faces_inside_and_three_in_a_corner():
    vol = np.zeros((5, 6, 7), np.int16)
    vol[2, 3, 4] = 7
    assert specific_surface_area(vol, 7) == 6 / vol.size
    vol[:] = 0
    vol[0, 0, 0] = 7
    assert specific_surface_area(vol, 7) == 3 / vol.size
    assert specific_surface_area(vol, 9) == 0.0  # an absent phase has no surface


def test_a_checkerboard_is_all_interface():
    assert specific_surface_area(_checkerboard((6, 6, 6)), 1) == 3 * 5 * 36 / 216
    assert specific_surface_area(_checkerboard((6, 8)), 0) == (5 * 8 + 6 * 7) / 48  # edges per pixel in 2D


# -- two-point correlation along each axis -----------------------------------------------------

def test_layers_normal_to_z_give_a_periodic_s2_along_z_and_a_flat_one_across():
    z = np.arange(16)
    vol = np.broadcast_to(((z % 4) < 2)[:, None, None], (16, 5, 6)).astype(np.uint8)  # 2 on, 2 off
    s2_z, s2_y, s2_x = two_point_correlation_axes(vol, 1)
    assert s2_z.shape == (16,) and s2_y.shape == (5,) and s2_x.shape == (6,)
    np.testing.assert_array_equal(s2_y, 0.5)
    np.testing.assert_array_equal(s2_x, 0.5)
    np.testing.assert_array_equal(s2_z[0::4], 0.5)  # a whole period: every pair in phase twice in four
    np.testing.assert_array_equal(s2_z[2::4], 0.0)  # half a period: never both in the phase
    # Lag 1: the pairs (z, z + 1) with z % 4 == 0, among the 15 that fit; lag 3: z % 4 == 1 among 13.
    assert s2_z[1] == pytest.approx(4 / 15, abs=1e-15) and s2_z[3] == pytest.approx(3 / 13, abs=1e-15)


def test_each_curve_is_the_plain_count_along_its_axis():
    vol = np.random.default_rng(1).integers(0, 2, (5, 6, 7))
    curves = two_point_correlation_axes(vol, 1, max_lag=3)
    for axis, curve in enumerate(curves):
        a = np.moveaxis(vol == 1, axis, 0)
        want = [np.mean(a[:a.shape[0] - r] & a[r:]) for r in range(4)]
        np.testing.assert_allclose(curve, want, rtol=0, atol=1e-15)
        assert curve[0] == np.mean(vol == 1)
    assert [c.size for c in two_point_correlation_axes(vol, 1, max_lag=100)] == [5, 6, 7]  # clipped per axis
    assert len(two_point_correlation_axes(vol[0], 1)) == 2  # an image: along rows, then columns


def test_s2_error_is_the_largest_gap_in_percent_of_the_fraction():
    assert s2_error([0.5, 0.3, 0.25], [0.5, 0.26, 0.25, 0.25]) == pytest.approx(8.0)  # 0.04 / 0.5
    assert s2_error([0.5, 0.3], [0.5, 0.26], fraction=0.4) == pytest.approx(10.0)
    assert s2_error([0.2, 0.1], [0.2, 0.1]) == 0.0
    with pytest.raises(InputError, match="fraction"):
        s2_error([0.1, 0.0], [0.0, 0.0])  # the reference lacks the phase: no scale
    with pytest.raises(InputError, match="s2"):
        s2_error([[0.5]], [0.5])


def test_random_phases_follow_the_independent_voxel_formulas():
    """Independent voxels in the phase with probability p: S2(r >= 1) = p^2 and a face is an
    interface with probability 2p(1 - p)."""
    p, n = 0.3, 32
    vol = (np.random.default_rng(2).random((n, n, n)) < p).astype(np.uint8)
    f = vol.mean()
    for curve in two_point_correlation_axes(vol, 1, max_lag=8):
        assert curve[0] == f
        # S2(r) averages about n^3 pairs, of standard deviation p sqrt(1 - p^2) each.
        np.testing.assert_allclose(curve[1:], p * p, atol=4 * p / n ** 1.5)
    want = 3 * 2 * p * (1 - p) * (n - 1) / n
    assert specific_surface_area(vol, 1) == pytest.approx(want, rel=0.02)


def test_a_thresholded_gaussian_field_is_alike_along_every_axis():
    vol = _gaussian_phases((40, 40, 40), 2.0, seed=3)
    curves = two_point_correlation_axes(vol, 255, max_lag=15)
    f = curves[0][0]
    assert f == pytest.approx(0.5, abs=1e-12)
    for curve in curves[1:]:
        assert s2_error(curve, curves[0]) < 5.0
    assert curves[0][-1] == pytest.approx(f * f, abs=0.05)  # decorrelated far beyond sigma


# -- connected fraction ------------------------------------------------------------------------

def test_only_the_rod_that_spans_the_block_is_connected():
    vol = np.zeros((6, 7, 8), np.uint8)
    vol[:, 3, 3] = 1  # a rod along z: spans z only
    vol[2, 5:7, 5:7] = 1  # a blob of 4 voxels touching the y face but not the other one
    assert connected_fraction(vol, 1, axis=0) == 6 / 10
    assert connected_fraction(vol, 1) == (6 / 10, 0.0, 0.0)
    vol[2, 0:7, 6] = 1  # the blob grows a bar across y (5 more voxels), joining both y faces
    assert connected_fraction(vol, 1) == pytest.approx((6 / 15, 9 / 15, 0.0), abs=1e-15)


def test_voxels_touching_only_by_edges_are_not_connected():
    stairs = np.zeros((4, 4, 4), np.uint8)
    for k in range(4):
        stairs[k, k, :] = 1  # each step meets the next along an edge only
    assert connected_fraction(stairs, 1, axis=0) == 0.0
    assert connected_fraction(stairs, 1, axis=2) == 1.0  # each step alone spans x
    assert np.isnan(connected_fraction(stairs, 5, axis=0))  # no voxel of the phase


def test_random_phases_percolate_well_above_the_threshold_and_not_below():
    rng = np.random.default_rng(4)
    dense = rng.random((24, 24, 24)) < 0.6  # site percolation threshold 0.3116 on the cubic lattice
    sparse = rng.random((24, 24, 24)) < 0.1
    assert min(connected_fraction(dense, True)) > 0.95
    assert max(connected_fraction(sparse, True)) == 0.0


# -- tortuosity factor -------------------------------------------------------------------------

@pytest.mark.parametrize("axis", [0, 1, 2])
def test_straight_channels_have_a_tortuosity_factor_of_one(axis):
    vol = np.zeros((6, 7, 8), np.uint8)
    cross = [slice(1, 3), slice(4, 5)]  # a 2-by-1 channel and, next, a 1-by-1 channel
    key = [slice(None)] * 3
    others = [a for a in range(3) if a != axis]
    key[others[0]], key[others[1]] = cross[0], cross[1]
    vol[tuple(key)] = 1
    key[others[0]] = 5
    vol[tuple(key)] = 1
    for solver in ("cg", "direct"):
        assert tortuosity_factor(vol, 1, axis, solver=solver) == pytest.approx(1.0, abs=1e-9)
    assert tortuosity_factor(vol, 1, others[0]) == np.inf  # channels do not cross the block that way


def test_a_block_filled_with_the_phase_has_a_tortuosity_factor_of_one():
    for shape in [(4, 5, 6), (1, 3, 3), (5, 7)]:
        full = np.ones(shape, np.uint8)
        for axis in range(len(shape)):
            assert tortuosity_factor(full, 1, axis) == pytest.approx(1.0, abs=1e-12)


def test_a_serpentine_path_has_the_square_of_its_length_ratio():
    """One path of P voxels across L layers: D_eff = L / (P A) and eps = P / (L A), so tau = (P / L)^2."""
    vol, length = _serpentine()
    want = (length / vol.shape[0]) ** 2
    assert tortuosity_factor(vol, 1, 0, solver="direct") == pytest.approx(want, rel=1e-12)
    assert tortuosity_factor(vol, 1, 0) == pytest.approx(want, rel=1e-8)
    # The same path along x: the answer does not depend on which axis carries it.
    assert tortuosity_factor(np.transpose(vol, (2, 1, 0)), 1, 2) == pytest.approx(want, rel=1e-8)
    assert tortuosity_factor(vol[::-1], 1, 0) == pytest.approx(want, rel=1e-8)  # nor on its direction


def test_parallel_paths_add_their_conductances():
    """A straight rod (resistance L) beside the serpentine (resistance P): F = 1/L + 1/P."""
    vol, p = _serpentine()
    vol[:, 2, 1] = 1  # apart from the serpentine, which lies in y = 0
    big_l = vol.shape[0]
    want = (big_l + p) / (big_l ** 2 * (1 / big_l + 1 / p))
    assert tortuosity_factor(vol, 1, 0, solver="direct") == pytest.approx(want, rel=1e-12)


def test_a_voxel_beside_the_inlet_feeds_the_path_through_the_inlet_face():
    """Layer 0 holds voxels a and b, layer 1 voxel c above a. The inlet face reaches a directly
    (conductance 2) and through b (2 in series with 1: 2/3), so inlet-to-outlet resistance is
    3/8 + 1 + 1/2 = 15/8; with L = 2, A = 2 and eps = 3/4, tau = (3/4) / (8/15) = 45/32."""
    image = np.array([[1, 1],
                      [1, 0]])
    assert tortuosity_factor(image, 1, 0, solver="direct") == pytest.approx(45 / 32, rel=1e-12)
    assert tortuosity_factor(image[:, None, :], 1, 0) == pytest.approx(45 / 32, rel=1e-8)


def test_clusters_that_do_not_span_count_in_the_fraction_but_carry_nothing():
    vol = np.zeros((5, 4, 4), np.uint8)
    vol[:, 1, 1] = 1
    vol[2, 3, 3] = 1  # an isolated voxel
    assert tortuosity_factor(vol, 1, 0) == pytest.approx(6 / 5, rel=1e-8)  # eps (L + 1) / (L A), D_eff 1 / A


def test_no_spanning_path_gives_infinity():
    vol = np.zeros((6, 6, 6), np.uint8)
    vol[:3, 2, 2] = vol[3:, 4, 4] = 1  # two half rods that never meet
    assert tortuosity_factor(vol, 1, 0) == np.inf
    assert tortuosity_factor(vol, 2, 0) == np.inf  # an absent phase


def test_a_random_structure_is_tortuous_and_the_solvers_agree():
    vol = _gaussian_phases((20, 20, 20), 1.5, seed=5)
    taus = [tortuosity_factor(vol, 255, axis, rtol=1e-10) for axis in range(3)]
    for axis, tau in enumerate(taus):
        assert tau > 1.0
        assert tortuosity_factor(vol, 255, axis, solver="direct") == pytest.approx(tau, rel=1e-7)
    assert max(taus) / min(taus) < 1.5  # an isotropic field: alike along every axis
    assert tortuosity_factor(np.flip(vol, 1), 255, 1, rtol=1e-10) == pytest.approx(taus[1], rel=1e-7)


# -- validation --------------------------------------------------------------------------------

def test_bad_arguments_are_refused_with_their_name():
    vol = np.ones((3, 3, 3))
    with pytest.raises(InputError, match="axis=3"):
        tortuosity_factor(vol, 1, 3)
    with pytest.raises(InputError, match="axis=True"):
        connected_fraction(vol, 1, axis=True)
    with pytest.raises(InputError, match="solver='lu'"):
        tortuosity_factor(vol, 1, 0, solver="lu")
    with pytest.raises(InputError, match="rtol=0"):
        tortuosity_factor(vol, 1, 0, rtol=0)
    with pytest.raises(InputError, match="phase='a'"):
        specific_surface_area(vol, "a")
    with pytest.raises(InputError, match="labels"):
        specific_surface_area(np.ones((2, 2, 2, 2)), 1)
    with pytest.raises(InputError, match="NaN"):
        connected_fraction(np.full((2, 2, 2), np.nan), 1)
    with pytest.raises(InputError, match="max_lag=-1"):
        two_point_correlation_axes(vol, 1, max_lag=-1)


def test_conjugate_gradients_that_stop_short_say_what_to_change():
    vol = _gaussian_phases((16, 16, 16), 1.5, seed=6)
    with pytest.raises(InputError, match="maxiter=2"):
        tortuosity_factor(vol, 255, 0, rtol=1e-12, maxiter=2)
