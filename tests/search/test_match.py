"""The exact nearest-neighbourhood matcher of the search methods: the exemplar table, the
float64 reference, and the OpenCL kernel against it (identical on integer grey levels)."""

import numpy as np
import pytest

from clsolid import DeviceMemoryError, InputError
from clsolid.search.match import (CLMatcher, best_match_reference, candidate_distances_reference,
                                  causal_weights, exemplar_table, k_nearest_reference, square_offsets)

# Every test here that takes a device checks a kernel against the reference: on every device.
pytestmark = pytest.mark.each_device


def _exemplar(seed=0, shape=(24, 28), levels=256):
    return np.random.default_rng(seed).integers(0, levels, shape).astype(np.uint8)


def test_table_holds_every_complete_neighbourhood():
    ex = _exemplar()
    table, sites = exemplar_table(ex, 5)
    assert table.shape == ((24 - 4) * (28 - 4), 25) and table.dtype == np.float32
    for s in (0, 7, table.shape[0] - 1):
        r, c = sites[s]
        np.testing.assert_array_equal(table[s].reshape(5, 5), ex[r - 2 : r + 3, c - 2 : c + 3])
    off = square_offsets(5)
    r, c = sites[11]
    np.testing.assert_array_equal(table[11], ex[r + off[:, 0], c + off[:, 1]])  # the offsets' order


def test_causal_weights_are_the_l_shape():
    w = causal_weights(5).reshape(5, 5)
    assert w[:2].all() and w[2, :2].all() and not w[2, 2:].any() and not w[3:].any()


def test_reference_is_the_brute_force_minimum_with_lowest_index_ties():
    table = np.array([[1, 1], [0, 0], [0, 0], [5, 5]], np.float32)
    idx, dist = best_match_reference(np.array([[0.0, 0.0], [4.0, 4.0], [0.5, 0.5]]), table)
    assert idx.tolist() == [1, 3, 0] and dist.tolist() == [0.0, 2.0, 0.5]  # [0.5, 0.5]: 0, 1 and 2 tie
    idx, _ = best_match_reference(np.array([[9.0, 0.0]]), table, weights=np.array([0.0, 1.0]))
    assert idx.tolist() == [1]  # the first term does not count: sites 1 and 2 tie at 0


@pytest.mark.parametrize("k, causal", [(3, False), (5, False), (7, True), (9, False)])
def test_kernel_matches_the_reference_exactly_on_grey_levels(device, k, causal):
    ex = _exemplar(1, (32, 30))
    table, _ = exemplar_table(ex, k)
    rng = np.random.default_rng(k)
    # queries: exemplar windows with integer noise, as a half-synthesized volume gives
    queries = table[rng.integers(0, table.shape[0], 500)] + rng.integers(-20, 21, (500, k * k))
    queries = np.clip(queries, 0, 255)
    weights = causal_weights(k) if causal else None
    want_i, want_d = best_match_reference(queries, table, weights)
    got_i, got_d = CLMatcher(device, table, weights, max_batch=128).best(queries)
    np.testing.assert_array_equal(got_i, want_i)
    np.testing.assert_array_equal(got_d, want_d.astype(np.float32))


def test_kernel_breaks_ties_to_the_lowest_index(device):
    ex = np.tile(np.array([[0, 255], [255, 0]], np.uint8), (8, 8))  # a checkerboard: many equal windows
    table, _ = exemplar_table(ex, 3)
    queries = table[[5, 6, 9]]
    want_i, _ = best_match_reference(queries, table)
    got_i, got_d = CLMatcher(device, table).best(queries)
    assert got_i.tolist() == want_i.tolist() == [1, 0, 1]  # the first window of its phase (odd, even column)
    assert not got_d.any()


def test_kernel_on_real_valued_data(device):
    """Float inputs: the indices agree wherever the best is clear of the second best."""
    rng = np.random.default_rng(3)
    table = rng.normal(size=(800, 25)).astype(np.float32)
    queries = rng.normal(size=(300, 25))
    want_i, want_d = best_match_reference(queries, table)
    got_i, got_d = CLMatcher(device, table).best(queries)
    d = (((queries[:, None, :] - table[None].astype(np.float64)) ** 2).sum(axis=2))
    second = np.sort(d, axis=1)[:, 1]
    clear = second - want_d > 1e-4 * want_d
    assert clear.mean() > 0.95
    np.testing.assert_array_equal(got_i[clear], want_i[clear])
    np.testing.assert_allclose(got_d, want_d, rtol=1e-5)


def test_a_window_of_the_exemplar_finds_itself(device):
    ex = _exemplar(4)
    table, sites = exemplar_table(ex, 7)
    pick = np.array([0, 17, 101, table.shape[0] - 1])
    idx, dist = CLMatcher(device, table).best(table[pick])
    assert idx.tolist() == pick.tolist() and not dist.any()  # random grey levels: no repeats


def test_k_nearest_reference_orders_by_distance_then_index():
    table = np.array([[1, 1], [0, 0], [0, 0], [5, 5], [0, 1]], np.float32)
    idx, dist = k_nearest_reference(np.array([[0.0, 0.0], [5.0, 5.0]]), table, 3)
    assert idx.tolist() == [[1, 2, 4], [3, 0, 4]]
    assert dist.tolist() == [[0.0, 0.0, 1.0], [0.0, 32.0, 41.0]]


@pytest.mark.parametrize("count", [1, 5, 15])
def test_k_nearest_kernel_matches_the_reference_exactly(device, count):
    """Binary and grey exemplars: many equal distances, all ordered as the reference does."""
    rng = np.random.default_rng(count)
    for ex in (_exemplar(2, (30, 26)), (rng.random((30, 26)) < 0.3).astype(np.uint8) * 255):
        table, _ = exemplar_table(ex, 5)
        queries = np.clip(table[rng.integers(0, table.shape[0], 300)] + rng.integers(-9, 10, (300, 25)), 0, 255)
        weights = np.ones(25, np.float32)
        weights[12] = 0.0  # the centre left out, as a first search does
        want_i, want_d = k_nearest_reference(queries, table, count, weights)
        got_i, got_d = CLMatcher(device, table, max_batch=128).nearest(queries, count, weights)
        np.testing.assert_array_equal(got_i, want_i)
        np.testing.assert_array_equal(got_d, want_d.astype(np.float32))


def test_best_match_with_general_weights_and_ragged_batches(device):
    """Weights other than 0 and 1 (the kernel keeps its multiply), a query count that is no
    multiple of the queries a work-item takes, and batches that end mid-item."""
    rng = np.random.default_rng(7)
    table, _ = exemplar_table(_exemplar(3, (26, 30)), 5)
    queries = np.clip(table[rng.integers(0, table.shape[0], 301)] + rng.integers(-5, 6, (301, 25)), 0, 255)
    weights = rng.choice(np.array([0.0, 0.5, 1.0, 2.0], np.float32), 25)
    want_i, want_d = best_match_reference(queries, table, weights)
    for batch in (301, 50, 7):
        got_i, got_d = CLMatcher(device, table, max_batch=batch).best(queries, weights)
        np.testing.assert_array_equal(got_i, want_i)
        np.testing.assert_array_equal(got_d, want_d.astype(np.float32))
    zero = CLMatcher(device, table).best(queries[:9], np.zeros(25, np.float32))  # every site at distance 0
    np.testing.assert_array_equal(zero[0], 0)
    np.testing.assert_array_equal(zero[1], 0.0)


def test_candidate_distances_kernel_matches_the_reference(device):
    ex = _exemplar(5, (28, 28))
    table, _ = exemplar_table(ex, 7)
    rng = np.random.default_rng(5)
    queries = np.clip(table[rng.integers(0, table.shape[0], 400)] + rng.integers(-30, 31, (400, 49)), 0, 255)
    cand = rng.integers(-1, table.shape[0], (400, 15))
    cand[:, 0] = -1  # "no candidate": +inf
    want = candidate_distances_reference(queries, table, cand, causal_weights(7))
    got = CLMatcher(device, table, max_batch=64).distances(queries, cand, causal_weights(7))  # 7 launches
    assert np.isinf(got[:, 0]).all() and np.isinf(want[:, 0]).all()
    np.testing.assert_array_equal(got, want.astype(np.float32))
    brute = k_nearest_reference(queries[:3], table, 1, causal_weights(7))[1][:, 0]
    every = candidate_distances_reference(queries[:3], table, np.tile(np.arange(table.shape[0]), (3, 1)),
                                          causal_weights(7))
    np.testing.assert_array_equal(every.min(axis=1), brute)  # the same distance as the search's


@pytest.mark.parametrize("call, word", [
    (lambda: k_nearest_reference(np.zeros((2, 9)), np.zeros((4, 9)), 5), r"count=5 .* \[1, 4\]"),
    (lambda: k_nearest_reference(np.zeros((2, 9)), np.zeros((4, 9)), 0), "count=0"),
    (lambda: candidate_distances_reference(np.zeros((2, 9)), np.zeros((4, 9)), np.zeros((3, 2), int)), r"\(2, C\)"),
    (lambda: candidate_distances_reference(np.zeros((2, 9)), np.zeros((4, 9)), np.full((2, 2), 4)), "below 4"),
    (lambda: candidate_distances_reference(np.zeros((2, 9)), np.zeros((4, 9)), np.zeros((2, 2))), "integer"),
    (lambda: exemplar_table(_exemplar(), 4), "odd"),
    (lambda: exemplar_table(_exemplar(), 33), "odd"),
    (lambda: exemplar_table(_exemplar(shape=(6, 40)), 7), "at least 7 x 7"),
    (lambda: exemplar_table(np.zeros((8, 8, 3)), 3), "2D"),
    (lambda: best_match_reference(np.zeros((2, 8)), np.zeros((4, 9))), r"\(m, 9\)"),
    (lambda: best_match_reference(np.zeros((2, 9)), np.zeros((4, 9)), np.full(9, -1.0)), "non-negative"),
])
def test_bad_input_says_what_is_wrong(call, word):
    with pytest.raises(InputError, match=word):
        call()


def test_a_table_beyond_the_device_is_refused_before_allocating(device):
    class Small:  # the device, with a tiny allocation limit
        def __getattr__(self, name):
            return getattr(device, name)
        max_alloc = 1000

    with pytest.raises(DeviceMemoryError, match="match table"):
        CLMatcher(Small(), np.zeros((100, 25), np.float32))


def _coded(seed, shape=(30, 26), phases=(0, 85, 170, 255), fractions=(0.55, 0.25, 0.15, 0.05)):
    """A 4-phase exemplar (grey values) and its phase codes."""
    from clsolid.search.codes import phase_codes

    ex = np.random.default_rng(seed).choice(np.array(phases, np.float64), shape, p=fractions)
    return ex, phase_codes(ex)


def test_reference_mismatch_terms_cost_the_sum_of_the_two_codes():
    q = np.array([[3.0, 5.0, 2.0]])
    table = np.array([[3, 7, 0], [4, 5, 2]], np.float32)
    _, dist = k_nearest_reference(q, table, 2, mismatch=2)  # terms 0, 1: codes; term 2: squared
    assert dist.tolist() == [[7.0, 16.0]]  # site 1: 3 != 4 costs 7; site 0: 5 != 7 costs 12, (2 - 0)^2 = 4


@pytest.mark.parametrize("k, parent, causal", [(3, False, False), (5, True, False), (7, True, True)])
def test_kernels_match_the_reference_on_phase_codes(device, k, parent, causal):
    """Codes in the square's terms, grey levels in a parent's: the best match, the K nearest
    and the candidate distances, exactly (integer codes, sums below 2^24)."""
    from clsolid.search.features import centre_weights

    ex, codes = _coded(k)
    table, _ = exemplar_table(ex, k)
    if parent:  # nine grey terms after the square's, as a multi-resolution neighbourhood has
        table = np.concatenate([table, np.random.default_rng(1).integers(0, 256, (table.shape[0], 9))], axis=1)
    searched = codes.encode_terms(table, k * k).astype(np.float32)
    rng = np.random.default_rng(k)
    queries = searched[rng.integers(0, table.shape[0], 300)].copy()
    flip = rng.random((300, k * k)) < 0.2  # a fifth of the square's terms another phase
    queries[:, : k * k][flip] = rng.choice(codes.codes, flip.sum())
    weights = centre_weights(k, parent, centre=False, causal=causal)
    matcher = CLMatcher(device, searched, max_batch=128, mismatch=k * k)
    for count in (1, 5):
        want_i, want_d = k_nearest_reference(queries, searched, count, weights, mismatch=k * k)
        got_i, got_d = matcher.nearest(queries, count, weights)
        np.testing.assert_array_equal(got_i, want_i)
        np.testing.assert_array_equal(got_d, want_d.astype(np.float32))
    cand = rng.integers(-1, table.shape[0], (300, 12))
    want = candidate_distances_reference(queries, searched, cand, weights, mismatch=k * k)
    np.testing.assert_array_equal(matcher.distances(queries, cand, weights), want.astype(np.float32))


def test_phase_codes_weigh_rare_phases_and_ignore_the_grey_values():
    from clsolid.search.codes import phase_codes

    ex, codes = _coded(0)
    f = np.array([np.mean(ex == p) for p in codes.phases])
    assert np.all(np.diff(codes.codes[np.argsort(f)]) < 0)  # the rarer the phase, the dearer its mismatch
    np.testing.assert_allclose(codes.codes * f, codes.codes[0] * f[0], rtol=0.01)  # c_p = S / (2 f_p)
    mean = sum(f[a] * f[b] * (codes.codes[a] + codes.codes[b]) for a in range(4) for b in range(4) if a != b)
    assert mean == pytest.approx(2 * ex.var(), rel=0.01)  # two random pixels: as far as by squared differences
    renamed = phase_codes(np.choose(np.searchsorted(codes.phases, ex), [0.0, 255.0, 85.0, 170.0]))
    # renamed phases keep their codes up to the scale (the variance changes with the names)
    np.testing.assert_allclose(np.sort(renamed.codes) / renamed.codes.max(), np.sort(codes.codes) / codes.codes.max(),
                               rtol=0.01)
    np.testing.assert_array_equal(codes.encode(np.array([[0.0, 90.0], [250.0, 170.0]])),
                                  codes.codes[[[0, 1], [3, 2]]])  # blends count for their nearest phase


def test_a_bad_mismatch_count_is_refused():
    with pytest.raises(InputError, match="mismatch=10"):
        k_nearest_reference(np.zeros((2, 9)), np.zeros((4, 9)), 1, mismatch=10)
