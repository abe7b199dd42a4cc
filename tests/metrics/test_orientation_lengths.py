"""The orientation field's own correlation length (clsolid.metrics.orientation_correlation_lengths)."""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

from clsolid.metrics import orientation_correlation_lengths
from clsolid.metrics.orientation import orientation_correlation, structure_tensor_orientation


def _wandering_stripes(scale: float, n: int = 128, seed: int = 0) -> np.ndarray:
    """Stripes of period 6 whose direction follows a smooth random field of correlation *scale*."""
    y, x = np.mgrid[:n, :n].astype(np.float64)
    angle = gaussian_filter(np.random.default_rng(seed).normal(size=(n, n)), scale, mode="wrap")
    angle *= 0.8 / angle.std()
    return np.cos(2 * np.pi / 6 * (x * np.cos(angle) + y * np.sin(angle)))


def test_orientation_that_wanders_slowly_stays_alike_longer():
    short = orientation_correlation_lengths(_wandering_stripes(4))
    long = orientation_correlation_lengths(_wandering_stripes(24))
    assert all(s < 4 for s in short) and all(g > 2 * s for g, s in zip(long, short))


def test_one_direction_everywhere_has_no_variation_to_correlate():
    y, x = np.mgrid[:40, :40].astype(np.float64)
    field = structure_tensor_orientation(np.cos(2 * np.pi * x / 8), periodic=True)
    assert np.all(np.isnan(orientation_correlation(field, 1, 5, periodic=True)))


def test_the_correlation_starts_at_one_and_the_slices_pool():
    image = _wandering_stripes(8, n=64)
    field = structure_tensor_orientation(np.stack([image, image.T]), periodic=True)
    rho = orientation_correlation(field, 2, 10, periodic=True)
    assert rho[0] == 1.0 and np.all(np.abs(rho) <= 1.0 + 1e-12) and rho[10] < rho[1]
    # a stack of an image and its transpose has the same lengths along both axes
    a, b = orientation_correlation_lengths(np.stack([image, image.T]), periodic=True)
    assert a == pytest.approx(b, rel=1e-9)
