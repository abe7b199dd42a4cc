"""The structure tensor field (clsolid.tensor.field) against known answers: ramps, stripes of
a known direction, the transpose, and the eigen-decomposition's logarithm."""

import numpy as np
import pytest

from clsolid.errors import InputError
from clsolid.tensor import coherence, log_tensor, orientation, structure_tensor
from clsolid.tensor.field import eigen, gaussian_taps


def test_the_derivative_kernel_gives_a_ramp_its_slope():
    assert gaussian_taps(1.5).sum() == pytest.approx(1.0)
    y, x = np.mgrid[:40, :40].astype(np.float64)
    s = structure_tensor(2.0 * x - 3.0 * y, grad_sigma=1.0, window_sigma=1.0)
    inner = s[8:-8, 8:-8]  # away from the mirrored edges, where the ramp folds
    np.testing.assert_allclose(inner[..., 0], 4.0, rtol=1e-12)
    np.testing.assert_allclose(inner[..., 1], -6.0, rtol=1e-12)
    np.testing.assert_allclose(inner[..., 2], 9.0, rtol=1e-12)


@pytest.mark.parametrize("kx, ky", [(4, 0), (4, 3), (-2, 5), (0, 3)])
def test_stripes_have_their_gradients_direction_and_full_coherence(kx, ky):
    """Periodic stripes cos(k . p) (wrapped): every gradient is parallel to k, so the tensor
    has rank one (C = 1) and O is k's direction, modulo pi (to the sampled kernels'
    transfer functions, which turn an oblique k by under a milliradian)."""
    y, x = np.mgrid[:64, :64].astype(np.float64)
    image = np.cos(2 * np.pi * (kx * x + ky * y) / 64)
    s = structure_tensor(image, boundary="wrap")
    np.testing.assert_allclose(coherence(s), 1.0, atol=1e-9)
    want = np.arctan2(ky, kx)
    diff = np.angle(np.exp(2j * (orientation(s) - want)))  # twice the difference, wrapped: modulo pi
    np.testing.assert_allclose(diff, 0.0, atol=2e-3)


def test_the_transposed_image_has_the_transposed_field():
    image = np.random.default_rng(0).normal(size=(30, 36))
    s = structure_tensor(image)
    t = structure_tensor(image.T)
    np.testing.assert_allclose(t, s.transpose(1, 0, 2)[..., ::-1], rtol=1e-12, atol=1e-12)


def test_a_flat_image_has_no_coherence():
    s = structure_tensor(np.full((20, 20), 7.0))
    assert np.all(s == 0) and np.all(coherence(s) == 0)


def test_eigen_and_log_of_known_tensors():
    l1, l2, theta = eigen(np.array([[3.0, 0.0, 1.0], [1.0, 0.0, 3.0], [2.0, 1.0, 2.0]]))
    np.testing.assert_allclose(l1, [3.0, 3.0, 3.0])
    np.testing.assert_allclose(l2, [1.0, 1.0, 1.0])
    np.testing.assert_allclose(theta, [0.0, np.pi / 2, np.pi / 4])
    np.testing.assert_allclose(log_tensor(np.array([[5.0, 0.0, 5.0]]), 1e-9), [[np.log(5), 0.0, np.log(5)]])
    # a general SPD tensor: exp(log S) = S, through the eigen-decomposition of the logarithm
    s = np.array([4.0, 1.5, 2.0])
    lg = log_tensor(s, 1e-9)
    w, v = np.linalg.eigh(np.array([[lg[0], lg[1]], [lg[1], lg[2]]]))
    back = v @ np.diag(np.exp(w)) @ v.T
    np.testing.assert_allclose(back, [[4.0, 1.5], [1.5, 2.0]], rtol=1e-12)
    # a zero eigenvalue is floored
    assert np.isfinite(log_tensor(np.array([1.0, 0.0, 0.0]), 1e-6)).all()


@pytest.mark.parametrize("kw, words", [
    ({"image": np.zeros((4, 4, 3))}, "2D grey image"),
    ({"image": np.zeros((8, 8)), "boundary": "edge"}, "boundary"),
    ({"image": np.zeros((8, 8)), "grad_sigma": 0}, "sigma"),
    ({"image": np.zeros((5, 5)), "window_sigma": 3.0}, "too short"),
    ({"image": np.array([[np.nan, 0.0], [0.0, 0.0]])}, "NaN"),
])
def test_bad_input_is_refused(kw, words):
    with pytest.raises(InputError, match=words):
        structure_tensor(**kw)
