"""The stretch measure (clsolid.metrics.axes): correlation lengths along each axis, and how
much taller than wide a volume's features are against the exemplar's."""

import numpy as np
import pytest
from scipy import ndimage as ndi

from clsolid.errors import InputError
from clsolid.metrics import correlation_length, correlation_lengths, lag_correlations, stretch


def _field(shape, sigmas, seed=0):
    """Smoothed white noise: correlation lengths in proportion to *sigmas* (toroidal)."""
    noise = np.random.default_rng(seed).standard_normal(shape)
    return ndi.gaussian_filter(noise, sigmas, mode="wrap")


def test_pearson_lags_are_the_plain_formula():
    a = np.random.default_rng(1).standard_normal((20, 30))
    rho = lag_correlations(a, 1, 5)
    c = a - a.mean()
    want = [np.mean(c[:, :30 - k] * c[:, k:]) / np.mean(c * c) for k in range(6)]
    np.testing.assert_allclose(rho, want, rtol=1e-12)


def test_on_two_phases_the_phase_form_is_pearsons():
    """(P_same - sum f^2) / (1 - sum f^2) is the indicator's Pearson correlation on two phases,
    whatever values code them."""
    img = (_field((64, 64), 3) > 0.3).astype(np.uint8) * 255
    grey = lag_correlations(img, 0, 10)
    phases = lag_correlations(img, 0, 10, phases=[0, 255])
    np.testing.assert_allclose(phases, grey, atol=1e-12)
    three = np.digitize(_field((64, 64), 3), [-0.1, 0.1])  # three phases: not the codes' correlation
    by_codes = lag_correlations(np.array([1.0, 7.0, 8.0])[three], 1, 6)  # Pearson on uneven codes
    assert not np.allclose(lag_correlations(three, 1, 6, phases=[0, 1, 2]), by_codes)


def test_the_length_is_where_the_correlation_falls_to_a_half():
    assert correlation_length([1.0, 0.75, 0.25]) == pytest.approx(1.5)
    assert correlation_length([1.0, 0.5, 0.1]) == pytest.approx(1.0)
    assert correlation_length([1.0, 0.9, 0.8]) == np.inf  # beyond the lags given
    assert np.isnan(correlation_length([1.0, np.nan]))
    assert np.isnan(lag_correlations(np.ones((8, 8)), 0, 3)).all()  # nothing to correlate


def test_lengths_follow_the_smoothing():
    f = _field((40, 40, 40), (2.0, 4.0, 2.0))
    lz, ly, lx = correlation_lengths(f)
    assert ly / lz == pytest.approx(2.0, rel=0.15) and ly / lx == pytest.approx(2.0, rel=0.15)
    assert lz == pytest.approx(lx, rel=0.15)


@pytest.mark.parametrize("binary", [False, True])
def test_a_volume_drawn_out_along_y_has_its_factor(binary):
    exemplar = _field((96, 96), 3.0, seed=2)
    tall = _field((48, 48, 48), (3.0, 6.0, 3.0), seed=3)
    even = _field((48, 48, 48), 3.0, seed=4)
    if binary:  # as phases: the exemplar's two values, the volumes thresholded alike
        exemplar, tall, even = ((a > 0) * 255.0 for a in (exemplar, tall, even))
    got = stretch(exemplar, tall)
    assert set(got) == {"front", "right"}
    assert got["front"] == pytest.approx(2.0, rel=0.2) and got["right"] == pytest.approx(2.0, rel=0.2)
    assert all(v == pytest.approx(1.0, rel=0.15) for v in stretch(exemplar, even, ["front", "right", "top"]).values())


def test_an_elongated_exemplar_sets_the_proportions_to_keep():
    """Layers along x in the exemplar (tall ratio below 1): a volume with the same layers in
    both views keeps its proportions; an isotropic one is too tall for them."""
    exemplar = _field((96, 96), (2.0, 6.0), seed=5)
    layered = _field((48, 48, 48), (6.0, 2.0, 6.0), seed=6)
    assert stretch(exemplar, layered)["front"] == pytest.approx(1.0, rel=0.2)
    assert stretch(exemplar, _field((48, 48, 48), 3.0, seed=7))["front"] > 2.0


def test_features_longer_than_half_the_volume_are_infinitely_tall():
    exemplar = _field((64, 64), 3.0, seed=8)
    extruded = np.broadcast_to(_field((40, 1, 40), (3.0, 1.0, 3.0), seed=9), (40, 40, 40))  # the same along y
    assert stretch(exemplar, extruded) == {"front": np.inf, "right": np.inf}
    flat = np.broadcast_to(_field((1, 40, 1), (1.0, 3.0, 1.0), seed=10), (40, 40, 40))  # layers along y only
    assert stretch(exemplar, flat) == {"front": 0.0, "right": 0.0}
    assert np.isnan(stretch(exemplar, np.ones((8, 8, 8)))["front"])  # a constant volume: nothing to say


def test_bad_input_is_refused():
    with pytest.raises(InputError, match="axis"):
        lag_correlations(np.zeros((4, 4)), 2, 1)
    with pytest.raises(InputError, match="max_lag"):
        lag_correlations(np.zeros((4, 4)), 0, 4)
    with pytest.raises(InputError, match="2-D and the volume 3-D"):
        stretch(np.zeros((4, 4, 4)), np.zeros((4, 4, 4)))
    with pytest.raises(InputError, match="views"):
        stretch(np.zeros((8, 8)), np.zeros((8, 8, 8)), ["side"])
