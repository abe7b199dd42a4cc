"""The mismatch distances: phases compared as names, not numbers (``distance="mismatch"`` and
``"weighted"``, the default for categorical exemplars).

The kernels are checked against the float64 reference in test_kernels and test_pruned (both
distances); here: what the distance is, that on two levels it is the squared one, that it
does not care which value a phase carries, and how ``"auto"`` resolves.
"""

import numpy as np
import pytest
from conftest import slow_except

import clsolid
from clsolid.errors import InputError
from clsolid.gallery import gallery_exemplar
from clsolid.ml import pruned
from clsolid.ml.model import build_scale, difference, phase_sigma, scale_exemplar
from clsolid.phases import phase_costs
from clsolid.ml.params import MLParams
from clsolid.ml.reference import ReferenceBackend, site_distances

SHAPE = (6, 8, 10)


def _labels(name: str) -> np.ndarray:
    ex = gallery_exemplar(name, 64)
    return np.searchsorted(np.unique(ex), ex).astype(np.uint8)


def _lcpdf(labels_img, vol, temp, voxels, **kw):
    params = MLParams(scales=1, neighborhood=5, **kw)
    model = build_scale(labels_img, SHAPE, params, 0)
    ref = ReferenceBackend()
    ref.start_scale(model, vol, temp, params)
    return model, ref.lcpdf(voxels)


def test_difference_is_squared_a_mismatch_or_a_weighted_one():
    a, b = np.array([0, 1, 2, 2]), np.array([2, 1, 0, 1])
    np.testing.assert_array_equal(difference(a, b, False), [4, 0, 4, 1])
    np.testing.assert_array_equal(difference(a, b, True), [1, 0, 1, 1])
    np.testing.assert_array_equal(difference(a, b, True, np.array([1.0, 10.0, 100.0])), [101, 0, 101, 110])


def test_phase_costs_are_half_inverse_fractions_and_distinct():
    img = np.repeat(np.array([0, 1, 2, 3]), [50, 30, 10, 10])
    costs = phase_costs(img)
    assert costs.dtype == np.float32
    np.testing.assert_allclose(costs, [1.0, 0.5 / 0.3, 5.0, 5.0], rtol=1e-6)
    assert costs[2] != costs[3]  # equal fractions, told apart


def test_mismatch_counts_differing_neighbours_weighted_by_temperature():
    labels_img = _labels("composite3")[:24, :24]
    model = build_scale(labels_img, SHAPE, MLParams(scales=1, neighborhood=3, distance="mismatch"), 0)
    rng = np.random.default_rng(0)
    vol = rng.integers(0, 3, SHAPE).astype(float)
    temp = rng.random(SHAPE)
    a = site_distances(model, vol, temp, np.array([0]), 0)[0]
    from clsolid.ml.model import wrapped_coords

    nb = wrapped_coords(np.array([0]), SHAPE, model.offsets[0])[0]
    site = 17
    want = sum((1 - temp.ravel()[j]) ** 2 for j, p in zip(nb, model.patches[:, site]) if vol.ravel()[j] != p)
    assert a[site] == pytest.approx(want)


def test_phase_sigma_of_two_levels_is_their_standard_deviation():
    img = (np.random.default_rng(2).random((40, 40)) < 0.3).astype(np.uint8)
    assert phase_sigma(img) == pytest.approx(img.std())
    three = np.repeat(np.arange(3), 100).reshape(30, 10)
    assert phase_sigma(three) == pytest.approx(np.sqrt((1 - 3 / 9) / 2))


@pytest.mark.parametrize("distance", ["mismatch", "weighted"])
def test_on_two_levels_every_distance_is_the_same_likelihood(distance):
    labels_img = _labels("porous50")[:24, :24]
    rng = np.random.default_rng(1)
    vol = rng.integers(0, 2, SHAPE).astype(float)
    temp = rng.random(SHAPE) * 0.5
    voxels = np.arange(0, vol.size, 5)
    m1, sq = _lcpdf(labels_img, vol, temp, voxels, distance="squared")
    m2, mm = _lcpdf(labels_img, vol, temp, voxels, distance=distance)
    if distance == "mismatch":  # same units; weighted: the units differ, the bandwidth follows
        assert m1.bandwidth == pytest.approx(m2.bandwidth)
    np.testing.assert_allclose(mm, sq, rtol=1e-6, atol=1e-6)  # the costs are float32


@pytest.mark.parametrize("distance, same", [("mismatch", True), ("weighted", True), ("squared", False)])
def test_renaming_the_phases_renames_the_likelihood(distance, same):
    """Which value a phase carries is the user's choice: with mismatches, permuting the values
    of the exemplar and of the volume permutes the log LCPDF's labels and nothing else."""
    labels_img = _labels("composite4")[:32, :32]
    perm = np.array([0, 3, 1, 2])  # phase i is called perm[i]
    rng = np.random.default_rng(3)
    vol = rng.integers(0, 4, SHAPE).astype(float)
    temp = rng.random(SHAPE) * 0.5
    voxels = np.arange(0, vol.size, 4)
    _, base = _lcpdf(labels_img, vol, temp, voxels, distance=distance)
    _, renamed = _lcpdf(perm[labels_img], perm[vol.astype(int)].astype(float), temp, voxels, distance=distance)
    # renamed[..., perm[i]] is the same label as base[..., i]
    assert np.allclose(renamed[..., perm], base, rtol=1e-12, atol=1e-9) == same


def test_phase_pyramid_keeps_the_phases_that_grey_averaging_invents_or_loses():
    """composite4: averaging the values of matrix (0) and particles (3) gives the grains' 1 or
    the rods' 2; smoothing each phase's indicator keeps the fractions at the first coarse scale."""
    labels_img = _labels("composite4")
    fine = np.bincount(labels_img.ravel(), minlength=4) / labels_img.size
    grey = scale_exemplar(labels_img, 1, "binomial")
    phases = scale_exemplar(labels_img, 1, "binomial", phases=True)
    assert phases.shape == grey.shape == (32, 32)
    assert np.abs(np.bincount(phases.ravel(), minlength=4) / phases.size - fine).max() < 0.02
    assert np.abs(np.bincount(grey.ravel(), minlength=4) / grey.size - fine).max() > 0.1
    # renaming the phases renames the coarse exemplar, but where two phases tie (the lowest wins)
    from scipy.ndimage import correlate1d

    share = np.stack([(labels_img == p).astype(float) for p in range(4)])
    for axis in (1, 2):
        share = correlate1d(share, [0.25, 0.5, 0.25], axis=axis, mode="nearest")
    share = np.sort(share[:, ::2, ::2], axis=0)
    untied = share[-1] > share[-2]
    assert untied.mean() > 0.95
    np.testing.assert_array_equal(share[-1][untied] > 0, True)
    perm = np.array([2, 0, 3, 1])
    renamed = scale_exemplar(perm[labels_img], 1, "binomial", phases=True)
    np.testing.assert_array_equal(renamed[untied], perm[phases][untied])


def test_phase_pyramid_on_two_levels_is_the_grey_one():
    labels_img = _labels("cracks")
    for level in (1, 2):
        np.testing.assert_array_equal(scale_exemplar(labels_img, level, "binomial", phases=True),
                                      scale_exemplar(labels_img, level, "binomial"))


@pytest.mark.parametrize("distance", ["mismatch", "weighted"])
def test_similar_windows_follow_the_mismatch_count(distance):
    labels_img = _labels("composite3")[:20, :20]
    model = build_scale(labels_img, SHAPE, MLParams(scales=1, neighborhood=3, distance=distance), 0)
    table = pruned.window_table(model, 5)
    rows = model.patches.T[table.first_site]
    d = difference(rows[:, None, :], rows[None, :, :], True, model.costs).sum(-1)
    np.fill_diagonal(d, np.inf)
    want = np.lexsort((np.broadcast_to(np.arange(d.shape[0]), d.shape), d), axis=1)[:, :4]
    np.testing.assert_array_equal(table.similar[:, 1:], want)


@pytest.mark.parametrize("name, levels, want", slow_except([
    ("composite3", 32, "weighted"), ("porous50", 32, "mismatch"), ("brick", 32, "squared"),
    ("composite3", 2, "squared")], 0))
def test_auto_counts_mismatches_on_categorical_exemplars(device, name, levels, want):
    ex = gallery_exemplar(name, 64)
    res = clsolid.synthesize(ex, (8, 8, 8), rng=1, device=device, scales=1, neighborhood=3, levels=levels,
                             max_sweeps=1, full_output=True)
    assert res.params["distance"] == want


@pytest.mark.parametrize("name, levels, given, want", slow_except([
    ("brick", 32, None, 3.0), ("composite3", 32, None, 0.0), ("composite3", 2, None, 3.0), ("brick", 32, 0, 0.0),
    ("porous50", 32, 1.5, 1.5)], 0))
def test_auto_falloff_on_grey_exemplars_only(device, name, levels, given, want):
    """The fall-off resolves like the distance: sigma 3 on grey exemplars (a quantised
    categorical one included), none on categorical ones; a given value is kept."""
    ex = gallery_exemplar(name, 64)
    res = clsolid.synthesize(ex, (8, 8, 8), rng=1, device=device, scales=1, neighborhood=3, levels=levels,
                             max_sweeps=1, full_output=True, **({} if given is None else {"falloff": given}))
    assert res.params["falloff"] == want


@pytest.mark.parametrize("bad", [-1.0, float("nan"), float("inf"), "3", True])
def test_bad_falloff_is_refused(bad):
    with pytest.raises(InputError, match="falloff"):
        MLParams(falloff=bad)


def test_bad_distance_is_refused():
    with pytest.raises(InputError, match="distance"):
        MLParams(distance="hamming")
    with pytest.raises(InputError, match="0..L-1"):  # the kernels look costs up by label
        build_scale(np.array([[0, 2], [2, 0]] * 8).reshape(8, 4), (4, 4, 4),
                    MLParams(scales=1, neighborhood=3, distance="weighted"), 0)
