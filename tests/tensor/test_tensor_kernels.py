"""The tensor kernels (kernels/tensor/tensor.cl) against the float64 references."""

import numpy as np
import pytest

from clsolid.tensor import METRICS, neighbourhood_dissimilarity, structure_tensor
from clsolid.tensor.opencl import TensorMatcher
from clsolid.tensor.opencl import structure_tensor as device_structure_tensor


@pytest.fixture(scope="module")
def field():
    from skimage import data

    return structure_tensor(data.camera()[100:150, 200:260].astype(np.float64))


@pytest.mark.parametrize("boundary", ["reflect", "wrap"])
def test_the_field_on_the_device_matches_the_reference(device, boundary):
    from skimage import data

    image = data.camera()[100:150, 200:260].astype(np.float64)
    ref = structure_tensor(image, 1.2, 2.0, boundary)
    got = device_structure_tensor(device, image, 1.2, 2.0, boundary)
    assert got.shape == (50, 60, 3) and got.dtype == np.float32
    assert np.abs(got - ref).max() <= 1e-5 * np.abs(ref).max()


def test_a_flat_image_has_a_zero_field_on_the_device(device):
    assert np.all(device_structure_tensor(device, np.full((16, 20), 9.0)) == 0)


@pytest.mark.parametrize("metric", METRICS)
def test_neighbourhood_sums_and_best_matches_on_the_device(device, field, metric):
    rng = np.random.default_rng(0)
    flat = field.reshape(-1, 3)
    table, queries = flat[rng.choice(len(flat), (150, 9))], flat[rng.choice(len(flat), (40, 9))]
    weights = np.r_[np.ones(4), 0.0, 2.0 * np.ones(4)]
    eps = 1e-3 * float(np.mean(flat[:, 0] + flat[:, 2]))
    matcher = TensorMatcher(device, table, metric, alpha=0.6, eps=eps, weights=weights)
    ref = neighbourhood_dissimilarity(queries[:, None], table[None], metric, alpha=0.6, eps=eps, weights=weights)
    got = matcher.distances(queries)
    assert np.abs(got - ref).max() <= 1e-5 * np.abs(ref).max()
    site, dist = matcher.best(queries)
    # the device's best is the reference's, or within float32 rounding of it
    rows = np.arange(len(queries))
    assert np.all(ref[rows, site] <= ref.min(axis=1) + 1e-5 * np.abs(ref).max())
    assert np.mean(site == ref.argmin(axis=1)) >= 0.95
    np.testing.assert_allclose(dist, got[rows, site], rtol=1e-6)
