"""The accelerated search (clsolid.search.coherence): candidates from the neighbours' matches
by hand, the parity inheritance from a coarser level, the OpenCL run against the float64
reference, and the matches it finds against the exhaustive search's."""

from functools import partial

import numpy as np
import pytest

import clsolid
from clsolid.gallery import gallery_exemplar
from clsolid.core.schedule import colour_sets
from clsolid.search.coherence import SIMILAR, Coherence
from clsolid.search.driver import run_search
from clsolid.search.features import valid_sites
from clsolid.search.match import CLMatcher, ReferenceMatcher, best_match_reference, exemplar_table
from clsolid.search.params import SearchParams
from clsolid.errors import InputError


def _coherence(shape=(4, 5, 6), image=(10, 10), k=3, views=("front", "right")):
    rows, cols = valid_sites(image, None, k)
    similar = np.tile(np.arange(rows.size)[:, None], (1, SIMILAR))  # each site alone: easy to read
    similar[:, 1:] = -1
    return Coherence(rows, cols, image, similar, shape, views), rows, cols


def test_a_neighbours_match_proposes_its_site_shifted_back():
    coh, rows, cols = _coherence()
    site_at = {(r, c): s for s, (r, c) in enumerate(zip(rows, cols))}
    v = np.ravel_multi_index((2, 2, 3), coh.shape)
    right_nb = np.ravel_multi_index((2, 2, 4), coh.shape)  # front view: columns along x
    coh.matched[0, right_nb] = site_at[(5, 5)]
    cand = coh.candidates(0, np.array([v]))[0]
    assert set(cand[cand >= 0].tolist()) == {site_at[(5, 4)]}
    below = np.ravel_multi_index((2, 3, 3), coh.shape)  # rows along y
    coh.matched[0, below] = site_at[(1, 1)]  # shifted back to row 0: not a valid site, no candidate
    assert set(coh.candidates(0, np.array([v]))[0].tolist()) - {-1} == {site_at[(5, 4)]}
    assert (coh.candidates(1, np.array([v])) < 0).all()  # the right view knows nothing yet


def test_the_volume_wraps_for_the_neighbours():
    coh, rows, cols = _coherence()
    site_at = {(r, c): s for s, (r, c) in enumerate(zip(rows, cols))}
    coh.matched[0, np.ravel_multi_index((0, 0, 0), coh.shape)] = site_at[(4, 4)]
    v = np.ravel_multi_index((0, 4, 5), coh.shape)  # its down-right neighbour wraps to (0, 0, 0)
    assert set(coh.candidates(0, np.array([v]))[0].tolist()) - {-1} == {site_at[(3, 3)]}


def test_a_finer_level_inherits_the_doubled_site_and_the_parity():
    coarse, c_rows, c_cols = _coherence(shape=(2, 3, 3), image=(10, 10))
    fine, f_rows, f_cols = _coherence(shape=(4, 6, 6), image=(20, 20))
    c_site = {(r, c): s for s, (r, c) in enumerate(zip(c_rows, c_cols))}
    f_site = {(r, c): s for s, (r, c) in enumerate(zip(f_rows, f_cols))}
    coarse.matched[0, np.ravel_multi_index((1, 1, 2), coarse.shape)] = c_site[(3, 4)]
    fine.inherit(coarse)
    for z, y, x in [(2, 2, 4), (3, 3, 5), (2, 3, 4)]:  # the children of coarse voxel (1, 1, 2)
        got = fine.matched[0, np.ravel_multi_index((z, y, x), fine.shape)]
        assert got == f_site[(6 + y % 2, 8 + x % 2)]
    assert fine.matched[1].max() == -1  # nothing known in the right view


def test_without_candidates_the_search_is_exhaustive():
    ex = np.random.default_rng(0).integers(0, 256, (16, 16))
    table, _ = exemplar_table(ex, 3)
    coh, _, _ = _coherence(shape=(2, 2, 2), image=(16, 16))
    queries = table[[3, 50, 90]] + 1.0
    site, dist = coh.best(ReferenceMatcher(table), 0, np.array([0, 3, 5]), queries, None)
    want = best_match_reference(queries, table)
    assert site.tolist() == want[0].tolist() and dist.tolist() == want[1].tolist()
    assert coh.matched[0, [0, 3, 5]].tolist() == site.tolist()  # recorded for the neighbours


@pytest.mark.parametrize("parent", [False, True])
def test_the_kernel_searches_as_the_numpy_gathering_does(device, parent):
    """coherence_best gathers squares, parents and proposals on the device: the same sites,
    distances and recorded matches as Coherence.best on NumPy's gathers, for voxels whose
    squares wrap, a view whose neighbours know nothing (an exhaustive search) and two weightings."""
    from clsolid.search.features import centre_weights, exemplar_features, voxel_features
    from clsolid.search.match import candidate_sets
    from clsolid.search.pyramid import gaussian_pyramid

    rng = np.random.default_rng(3)
    pyr = gaussian_pyramid(gallery_exemplar("gravel", 64)[:24, :28].astype(np.float64), 2)
    k, shape = 5, (10, 10, 10)
    table, _ = exemplar_features(pyr[0], pyr[1] if parent else None, k)
    rows, cols = valid_sites(pyr[0].shape, pyr[1].shape if parent else None, k)
    matcher = CLMatcher(device, table)
    similar = candidate_sets(matcher, table, SIMILAR, centre_weights(k, parent, centre=True))
    views = ("front", "right", "top")
    twins = [Coherence(rows, cols, pyr[0].shape, similar, shape, views) for _ in range(2)]
    known = rng.integers(-rows.size // 3, rows.size, (len(views), int(np.prod(shape))))  # about 1 in 4 unknown
    vol, coarse = rng.random(shape) * 255, (rng.random((3, 5, 5)) * 255 if parent else None)
    for twin in twins:
        twin.matched[...] = np.maximum(known, -1)
    colour = colour_sets(shape, k // 2)[0].ravel()  # conflict-free, as the driver's sets
    for centre, corner in ((False, 0), (True, vol.size - 1)):  # at a corner every square wraps
        voxels = np.flatnonzero(colour == colour[corner])
        w = centre_weights(k, parent, centre)
        for i, view in enumerate(views):
            got = twins[0].search(matcher, i, voxels, vol, coarse, k, w)
            want = twins[1].best(matcher, i, voxels, voxel_features(vol, coarse, voxels, view, k), w)
            np.testing.assert_array_equal(got[0], want[0])
            np.testing.assert_array_equal(got[1], want[1])
            np.testing.assert_array_equal(twins[0].matched, twins[1].matched)
        for twin in twins:  # nothing known in the front view: every voxel searched exhaustively there
            twin.matched[0] = -1
        twins[0]._device._sent[0] = False  # the host's copy changed: the device's is sent again


@pytest.mark.parametrize("method, scales", [("wl", 1), ("kopf", 1), ("chen-wang", 1), ("kopf", 2)])
def test_opencl_run_matches_the_reference(device, method, scales):
    """One scale: integer grey levels, float32 distances are exact, the blocks identical. Two:
    the coarser level's blurred values can tip near ties (chen-wang's discrete choices then
    differ on a few per cent of voxels), so kopf's weighted means are asked to agree closely,
    without the histogram specification, which ranks them (a float32 tip swaps two ranks)."""
    ex = gallery_exemplar("composite3", 64)[:32, :32].astype(np.float64)
    params = SearchParams(method=method, neighborhood=5, scales=scales, iterations=2, search="coherence",
                          specify=False)
    ref = run_search(ex, (10, 12, 14), params, 3, ReferenceMatcher).volume
    got = run_search(ex, (10, 12, 14), params, 3, partial(CLMatcher, device)).volume
    if scales == 1:
        np.testing.assert_array_equal(got, ref)
    agree = np.mean(np.isclose(ref, got, rtol=0, atol=1e-3))
    assert agree >= 0.99, f"only {agree:.2%} of voxels agree with the float64 reference"


@pytest.mark.parametrize("method", ["wl", "kopf", "chen-wang"])
def test_exact_passes_search_every_site_and_seed_the_candidates(device, method):
    """exact_passes = every pass: the exact search's block, bit for bit (the coherence state
    is only recorded). One exact pass: its matches are what the next passes' candidates come
    from, on the device as with the float64 reference, and the block is not the one
    without it."""
    ex = gallery_exemplar("composite3", 64)[:32, :32].astype(np.float64)
    common = dict(method=method, neighborhood=5, scales=2, iterations=3, specify=False)
    make = partial(CLMatcher, device)
    exact = run_search(ex, (10, 12, 14), SearchParams(**common), 3, make).volume
    every = run_search(ex, (10, 12, 14), SearchParams(search="coherence", exact_passes=3, **common), 3, make).volume
    np.testing.assert_array_equal(every, exact)
    one_scale = {**common, "scales": 1}  # integer grey levels: device and reference agree exactly
    params = SearchParams(search="coherence", exact_passes=1, **one_scale)
    once = run_search(ex, (10, 12, 14), params, 3, make).volume
    np.testing.assert_array_equal(once, run_search(ex, (10, 12, 14), params, 3, ReferenceMatcher).volume)
    assert not np.array_equal(once, run_search(ex, (10, 12, 14), SearchParams(search="coherence", **one_scale), 3,
                                               make).volume)


def test_exact_passes_need_the_coherence_search():
    with pytest.raises(InputError, match="search='coherence'"):
        SearchParams(method="kopf", exact_passes=1)
    with pytest.raises(InputError, match="exact_passes"):
        SearchParams(method="kopf", search="coherence", exact_passes=-1)


def test_coherence_matches_are_near_the_exhaustive_ones(device):
    """On a finished kopf block, each voxel's coherence match is never better than the
    exhaustive one (it searches a subset; its distances are summed in another order, so
    equal ones may differ by float32 rounding) and, on average, not far from it."""
    ex = gallery_exemplar("gravel", 64).astype(np.float64)
    params = SearchParams(method="kopf", search="coherence", scales=2, iterations=3)
    seen = {}

    from clsolid.search import driver, kopf

    def spy(level, vol, coarse, voxels):
        seen["level"], seen["vol"], seen["coarse"] = level, vol, coarse
        return kopf.update(level, vol, coarse, voxels)

    mp = pytest.MonkeyPatch()
    mp.setitem(driver.UPDATES, "kopf", spy)
    try:
        run_search(ex, (16, 16, 16), params, 2, partial(CLMatcher, device))
    finally:
        mp.undo()
    from clsolid.search.features import voxel_features

    level, vol = seen["level"], seen["vol"]
    every = np.arange(vol.size)
    q = voxel_features(vol, seen["coarse"], every, "front", 7)
    exact = level.matcher.best(q, level.w_first)[1].astype(np.float64)
    coh = level.coherence.best(level.matcher, 0, every, q, level.w_first)[1].astype(np.float64)
    assert (coh >= exact * (1 - 1e-5)).all()
    assert np.mean(np.sqrt(coh)) < 1.3 * np.mean(np.sqrt(exact)), (np.mean(np.sqrt(coh)), np.mean(np.sqrt(exact)))


def test_synthesize_and_cli_take_the_search(tmp_path):
    import json

    from clsolid.cli import main

    a = clsolid.synthesize("brick", (8, 8, 8), method="kopf", search="coherence", iterations=1, rng=1)
    b = clsolid.synthesize("brick", (8, 8, 8), method="kopf", search="coherence", iterations=1, rng=1)
    assert np.array_equal(a, b)
    with pytest.raises(clsolid.InputError, match="search='fast'"):
        clsolid.synthesize("brick", (8, 8, 8), method="kopf", search="fast")
    out = tmp_path / "k.npy"
    assert main(["synth", "brick", "-o", str(out), "--method", "kopf", "--search", "coherence", "--shape", "8", "8",
                 "8", "--iterations", "1", "--seed", "1", "-q"]) == 0
    assert json.loads((tmp_path / "k.json").read_text())["params"]["search"] == "coherence"
    np.testing.assert_array_equal(np.load(out), a)
    assert main(["synth", "brick", "-o", str(out), "--search", "coherence", "--shape", "8", "8", "8"]) != 0  # ml
    assert main(["synth", "brick", "-o", str(out), "--method", "kopf", "--search", "coherence", "--exact-passes", "1",
                 "--shape", "8", "8", "8", "--iterations", "2", "--seed", "1", "-q"]) == 0
    assert json.loads((tmp_path / "k.json").read_text())["params"]["exact_passes"] == 1
    np.testing.assert_array_equal(np.load(out), clsolid.synthesize("brick", (8, 8, 8), method="kopf", search="coherence",
                                                                   exact_passes=1, iterations=2, rng=1))
    assert main(["synth", "brick", "-o", str(out), "--exact-passes", "1", "--shape", "8", "8", "8"]) != 0  # ml
