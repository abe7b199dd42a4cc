"""Visiting orders (clsolid.core.orders) and the search methods' sequential mode."""

import numpy as np
import pytest

import clsolid
from clsolid.core.orders import ORDERS, hilbert_keys, morton_keys, visiting_order
from clsolid.errors import InputError
from clsolid.gallery import gallery_exemplar
from clsolid.search import driver
from clsolid.search.params import SearchParams


@pytest.mark.parametrize("shape", [(4, 4, 4), (5, 6, 7), (1, 3, 2)])
@pytest.mark.parametrize("order", ORDERS)
def test_every_order_is_a_permutation(shape, order):
    idx = visiting_order(shape, order, np.random.default_rng(0))
    assert np.array_equal(np.sort(idx), np.arange(np.prod(shape)))


@pytest.mark.parametrize("n", [2, 4, 8, 16])
def test_hilbert_steps_to_a_face_neighbour(n):
    pos = np.stack(np.unravel_index(visiting_order((n, n, n), "hilbert"), (n, n, n)), axis=1)
    steps = np.abs(np.diff(pos, axis=0)).sum(axis=1)
    assert np.all(steps == 1)
    assert np.array_equal(np.sort(hilbert_keys((n, n, n))), np.arange(n**3))  # a bijection onto the curve


def test_morton_interleaves_the_bits():
    keys = morton_keys((4, 4, 4)).reshape(4, 4, 4)
    assert keys[0, 0, 1] == 1 and keys[0, 1, 0] == 2 and keys[1, 0, 0] == 4 and keys[0, 0, 2] == 8
    assert keys[3, 3, 3] == 63 and keys[2, 1, 3] == 0b101011


def test_lexicographic_and_random_orders():
    assert np.array_equal(visiting_order((2, 3, 4), "lexicographic"), np.arange(24))
    a = visiting_order((4, 4, 4), "random", np.random.default_rng(5))
    assert np.array_equal(a, visiting_order((4, 4, 4), "random", np.random.default_rng(5)))
    assert not np.array_equal(a, np.arange(64))
    with pytest.raises(InputError, match="seeded"):
        visiting_order((4, 4, 4), "random")
    with pytest.raises(InputError, match="order"):
        visiting_order((4, 4, 4), "spiral")


@pytest.mark.parametrize("order", ["lexicographic", "hilbert", "random"])
def test_sequential_mode_visits_one_voxel_at_a_time_in_the_order(monkeypatch, order):
    seen = []
    inner = driver.UPDATES["wl"]

    def spy(level, vol, coarse, voxels):
        seen.append((vol.shape, voxels.tolist()))
        return inner(level, vol, coarse, voxels)

    monkeypatch.setitem(driver.UPDATES, "wl", spy)
    ex = gallery_exemplar("porous50", 64)[:16, :16].astype(np.float64)
    params = SearchParams(method="wl", neighborhood=3, scales=2, iterations=2, order=order)
    driver.run_search(ex, (4, 6, 8), params, 7, driver_matcher)
    finest = [v[0] for shape, v in seen if shape == (4, 6, 8)]
    assert all(len(v) == 1 for _, v in seen)
    first, second = finest[:192], finest[192:]
    assert first == visiting_order((4, 6, 8), order, np.random.default_rng([7, 0, 1])).tolist()
    assert second == visiting_order((4, 6, 8), order, np.random.default_rng([7, 0, 2])).tolist()


def driver_matcher(table, mismatch=0):
    from clsolid.search.match import ReferenceMatcher

    return ReferenceMatcher(table, mismatch=mismatch)


@pytest.mark.slow
def test_sequential_order_runs_and_is_refused_with_the_overlap_rule(device):
    ex = gallery_exemplar("porous80", 64)
    a = clsolid.synthesize(ex, (8, 8, 8), method="kopf", order="morton", scales=2, iterations=2, rng=1,
                           device=device)
    assert set(np.unique(a)) <= {0.0, 255.0}
    np.testing.assert_array_equal(a, clsolid.synthesize(ex, (8, 8, 8), method="kopf", order="morton", scales=2,
                                                        iterations=2, rng=1, device=device))
    with pytest.raises(InputError, match="no visiting"):
        clsolid.synthesize(ex, (8, 8, 8), method="kopf", order="hilbert", rule="overlap")


def test_causal_weights_keep_only_what_a_raster_has_visited():
    from clsolid.search.features import centre_weights

    w = centre_weights(5, True, centre=True, causal=True)
    assert w[:12].tolist() == [1.0] * 12 and w[12:25].tolist() == [0.0] * 13  # rows above, left half
    assert w[25:].tolist() == [1.0] * 9  # the parent square whole
    assert centre_weights(5, False, centre=False).sum() == 24


@pytest.mark.slow
def test_causal_raster_run(monkeypatch, device):
    from clsolid.search import features

    calls = []
    inner = features.centre_weights
    monkeypatch.setattr(driver, "centre_weights", lambda *a, **kw: calls.append(kw) or inner(*a, **kw))
    ex = gallery_exemplar("porous50", 64)
    a = clsolid.synthesize(ex, (8, 8, 8), method="wl", causal=True, order="lexicographic", scales=2, iterations=1,
                           rng=1, device=device)
    assert calls and all(kw["causal"] for kw in calls)
    assert a.shape == (8, 8, 8) and np.isfinite(a).all()
    with pytest.raises(InputError, match="whole"):
        clsolid.synthesize(ex, (8, 8, 8), method="kopf", causal=True, rule="overlap")
