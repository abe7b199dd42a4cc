"""The tensor dissimilarities (clsolid.tensor.dissimilarity) against known answers: zero on
identical tensors, symmetry, the SO orientation term under rotation, LE of scaled identities,
invariance to a common rotation, and the neighbourhood sum."""

import numpy as np
import pytest

from clsolid.errors import InputError
from clsolid.tensor import METRICS, coherence, dissimilarity, neighbourhood_dissimilarity


def _spd(rng, n):
    """n random symmetric positive-definite tensors (xx, xy, yy)."""
    a = rng.normal(size=(n, 2, 2))
    m = a @ a.transpose(0, 2, 1) + 0.1 * np.eye(2)
    return np.stack([m[:, 0, 0], m[:, 0, 1], m[:, 1, 1]], axis=-1)


def _rotate(s, angle):
    """R S R^T for tensors (..., 3)."""
    c, n = np.cos(angle), np.sin(angle)
    r = np.array([[c, -n], [n, c]])
    m = np.stack([np.stack([s[..., 0], s[..., 1]], -1), np.stack([s[..., 1], s[..., 2]], -1)], -2)
    out = r @ m @ r.T
    return np.stack([out[..., 0, 0], out[..., 0, 1], out[..., 1, 1]], axis=-1)


@pytest.mark.parametrize("metric", METRICS)
def test_identical_tensors_are_at_zero_and_the_metric_is_symmetric(metric):
    rng = np.random.default_rng(1)
    a, b = _spd(rng, 50), _spd(rng, 50)
    assert np.all(dissimilarity(a, a, metric) == 0)
    np.testing.assert_allclose(dissimilarity(a, b, metric), dissimilarity(b, a, metric), rtol=1e-12)
    assert np.all(dissimilarity(a, b, metric) > 0)


@pytest.mark.parametrize("metric", METRICS)
def test_a_common_rotation_changes_nothing(metric):
    rng = np.random.default_rng(2)
    a, b = _spd(rng, 40), _spd(rng, 40)
    for angle in (0.3, np.pi / 2, 2.0):
        np.testing.assert_allclose(dissimilarity(_rotate(a, angle), _rotate(b, angle), metric),
                                   dissimilarity(a, b, metric), rtol=1e-9, atol=1e-12)


def test_ed_and_fn_by_hand():
    a, b = np.array([3.0, 1.0, 2.0]), np.array([1.0, 0.0, 4.0])
    assert dissimilarity(a, b, "ED") == pytest.approx(4.0 + 2.0 * 1.0 + 4.0)
    assert dissimilarity(a, b, "FN") == pytest.approx(np.sqrt(10.0))


def test_le_of_scaled_identities_is_root_two_times_the_log_ratio():
    for p, q in ((1.0, np.e), (2.0, 8.0), (5.0, 0.5)):
        got = dissimilarity(np.array([p, 0.0, p]), np.array([q, 0.0, q]), "LE")
        assert got == pytest.approx(np.sqrt(2.0) * abs(np.log(p / q)), rel=1e-12)


def test_a_right_angle_gives_the_largest_so_orientation_term():
    """With alpha = 1, SO is the orientation term |sin(dO)| min(C1, C2): a tensor against
    itself rotated by theta gives |sin theta| C, largest (C) at 90 degrees."""
    s = np.array([5.0, 1.0, 2.0])
    c = coherence(s)
    angles = np.linspace(0, np.pi, 13)
    got = np.array([dissimilarity(s, _rotate(s, t), "SO", alpha=1.0) for t in angles])
    np.testing.assert_allclose(got, np.abs(np.sin(angles)) * c, atol=1e-12)
    assert np.argmax(got) == 6 and got[6] == pytest.approx(c)
    # alpha = 0: the coherence ratio alone, 1 for equal coherences
    assert dissimilarity(s, _rotate(s, 1.0), "SO", alpha=0.0) == pytest.approx(1.0)


def test_the_neighbourhood_sum_adds_the_weighted_dissimilarities():
    rng = np.random.default_rng(3)
    f1, f2 = _spd(rng, 9).reshape(1, 9, 3), _spd(rng, 9).reshape(1, 9, 3)
    per = dissimilarity(f1, f2, "FN")[0]
    assert neighbourhood_dissimilarity(f1, f2, "FN")[0] == pytest.approx(per.sum())
    w = np.r_[np.ones(4), np.zeros(5)]  # a causal neighbourhood: the first four
    assert neighbourhood_dissimilarity(f1, f2, "FN", weights=w)[0] == pytest.approx(per[:4].sum())


@pytest.mark.parametrize("kw, words", [({"metric": "L2"}, "metric"), ({"metric": "SO", "alpha": 1.5}, "alpha")])
def test_bad_metrics_are_refused(kw, words):
    with pytest.raises(InputError, match=words):
        dissimilarity(np.ones(3), np.ones(3), **kw)
