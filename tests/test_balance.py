"""The label-histogram balance (clsolid.balance): the dual projection reaches the target
fractions, the sweep target accounts for the voxels left alone, and a run keeps the
exemplar's fractions where the published form does not."""

import math

import numpy as np
import pytest

from clsolid.balance import MAX_BIAS, OFF_BIAS, n_score_slots, project_bias, score_stride, softmax, sweep_target
from clsolid.ml.opencl import CLBackend
from clsolid.gallery import gallery_exemplar
from clsolid.ml.params import MLParams
from clsolid.ml.driver import label_fractions, run_ml


def _scores(seed: int, m: int, n: int, spread: float) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.normal(0.0, spread, (m, n)) + rng.normal(0.0, spread, n)  # labels unequally likely


@pytest.mark.parametrize("spread", [0.5, 3.0, 40.0])
def test_projection_reaches_the_target(spread):
    """From mild to nearly one-hot laws, the biased softmax averages to the target."""
    s = _scores(1, 4000, 4, spread)
    target = np.array([0.1, 0.2, 0.3, 0.4])
    b = project_bias(s, target, max_iter=200)
    got = softmax(s + b).mean(axis=0)
    np.testing.assert_allclose(got, target, atol=2e-3)
    assert b[3] == 0.0  # F does not change when all biases move together: the largest is held
    unbiased = softmax(s).mean(axis=0)
    assert np.max(np.abs(unbiased - target)) > 0.05  # the test asks for a real move


def test_absent_labels_are_forbidden_and_the_rest_still_match():
    s = _scores(2, 3000, 5, 2.0)
    target = np.array([0.5, 0.0, 0.3, 0.2, 0.0])
    b = project_bias(s, target, max_iter=200)
    assert b[1] == b[4] == OFF_BIAS
    got = softmax(s + b).mean(axis=0)
    assert got[1] == got[4] == 0.0
    np.testing.assert_allclose(got, target, atol=2e-3)


def test_an_unreachable_label_stops_at_the_cap():
    """A label no voxel can take (score -inf everywhere) stops MAX_BIAS past the scores' spread."""
    s = _scores(3, 500, 3, 1.0)
    s[:, 2] = -np.inf
    b = project_bias(s, np.array([0.4, 0.4, 0.2]), max_iter=200)
    spread = np.max(s[:, :2].max(axis=1) - s[:, :2].min(axis=1))
    assert math.isclose(b[2] - b[0], spread + MAX_BIAS) and np.all(np.abs(b - b[0]) <= spread + MAX_BIAS + 1e-9)
    # the search goes on without it: the other free label gets its share, the largest the rest
    got = softmax(s + b).mean(axis=0)
    np.testing.assert_allclose(got, [0.6, 0.4, 0.0], atol=2e-3)


def test_a_far_but_finite_label_gets_its_share():
    """Scores 1e4 nats down (sharp laws, summed over three views) are still reachable: the
    bias goes as far as the scores spread, not to a fixed cap."""
    s = _scores(3, 500, 3, 1.0)
    s[:, 2] -= 1e4
    target = np.array([0.4, 0.4, 0.2])
    b = project_bias(s, target, max_iter=2000)
    np.testing.assert_allclose(softmax(s + b).mean(axis=0), target, atol=2e-3)


def test_a_warm_start_at_the_answer_stays_there():
    s = _scores(4, 2000, 3, 1.0)
    target = np.array([0.2, 0.5, 0.3])
    b = project_bias(s, target, max_iter=200)
    np.testing.assert_allclose(project_bias(s, target, b, max_iter=200), b, atol=1e-9)


def test_sweep_target_brings_the_whole_volume_to_the_exemplar():
    pi = np.array([0.5, 0.3, 0.2, 0.0])
    fixed = np.array([30, 0, 10, 0])  # 40 voxels left alone
    n_visited = 60
    unbiased = np.array([0.7, 0.1, 0.1, 0.1])
    t = sweep_target(pi, fixed, n_visited, unbiased, 1.0)
    np.testing.assert_allclose((t * n_visited + fixed) / 100, pi)
    np.testing.assert_allclose(sweep_target(pi, fixed, n_visited, unbiased, 0.0), [0.7, 0.1, 0.1, 0.0])
    half = sweep_target(pi, fixed, n_visited, unbiased, 0.5)
    np.testing.assert_allclose(half, 0.5 * (t + np.array([0.7, 0.1, 0.1, 0.0])))


def test_sweep_target_never_asks_for_a_negative_share():
    t = sweep_target(np.array([0.5, 0.5]), np.array([80, 0]), 20, np.array([0.5, 0.5]), 1.0)
    assert np.all(t > 0) and math.isclose(t.sum(), 1.0)  # too many 0s already: all 1s asked, 0 floored


@pytest.mark.parametrize("shape", [(8, 8, 8), (64, 64, 64), (96, 100, 105), (128, 128, 128)])
def test_score_lattice(shape):
    stride, n = score_stride(shape), int(np.prod(shape))
    assert n_score_slots(shape) == -(-n // stride)
    if n <= 1 << 17:
        assert stride == 1
    else:  # about 2^17 kept, not lined up with rows or columns
        assert (1 << 16) < n // stride <= 1 << 17
        assert math.gcd(stride, shape[2]) == 1 and math.gcd(stride, shape[1]) == 1


@pytest.mark.slow
def test_a_run_keeps_the_exemplar_fractions(device):
    """Gibbs with the balance ends within a point of porous80 (about 20/80); without, it drifts."""
    img = gallery_exemplar("porous80", 64)
    labels = np.where(img > 0, 0.0, 1.0)  # label 1: the pores
    want = labels.mean()
    assert 0.1 < want < 0.35
    got = {}
    for beta in (0.0, 1.0):
        params = MLParams(neighborhood=5, scales=2, balance=beta)
        vol = run_ml(labels, (16, 16, 16), params, 3, CLBackend(device))[0]
        got[beta] = label_fractions(vol, np.array([0.0, 1.0]))[1]
    assert abs(got[1.0] - want) < 0.01, got
    assert abs(got[0.0] - want) > abs(got[1.0] - want), got


@pytest.mark.each_device
@pytest.mark.parametrize("kind", ["opencl", "tiled", "reference"])
def test_the_balance_reads_a_sets_values_and_score_rows_as_the_whole_would_give(device, kind):
    """After every set the balance reads only that set's values and score rows (a gather on
    the device, not the whole block): the same numbers as the whole block's arrays."""
    from clsolid.ml.reference import ReferenceBackend
    from clsolid.ml.tiled import LocalTiles, TiledBackend

    backend = {"opencl": lambda: CLBackend(device), "tiled": lambda: TiledBackend(LocalTiles(CLBackend(device)), 8),
               "reference": ReferenceBackend}[kind]()
    labels = np.where(gallery_exemplar("porous80", 64)[:32, :32] > 0, 0.0, 1.0)
    run_ml(labels, (12, 12, 12), MLParams(neighborhood=5, scales=1, sweeps=1), 3, backend)
    voxels = np.random.default_rng(0).choice(12**3, 200, replace=False)
    np.testing.assert_array_equal(backend.values(voxels), np.asarray(backend.volume()).ravel()[voxels])
    rows = np.arange(0, n_score_slots((12, 12, 12)), 3)
    np.testing.assert_array_equal(backend.read_scores(rows), np.asarray(backend.scores())[rows])
    assert np.asarray(backend.scores())[rows].any()  # the rows hold scores, not the zeros they start with


def test_serial_blas_holds_numpy_blas_at_one_thread_and_restores_it():
    from threadpoolctl import threadpool_info

    from clsolid.core.threads import serial_blas

    def blas_threads():
        return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]

    before = blas_threads()
    with serial_blas():
        inside = blas_threads()
    assert inside and set(inside) == {1}  # NumPy always loads a BLAS
    assert blas_threads() == before
