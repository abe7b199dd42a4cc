"""Known-answer tests of clsolid.metrics: every metric against a case whose result is known."""

from __future__ import annotations

import json
import math
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage as ndi

from clsolid.errors import InputError
from clsolid.metrics import (autocorrelation, autocorrelation_distance, chord_lengths,
                             dominant_orientation_deg, evaluate, first_order_stats, histogram_distance,
                             lineal_path, orientation_histogram, patch_distance, quantise,
                             structure_tensor_orientation, symmetric_kl, trace_fringes,
                             two_point_cluster, two_point_correlation, view_slices, volume_fractions,
                             wasserstein_1d)
from clsolid.metrics.orientation import bin_centres_deg
from clsolid.metrics.references import exemplar_halves, shuffled_stack, size_factor


def gaussian_field(rng: np.random.Generator, shape: tuple, sigma: float) -> np.ndarray:
    """A stationary, periodic Gaussian random field with unit variance."""
    f = ndi.gaussian_filter(rng.standard_normal(shape), sigma, mode="wrap")
    return f / f.std()


def grating(angle_deg: float, period: float = 8.0, size: int = 64) -> np.ndarray:
    """cos stripes whose gradient points at ``angle_deg`` (counter-clockwise, y up)."""
    r, c = np.mgrid[:size, :size].astype(float)
    a = math.radians(angle_deg)
    return np.cos(2 * np.pi * (c * math.cos(a) - r * math.sin(a)) / period)


def bars(shape=(128, 128), length=24, width=4, row_step=8, col_step=32) -> np.ndarray:
    """Straight horizontal bars of known length on a periodic lattice."""
    img = np.zeros(shape)
    for r0 in range(2, shape[0] - width, row_step):
        for c0 in range(4, shape[1] - length, col_step):
            img[r0:r0 + width, c0:c0 + length] = 1.0
    return img


def _plain(obj) -> bool:
    """True when ``obj`` holds only JSON-native Python types."""
    if isinstance(obj, dict):
        return all(isinstance(k, str) and _plain(v) for k, v in obj.items())
    if isinstance(obj, list):
        return all(_plain(v) for v in obj)
    return obj is None or type(obj) in (bool, int, float, str)


# --------------------------------------------------------------------------- views


def test_view_slices_follow_the_orientation_conventions():
    z, y, x = np.meshgrid(np.arange(4), np.arange(5), np.arange(6), indexing="ij")
    vol = 100 * z + 10 * y + x
    front, right, top = (view_slices(vol, v) for v in ("front", "right", "top"))
    assert front.shape == (4, 5, 6) and right.shape == (6, 5, 4) and top.shape == (5, 4, 6)
    np.testing.assert_array_equal(front[2], vol[2])
    np.testing.assert_array_equal(right[3], vol[:, :, 3].T)  # rows = y, columns = z
    np.testing.assert_array_equal(top[1], vol[:, 1, :])  # rows = z, columns = x
    assert right[3][4, 2] == 100 * 2 + 10 * 4 + 3


def test_view_slices_subsample_evenly():
    vol = np.arange(20)[:, None, None] * np.ones((1, 3, 3))
    sub = view_slices(vol, "front", max_slices=4)
    np.testing.assert_array_equal(sub[:, 0, 0], [2, 7, 12, 17])  # centres of 4 blocks of 5
    assert len(view_slices(vol, "front", max_slices=50)) == 20


def test_view_slices_leave_out_the_excluded_ones_and_space_the_rest_evenly():
    vol = np.arange(20)[:, None, None] * np.ones((1, 3, 3))
    every = view_slices(vol, "front", exclude=[0, 5, 10, 15])
    np.testing.assert_array_equal(every[:, 0, 0], [i for i in range(20) if i % 5])
    sub = view_slices(vol, "front", max_slices=4, exclude=[0, 5, 10, 15])  # centres of 4 blocks of the 16 left
    np.testing.assert_array_equal(sub[:, 0, 0], [3, 8, 13, 18])
    np.testing.assert_array_equal(view_slices(vol, "front", 4, exclude=[]), view_slices(vol, "front", 4))
    with pytest.raises(InputError, match="0..19"):
        view_slices(vol, "front", exclude=[20])
    with pytest.raises(InputError, match="nothing is left"):
        view_slices(vol, "front", exclude=range(20))


def test_evaluate_excludes_slices_per_view_and_records_them():
    rng = np.random.default_rng(0)
    ex, vol = rng.random((32, 32)), rng.random((16, 16, 16))
    rep = evaluate(ex, vol, exclude={"right": [0, 7, 8]}, max_slices=None, reference_repeats=2)
    assert rep["views"]["right"]["slice_indices"] == [i for i in range(16) if i not in (0, 7, 8)]
    assert rep["views"]["front"]["slice_indices"] == list(range(16))
    assert rep["settings"]["excluded_slices"] == {"right": [0, 7, 8]}
    with pytest.raises(InputError, match="unknown views"):
        evaluate(ex, vol, exclude={"side": [1]}, reference_repeats=0)


@settings(max_examples=25, deadline=None)
@given(st.tuples(*(st.integers(1, 7),) * 3), st.sampled_from(["front", "right", "top"]),
       st.one_of(st.none(), st.integers(1, 8)))
def test_view_slices_shapes(shape, view, max_slices):
    vol = np.random.default_rng(0).random(shape)
    out = view_slices(vol, view, max_slices)
    axis = {"front": 0, "right": 2, "top": 1}[view]
    rows_cols = {"front": (shape[1], shape[2]), "right": (shape[1], shape[0]),
                 "top": (shape[0], shape[2])}[view]
    assert out.shape == (min(shape[axis], max_slices or shape[axis]), *rows_cols)


@pytest.mark.parametrize("bad", [{"view": "side"}, {"max_slices": 0}, {"max_slices": 2.0}])
def test_view_slices_refuses_bad_input(bad):
    kwargs = {"view": "front", **bad}
    with pytest.raises(InputError):
        view_slices(np.zeros((3, 3, 3)), **kwargs)
    with pytest.raises(InputError, match="3D"):
        view_slices(np.zeros((3, 3)), "front")


# --------------------------------------------------------------------------- first order


def test_first_order_stats_known_values():
    s = first_order_stats([1.0, 2.0, 3.0, 4.0])
    assert s["mean"] == 2.5 and s["mad"] == 1.0 and s["variance"] == 1.25
    assert s["std"] == pytest.approx(math.sqrt(1.25))
    assert s["skewness"] == pytest.approx(0.0)
    assert s["kurtosis"] == pytest.approx(2.5625 / 1.5625 - 3.0)  # excess kurtosis


def test_first_order_stats_of_known_distributions():
    rng = np.random.default_rng(1)
    g = first_order_stats(rng.standard_normal(400_000))
    assert abs(g["skewness"]) < 0.02 and abs(g["kurtosis"]) < 0.05  # excess: 0 for a Gaussian
    assert g["mad"] == pytest.approx(math.sqrt(2 / math.pi), rel=0.01)
    e = first_order_stats(rng.exponential(size=400_000))
    assert e["skewness"] == pytest.approx(2.0, rel=0.05) and e["kurtosis"] == pytest.approx(6.0, rel=0.1)
    flat = first_order_stats(np.full(10, 3.0))
    assert flat["variance"] == 0.0 and flat["skewness"] is None and flat["kurtosis"] is None


def test_quantise_keeps_existing_levels():
    levels = np.arange(8.0)
    np.testing.assert_array_equal(quantise(levels, 8, 0.0, 7.0), levels)
    np.testing.assert_array_equal(quantise([-5.0, 0.49, 0.51, 99.0], 2, 0.0, 1.0), [0, 0, 1, 1])


# --------------------------------------------------------------------------- histograms


def test_histogram_distance_known_value():
    # Bins are the grey levels 0 and 1; counts (2, 2) vs (4, 0), plus 0.5 per bin.
    p, q = np.array([0.5, 0.5]), np.array([0.9, 0.1])
    expected = float(np.sum((p - q) * np.log(p / q)))
    assert histogram_distance(np.array([[0, 0], [1, 1]]), np.zeros((1, 2, 2))) == pytest.approx(expected)
    assert expected == pytest.approx(np.sum(p * np.log(p / q)) + np.sum(q * np.log(q / p)))


def test_histogram_distance_identical_and_symmetric():
    rng = np.random.default_rng(2)
    a, b = rng.integers(0, 50, (32, 32)), rng.integers(0, 40, (32, 32))
    assert histogram_distance(a, a[None]) == 0.0
    assert histogram_distance(a, b) == pytest.approx(histogram_distance(b, a))
    assert histogram_distance(a, b, bins=10, value_range=(0, 50)) > 0


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(0.0, 1.0), min_size=4, max_size=64),
       st.lists(st.floats(0.0, 1.0), min_size=4, max_size=64))
def test_histogram_distance_is_finite_and_non_negative(a, b):
    d = histogram_distance(np.array(a)[None], np.array(b)[None])
    assert math.isfinite(d) and d >= 0.0


def test_histogram_distance_refuses_bad_range():
    with pytest.raises(InputError, match="value_range"):
        histogram_distance(np.zeros((4, 4)), np.zeros((1, 4, 4)), value_range=(1.0, 1.0))
    with pytest.raises(InputError, match="bins"):
        histogram_distance(np.zeros((4, 4)), np.zeros((1, 4, 4)), bins=0)


def test_symmetric_kl_and_wasserstein_small_cases():
    assert symmetric_kl([0.5, 0.5], [0.5, 0.5]) == 0.0
    assert wasserstein_1d([0.0, 1.0], [2.0, 3.0]) == pytest.approx(2.0)
    assert wasserstein_1d([0.0, 10.0], [0.0], [1.0, 0.0], [1.0]) == pytest.approx(0.0)


# --------------------------------------------------------------------------- autocorrelation


def test_autocorrelation_of_a_grating_is_its_cosine():
    img = grating(0.0, period=8.0, size=128)  # varies along columns only
    acf = autocorrelation(img, lags=32)
    assert acf.shape == (65, 65) and acf[32, 32] == pytest.approx(1.0)
    dx = np.arange(-32, 33)
    np.testing.assert_allclose(acf[32], np.cos(2 * np.pi * dx / 8), atol=0.02)  # finite overlaps
    np.testing.assert_allclose(acf[:, 32], 1.0, atol=1e-9)  # constant along rows


def test_autocorrelation_clips_lags_and_handles_flat_images():
    assert autocorrelation(np.random.default_rng(0).random((20, 50)), lags=32).shape == (21, 51)
    np.testing.assert_array_equal(autocorrelation(np.ones((10, 10)), lags=3), np.ones((7, 7)))


def test_autocorrelation_of_white_noise_is_a_spike():
    acf = autocorrelation(np.random.default_rng(3).standard_normal((128, 128)), lags=8)
    off = acf.copy()
    off[8, 8] = 0.0
    assert np.abs(off).max() < 0.05


def test_autocorrelation_distance_tells_structure_from_shuffle():
    rng = np.random.default_rng(4)
    vol = gaussian_field(rng, (16, 96, 96), 2.0)
    ex = gaussian_field(rng, (1, 64, 64), 2.0)[0]
    # Slices larger than the exemplar; a window of 8 lags holds this texture's correlations
    # (at 32 lags, the estimation noise of a 64x64 exemplar dominates: see evaluate's floor).
    same = autocorrelation_distance(ex, vol, lags=8)
    shuffled = autocorrelation_distance(ex, rng.permutation(vol.ravel()).reshape(vol.shape), lags=8)
    assert same < 0.5 * shuffled
    assert autocorrelation_distance(ex, ex) == pytest.approx(0.0, abs=1e-12)


# --------------------------------------------------------------------------- orientation


@pytest.mark.parametrize("angle", [-60.0, 0.0, 30.0, 75.0])
def test_grating_orientation_peaks_at_its_angle(angle):
    field = structure_tensor_orientation(grating(angle))
    assert dominant_orientation_deg(field) == pytest.approx(angle, abs=2.0)
    hist = orientation_histogram(field)
    peak = bin_centres_deg()[np.argmax(hist)]
    assert abs((peak - angle + 90) % 180 - 90) <= 5.0  # within one 5-degree bin
    assert np.median(field.coherence) > 0.9


def test_orientation_is_periodic_and_flat_images_have_no_orientation():
    field = structure_tensor_orientation(grating(90.0), periodic=True)
    assert field.theta.shape == (1, 64, 64)
    assert abs(abs(dominant_orientation_deg(field)) - 90.0) < 2.0
    flat = structure_tensor_orientation(np.ones((20, 20)))
    assert np.all(flat.coherence == 0.0) and dominant_orientation_deg(flat) is None


# --------------------------------------------------------------------------- fringes


@pytest.mark.parametrize("periodic", [True, False])
def test_straight_fringes_have_their_length_and_tortuosity_one(periodic):
    f = trace_fringes(bars(), level=0.5, periodic=periodic, max_extent=40)
    assert len(f.lengths) == 16 * 4
    np.testing.assert_allclose(f.lengths, 24.0, atol=0.5)
    np.testing.assert_allclose(f.tortuosities, 1.0, atol=0.01)


def test_periodic_fringes_are_counted_once_even_across_the_border():
    img = np.roll(bars(), (5, 17), axis=(0, 1))
    f = trace_fringes(img, level=0.5, periodic=True, max_extent=40)
    assert len(f.lengths) == 64 and np.all(f.weights == 1.0)
    cut = trace_fringes(img, level=0.5, periodic=False, max_extent=40)
    assert len(cut.lengths) < 64  # those cut by the border are discarded ...
    bbox = np.array([4, 24])  # ... and the rest weighted by H W / ((H - a)(W - b))
    np.testing.assert_allclose(cut.weights, 128 * 128 / np.prod(128 - bbox), rtol=0.02)


def test_a_bent_fringe_has_tortuosity_above_one():
    r, c = np.mgrid[:128, :128]
    radius, angle = np.hypot(r - 64, c - 64), np.arctan2(r - 64, c - 64)
    arc = ((radius > 28) & (radius < 32) & (angle > 0) & (angle < np.pi)).astype(float)
    f = trace_fringes(arc, level=0.5, max_extent=100)
    assert len(f.lengths) == 1
    # The centre line of a 4-px-thick half ring of radius 30 is pi * 30 long and its ends are
    # 60 apart (tortuosity pi / 2); the two-sides average cuts the thick ends' corners a little.
    assert f.lengths[0] == pytest.approx(np.pi * 30, rel=0.1)
    assert 1.35 < f.tortuosities[0] < np.pi / 2 + 0.05


def test_fringe_tracing_refuses_a_cap_larger_than_the_image():
    with pytest.raises(InputError, match="max_extent"):
        trace_fringes(np.zeros((16, 16)), max_extent=16)


# --------------------------------------------------------------------------- phases


def test_s2_of_stripes_matches_the_analytic_triangle():
    period, width = 8, 3
    labels = np.tile((np.arange(256) % period < width).astype(int), (64, 1))
    s2 = two_point_correlation(labels, phase=1, axis=1, max_lag=16)
    r = np.arange(17)
    d = np.minimum(r % period, period - r % period)
    np.testing.assert_allclose(s2, np.maximum(0, width - d) / period, atol=0.01)
    np.testing.assert_allclose(two_point_correlation(labels, 1, 0, 16), width / period)


def test_c2_of_stripes_stops_at_each_stripe():
    period, width = 8, 3
    labels = np.tile((np.arange(256) % period < width).astype(int), (64, 1))
    c2 = two_point_cluster(labels, phase=1, axis=1, max_lag=16)
    r = np.arange(17)
    np.testing.assert_allclose(c2, np.maximum(0, width - r) / period, atol=0.01)  # S2 comes back; C2 does not
    np.testing.assert_allclose(two_point_cluster(labels, 1, 0, 16), width / period)  # one stripe, one cluster


def _c2_by_pairs(image: np.ndarray, phase: int, r: int) -> float:
    """C2 of one image at a horizontal lag r, pair by pair, from its own 8-connected labels."""
    cluster, _ = ndi.label(image == phase, structure=np.ones((3, 3)))
    rows, cols = image.shape
    same = [cluster[i, j] > 0 and cluster[i, j] == cluster[i, j + r] for i in range(rows) for j in range(cols - r)]
    return float(np.mean(same))


def test_c2_of_a_stack_equals_each_image_alone():
    rng = np.random.default_rng(8)
    stack = (ndi.uniform_filter(rng.random((3, 20, 24)), (1, 3, 3)) > 0.52).astype(int)
    c2 = two_point_cluster(stack, 1, 1, 6)
    want = [np.mean([_c2_by_pairs(img, 1, r) for img in stack]) for r in range(7)]
    np.testing.assert_allclose(c2, want, atol=1e-12)  # clusters never join across images
    np.testing.assert_allclose(two_point_cluster(stack, 0, 0, 6),
                               two_point_cluster(np.swapaxes(stack, 1, 2), 0, 1, 6), atol=1e-12)
    assert np.all(c2 <= two_point_correlation(stack, 1, 1, 6) + 1e-12)


def test_c2_tells_a_broken_network_from_a_connected_one():
    """Scatter a third of a grain-boundary network's pixels: S2 at 8 pixels barely moves (it is
    near the fraction squared either way); C2 there falls to a third (the network is broken)."""
    from clsolid.gallery import gallery_exemplar

    net = (gallery_exemplar("grains", 128) > 0).astype(int)
    phase = int(np.argmin(np.bincount(net.ravel())))  # the boundaries, the minority phase
    rng = np.random.default_rng(0)
    broken = net.copy()
    on = np.flatnonzero(net.ravel() == phase)
    off = np.flatnonzero(net.ravel() != phase)
    moved = rng.choice(on, on.size // 3, replace=False)
    broken.ravel()[moved] = broken.ravel()[off[0]]
    broken.ravel()[rng.choice(off, moved.size, replace=False)] = phase
    s2 = [two_point_correlation(img, phase, 1, 8) for img in (net, broken)]
    c2 = [two_point_cluster(img, phase, 1, 8) for img in (net, broken)]
    np.testing.assert_allclose(c2[0], s2[0])  # one connected network: every pair is in it
    assert abs(s2[1][8] - s2[0][8]) < 0.1 * s2[0][8]
    assert c2[1][8] < 0.5 * c2[0][8]


def test_random_phases_give_the_independent_answers():
    phi = 0.3
    labels = (np.random.default_rng(5).random((64, 256, 256)) < phi).astype(int)
    np.testing.assert_allclose(volume_fractions(labels, 2), [1 - phi, phi], atol=0.002)
    s2 = two_point_correlation(labels, 1, 1, 5)
    assert s2[0] == pytest.approx(phi, abs=0.002)
    np.testing.assert_allclose(s2[1:], phi**2, atol=0.002)
    np.testing.assert_allclose(lineal_path(labels, 1, 0, 4), phi ** (np.arange(5) + 1), atol=0.002)
    lengths, weights = chord_lengths(labels, 1, 1)
    assert np.average(lengths, weights=weights) == pytest.approx(1 / (1 - phi), rel=0.01)  # geometric


def test_lineal_path_and_chords_of_a_known_row():
    row = np.array([[1, 1, 0, 1, 1, 1, 0, 0, 1, 0]])
    np.testing.assert_allclose(lineal_path(row, 1, 1, 3), [6 / 10, 3 / 9, 1 / 8, 0 / 7])
    lengths, weights = chord_lengths(row, 1, 1)
    np.testing.assert_array_equal(lengths, [3, 1])  # the run at the start touches the border
    np.testing.assert_allclose(weights, [10 / 6, 10 / 8])


# --------------------------------------------------------------------------- patches


def test_patch_distance_is_small_for_the_same_texture_and_large_for_shuffles():
    rng = np.random.default_rng(6)
    ex = gaussian_field(rng, (1, 64, 64), 1.5)[0]
    vol = gaussian_field(rng, (8, 64, 64), 1.5)
    same = patch_distance(ex, vol, rng=1)
    assert same == patch_distance(ex, vol, rng=1)  # fixed projections, seeded sampling
    assert same < 0.5 * patch_distance(ex, rng.permutation(vol.ravel()).reshape(vol.shape), rng=1)


# --------------------------------------------------------------------------- references


def test_halves_and_shuffles():
    rng = np.random.default_rng(7)
    ex = rng.random((40, 50))
    for a, b in exemplar_halves(ex, rng, 6):
        assert a.size + b.size == ex.size and 0.35 * ex.size < a.size < 0.65 * ex.size
    sh = shuffled_stack(ex, (40, 50), 3, rng)
    np.testing.assert_array_equal(np.sort(sh.ravel()), np.sort(np.tile(ex.ravel(), 3)))
    assert size_factor(1000, 1000, 2000, 10**9, 1.0) == pytest.approx(0.25, rel=1e-5)


# --------------------------------------------------------------------------- evaluate


@pytest.fixture(scope="module")
def field_case():
    rng = np.random.default_rng(0)
    ex = np.round(gaussian_field(rng, (8, 64, 64), 1.5)[4] * 30 + 128)
    vol = np.round(gaussian_field(rng, (48, 48, 48), 1.5) * 30 + 128)
    shuffled = rng.permutation(vol.ravel()).reshape(vol.shape)
    return ex, evaluate(ex, vol, rng=0), evaluate(ex, shuffled, rng=0)


def test_evaluate_is_plain_json_with_labelled_views(field_case):
    _, report, _ = field_case
    assert _plain(report)
    json.dumps(report, allow_nan=False)
    views = report["views"]
    assert list(views) == ["front", "right", "top"]
    assert [views[v]["constrained"] for v in views] == [True, True, False]
    assert views["top"]["label"] == "top (unconstrained)"
    d = views["front"]["distances"]["autocorrelation_l2"]
    assert set(d) >= {"value", "floor", "ceiling", "informative", "score", "note"}
    assert d["floor"]["halves"]["n"] == 5 and d["ceiling"]["kind"] == "shuffle"
    assert views["front"]["distances"]["histogram_kl"]["ceiling"]["kind"] == "noise"
    assert len(report["summary"]) == 3 * len(views["front"]["distances"])


def test_a_true_random_field_scores_near_the_floor_and_shuffles_near_the_ceiling(field_case):
    _, report, shuffled = field_case
    for view in ("front", "right", "top"):
        good = report["views"][view]["distances"]
        bad = shuffled["views"][view]["distances"]
        for key in ("autocorrelation_l2", "patch_sw", "histogram_kl"):
            assert good[key]["informative"], key
            assert good[key]["score"] < 0.5, (view, key, good[key])
        for key in ("autocorrelation_l2", "patch_sw"):
            assert bad[key]["score"] > 0.8, (view, key, bad[key])
        # Shuffling keeps the histogram: the shuffled volume stays at the histogram floor.
        assert bad["histogram_kl"]["score"] < 0.2


def test_white_noise_exemplar_makes_structure_distances_uninformative():
    rng = np.random.default_rng(1)
    report = evaluate(rng.random((64, 64)), rng.random((32, 32, 32)), views=["front"], rng=1)
    d = report["views"]["front"]["distances"]
    for key in ("autocorrelation_l2", "patch_sw", "orientation_kl"):
        assert d[key]["informative"] is False and d[key]["score"] is None
        assert "uninformative" in d[key]["note"]


def test_few_phase_exemplars_get_phase_metrics():
    rng = np.random.default_rng(2)
    ex = (gaussian_field(rng, (4, 48, 48), 2.0)[1] > 0.3).astype(np.uint8)
    vol = (gaussian_field(rng, (32, 32, 32), 2.0) > 0.3).astype(np.uint8)
    report = evaluate(ex, vol, views=["front"], reference_repeats=3)
    view = report["views"]["front"]
    assert {"volume_fraction_tv", "s2_l2", "c2_l2", "lineal_path_l2", "chord_length_w1"} <= set(view["distances"])
    assert view["phases"]["phase_values"] == [0.0, 1.0]
    assert view["distances"]["chord_length_w1"]["informative"]
    assert view["distances"]["chord_length_w1"]["score"] < 0.5


def test_levels_quantise_histograms_and_enable_phases():
    rng = np.random.default_rng(3)
    ex = gaussian_field(rng, (2, 40, 40), 2.0)[0]
    report = evaluate(ex, gaussian_field(rng, (16, 24, 24), 2.0), views=["top"], levels=2,
                      reference_repeats=0)
    assert report["settings"]["histogram"]["bins"] == 2
    assert "s2_l2" in report["views"]["top"]["distances"]
    d = report["views"]["top"]["distances"]["s2_l2"]
    assert d["floor"] is None and d["informative"] is None and d["score"] is None


@pytest.mark.parametrize("kwargs, match", [
    ({"views": ["side"]}, "views"), ({"constrained": "bottom"}, "constrained"), ({"levels": 1}, "levels"),
    ({"reference_repeats": 1}, "reference_repeats"), ({"max_slices": 0}, "max_slices"),
])
def test_evaluate_refuses_bad_parameters(kwargs, match):
    with pytest.raises(InputError, match=match):
        evaluate(np.zeros((16, 16)), np.zeros((8, 8, 8)), **kwargs)


def test_evaluate_refuses_bad_arrays():
    with pytest.raises(InputError, match="exemplar"):
        evaluate(np.zeros((16, 16, 3)), np.zeros((8, 8, 8)))
    with pytest.raises(InputError, match="volume"):
        evaluate(np.zeros((16, 16)), np.zeros((8, 8)))
    with pytest.raises(InputError, match="NaN"):
        evaluate(np.full((16, 16), np.nan), np.zeros((8, 8, 8)))


@pytest.mark.slow
def test_a_128_cube_is_evaluated_in_reasonable_time():
    rng = np.random.default_rng(4)
    vol = gaussian_field(rng, (128, 128, 128), 2.0).astype(np.float32)
    start = time.perf_counter()
    evaluate(vol[64], vol)
    assert time.perf_counter() - start < 60.0
