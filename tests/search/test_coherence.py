"""The accelerated search (clsolid.search.coherence): candidates from the neighbours' matches
by hand, the parity inheritance from a coarser level, the OpenCL run against the float64
reference, and the matches it finds against the exhaustive search's."""

from functools import partial

import numpy as np
import pytest
from conftest import slow_except

import clsolid
from clsolid.phases import is_categorical
from clsolid.gallery import gallery_exemplar
from clsolid.core.schedule import colour_sets
from clsolid.search.coherence import SIMILAR, Coherence, phase_nearest
from clsolid.search.driver import run_search
from clsolid.search.features import valid_sites
from clsolid.search.match import CLMatcher, ReferenceMatcher, best_match_reference, exemplar_table
from clsolid.search.params import SearchParams
from clsolid.errors import InputError


def _coherence(shape=(4, 5, 6), image=(10, 10), k=3, views=("front", "right"), spread_eps=None):
    rows, cols = valid_sites(image, None, k)
    similar = np.tile(np.arange(rows.size)[:, None], (1, SIMILAR))  # each site alone: easy to read
    similar[:, 1:] = -1
    return Coherence(rows, cols, image, similar, shape, views, spread_eps), rows, cols


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


def _two_candidates(spread_eps):
    """Voxel (2, 2, 3)'s front-view candidates: A at distance 4 (its right neighbour's match
    shifted back) and B at distance 9 (its left neighbour's)."""
    coh, rows, cols = _coherence(spread_eps=spread_eps)
    site_at = {(r, c): s for s, (r, c) in enumerate(zip(rows, cols))}
    a, b = site_at[(5, 4)], site_at[(5, 6)]
    coh.matched[0, np.ravel_multi_index((2, 2, 4), coh.shape)] = site_at[(5, 5)]
    coh.matched[0, np.ravel_multi_index((2, 2, 2), coh.shape)] = site_at[(5, 5)]
    coh.count_usage()
    table = np.zeros((rows.size, 9))
    table[a, 0], table[b, 0] = 2.0, -3.0
    return coh, ReferenceMatcher(table), a, b, np.array([np.ravel_multi_index((2, 2, 3), coh.shape)])


def test_the_index_histogram_gives_a_site_used_beyond_its_share_away():
    """Ranked by (norm + eps) * (1 + max(0, use / uniform - 1)), uniform = 2 views x 120
    voxels / 64 sites = 3.75: A (norm 2) wins while unused; matched by 8 other voxels
    (factor 2.13: 4.27 against B's 3) it gives way to B; by distance alone it always wins.
    The distance returned is the chosen site's, and the use follows every match made."""
    coh, matcher, a, b, v = _two_candidates(0.01)
    q = np.zeros((1, 9))
    assert coh.best(matcher, 0, v, q, None)[0].tolist() == [a]
    assert coh.usage[a] == 1 and coh.usage.sum() == 3  # v's match, and its two neighbours'
    coh.record(1, np.arange(8), np.full(8, a))  # 8 voxels of the right view match A
    assert coh.usage[a] == 9
    site, dist = coh.best(matcher, 0, v, q, None)
    assert site.tolist() == [b] and dist.tolist() == [9.0]
    assert coh.usage[a] == 8 and coh.usage[b] == 1  # v moved from A to B
    assert coh.excess()[a] == pytest.approx(8 / 3.75) and coh.excess()[b] == 1.0
    plain, matcher, a, b, v = _two_candidates(None)
    plain.record(1, np.arange(8), np.full(8, a))
    assert plain.best(matcher, 0, v, q, None)[0].tolist() == [a] and plain.usage is None


def test_the_use_is_counted_anew_from_the_inherited_matches():
    coarse, c_rows, c_cols = _coherence(shape=(2, 3, 3), image=(10, 10))
    fine, _, _ = _coherence(shape=(4, 6, 6), image=(20, 20), spread_eps=0.1)
    coarse.matched[0, :] = 0
    fine.inherit(coarse)
    assert fine.usage.sum() == np.count_nonzero(fine.matched >= 0) > 0
    np.testing.assert_array_equal(fine.usage, np.bincount(fine.matched[fine.matched >= 0],
                                                          minlength=fine.usage.size))


@pytest.mark.each_device
@pytest.mark.parametrize("parent, spread_eps", [(False, None), (True, None), (True, 0.3)])
def test_the_kernel_searches_as_the_numpy_gathering_does(device, parent, spread_eps):
    """coherence_best gathers squares, parents and proposals on the device: the same sites,
    distances and recorded matches as Coherence.best on NumPy's gathers, for voxels whose
    squares wrap, a view whose neighbours know nothing (an exhaustive search) and two
    weightings; with the index histogram, the same ranking and the same use counted. The
    last call searches every voxel at once (Kopf's overlap rule), neighbours included: each
    reads its neighbours' matches as the call began (read in place, the result would depend on
    the order the work-items run in)."""
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
    twins = [Coherence(rows, cols, pyr[0].shape, similar, shape, views, spread_eps) for _ in range(2)]
    # about 1 in 4 unknown; the known ones crowded on few sites, so that the use weighs
    known = rng.integers(-rows.size // 3, rows.size, (len(views), int(np.prod(shape)))) // 8
    vol, coarse = rng.random(shape) * 255, (rng.random((3, 5, 5)) * 255 if parent else None)
    for twin in twins:
        twin.matched[...] = np.maximum(known, -1)
        twin.count_usage()
    colour = colour_sets(shape, k // 2)[0].ravel()  # conflict-free, as the driver's sets
    calls = [(False, np.flatnonzero(colour == colour[0])),  # at a corner every square wraps
             (True, np.flatnonzero(colour == colour[-1])), (True, np.arange(vol.size))]
    for centre, voxels in calls:
        w = centre_weights(k, parent, centre)
        for i, view in enumerate(views):
            got = twins[0].search(matcher, i, voxels, vol, coarse, k, w)
            want = twins[1].best(matcher, i, voxels, voxel_features(vol, coarse, voxels, view, k), w)
            np.testing.assert_array_equal(got[0], want[0])
            np.testing.assert_array_equal(got[1], want[1])
            np.testing.assert_array_equal(twins[0].matched, twins[1].matched)
            if spread_eps is not None:
                np.testing.assert_array_equal(twins[0].usage, twins[1].usage)
        for twin in twins:  # nothing known in the front view: every voxel searched exhaustively there
            twin.matched[0] = -1
            twin.count_usage()
        twins[0]._device._sent[0] = False  # the host's copy changed: the device's is sent again


@pytest.mark.parametrize("method, scales", slow_except([("wl", 1), ("kopf", 1), ("chen-wang", 1), ("kopf", 2)], 2))
def test_opencl_run_matches_the_reference(device, method, scales):
    """One scale: integer grey levels, float32 distances are exact, the blocks identical. Two:
    the coarser level's blurred values can tip near ties, and one tipped match changes the
    voxels matched after it (chen-wang's discrete choices differ on a few per cent of voxels),
    so kopf's weighted means are asked to agree on 90 % of the voxels, without the histogram
    specification, which ranks them (a float32 tip swaps two ranks). Two views: the mean of two
    integer levels is exact in float32, the mean of three (thirds) is not, and tips ties too."""
    ex = gallery_exemplar("composite3", 64)[:32, :32].astype(np.float64)
    params = SearchParams(method=method, neighborhood=5, scales=scales, iterations=2, search="coherence",
                          specify=False, views=2)
    ref = run_search(ex, (10, 12, 14), params, 3, ReferenceMatcher).volume
    got = run_search(ex, (10, 12, 14), params, 3, partial(CLMatcher, device)).volume
    if scales == 1:
        np.testing.assert_array_equal(got, ref)
    agree = np.mean(np.isclose(ref, got, rtol=0, atol=1e-3))
    assert agree >= 0.9, f"only {agree:.2%} of voxels agree with the float64 reference"


@pytest.mark.slow
@pytest.mark.parametrize("method", ["wl", "kopf", "chen-wang"])
def test_exact_passes_search_every_site_and_seed_the_candidates(device, method):
    """exact_passes = every pass: the exact search's block, bit for bit (the coherence state
    is only recorded). One exact pass: its matches are what the next passes' candidates come
    from, on the device as with the float64 reference, and the block is not the one
    without it."""
    ex = gallery_exemplar("composite3", 64)[:32, :32].astype(np.float64)
    common = dict(method=method, neighborhood=5, scales=2, iterations=3, specify=False, views=2)  # exact halves
    make = partial(CLMatcher, device)
    exact = run_search(ex, (10, 12, 14), SearchParams(search="exact", **common), 3, make).volume
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
        SearchParams(method="kopf", search="exact", exact_passes=1)
    with pytest.raises(InputError, match="exact_passes"):
        SearchParams(method="kopf", search="coherence", exact_passes=-1)


def test_one_exact_pass_is_kopfs_default_on_grey_exemplars_only():
    def resolved(n_values=256, **kw):
        return SearchParams(**kw).for_exemplar(n_values, is_categorical(n_values)).exact_passes

    assert SearchParams(method="kopf").exact_passes is None  # until the exemplar is known
    # grey: docs/design.md#exhaustive-first-pass
    assert resolved(method="kopf") == 1 and resolved(9, method="kopf") == 1
    for phases in (2, 8):  # categorical: it gained nothing there
        assert resolved(phases, method="kopf") == 0
        assert resolved(phases, method="kopf", exact_passes=2) == 2
    assert resolved(method="kopf", exact_passes=0) == 0
    assert resolved(method="kopf", search="exact") == 0  # every pass is exhaustive anyway
    assert resolved(method="wl", search="coherence") == 0 and resolved(method="chen-wang", search="coherence") == 0


@pytest.mark.slow
def test_the_coarser_levels_search_every_site(device):
    """coherence_levels=1 (kopf's default, as its coherence search): the coarser level is the exact search's, bit for bit,
    and the finest is not; coherence_levels=2 searches the coarser level among the candidates
    too (as wl and chen-wang do)."""
    ex = gallery_exemplar("gravel", 64)[:32, :32].astype(np.float64)
    common = dict(method="kopf", neighborhood=5, scales=2, iterations=2)
    coarse = {}

    def runs(name, **kw):
        def keep(info):
            if info.scale == 1:
                coarse[name] = info.volume()
        return run_search(ex, (10, 12, 14), SearchParams(**common, **kw), 3, partial(CLMatcher, device),
                          progress=keep).volume

    exact, default, every = runs("exact", search="exact"), runs("default"), runs("every", coherence_levels=2)
    np.testing.assert_array_equal(coarse["default"], coarse["exact"])
    assert not np.array_equal(coarse["every"], coarse["exact"])
    assert not np.array_equal(default, exact) and not np.array_equal(default, every)


def test_coherence_levels_need_the_coherence_search():
    for given in (1, 2):
        with pytest.raises(InputError, match="search='coherence'"):
            SearchParams(method="kopf", search="exact", coherence_levels=given)
    for bad in (0, 9, 1.5, True):
        with pytest.raises(InputError, match="coherence_levels"):
            SearchParams(method="kopf", search="coherence", coherence_levels=bad)
    assert SearchParams(method="kopf", search="exact").coherence_levels is None  # nothing to say
    assert SearchParams(method="kopf").coherence_levels == 1  # kopf's default (docs/design.md#coherence-levels)
    for method in ("wl", "chen-wang"):  # every level
        assert SearchParams(method=method, search="coherence", scales=4).coherence_levels == 4
    params = SearchParams(method="chen-wang", search="coherence", coherence_levels=1)
    assert SearchParams.from_dict(params.to_dict()) == params
    assert SearchParams.from_dict(SearchParams(method="wl").to_dict()) == SearchParams(method="wl")


def test_the_estimate_counts_each_levels_search():
    """The progress report's ETA: an exhaustive coarser level before the first level among the
    candidates costs about a third of it (brick, 64^3), not an eighth."""
    from clsolid.search.driver import _report

    img, vol = np.zeros((4, 4)), np.zeros((2, 2, 2))
    params = SearchParams(method="kopf", search="coherence", scales=3, iterations=10)
    eta = _report(params, 1, 10, (8, 8, 8), 1.0, 0.0, img, vol).eta  # the last pass of the exhaustive level 1
    assert eta == pytest.approx(10 * 3.0)
    every = SearchParams(method="kopf", search="coherence", scales=3, iterations=10, coherence_levels=3)
    assert _report(every, 2, 9, (4, 4, 4), 1.0, 0.0, img, vol).eta == pytest.approx(1 + 10 * 8 + 10 * 64)
    exact = SearchParams(method="kopf", search="exact", scales=3, iterations=10)
    assert _report(exact, 2, 10, (4, 4, 4), 1.0, 0.0, img, vol).eta == pytest.approx(10 * 32 + 10 * 32 * 32)


@pytest.mark.slow
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


@pytest.mark.slow
def test_synthesize_and_cli_take_the_search(tmp_path):
    import json

    from clsolid.cli import main

    a = clsolid.synthesize("brick", (8, 8, 8), method="kopf", search="coherence", iterations=1, rng=1)
    b = clsolid.synthesize("brick", (8, 8, 8), method="kopf", search="coherence", iterations=1, rng=1)
    assert np.array_equal(a, b)
    # kopf's default search; the others' is the exact one
    np.testing.assert_array_equal(clsolid.synthesize("brick", (8, 8, 8), method="kopf", iterations=1, rng=1), a)
    assert [SearchParams(method=m).search for m in ("kopf", "wl", "chen-wang")] == ["coherence", "exact", "exact"]
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
    assert main(["synth", "brick", "-o", str(out), "--method", "kopf", "--search", "coherence", "--coherence-levels",
                 "3", "--shape", "8", "8", "8", "--iterations", "2", "--seed", "1", "-q"]) == 0
    assert json.loads((tmp_path / "k.json").read_text())["params"]["coherence_levels"] == 3
    want = clsolid.synthesize("brick", (8, 8, 8), method="kopf", search="coherence", coherence_levels=3, iterations=2,
                              rng=1)
    np.testing.assert_array_equal(np.load(out), want)
    assert main(["synth", "brick", "-o", str(out), "--method", "kopf", "--search", "exact", "--coherence-levels", "2",
                 "--shape", "8", "8", "8"]) != 0
    assert main(["synth", "brick", "-o", str(out), "--method", "wl", "--search", "coherence", "--shape", "8", "8", "8",
                 "--iterations", "1", "-q"]) == 0
    assert json.loads((tmp_path / "k.json").read_text())["params"]["coherence_levels"] == 3  # every level


def _phase_table(rng, n_sites=300, dim=12, phases=(0.0, 1.0, 2.0)):
    table = rng.integers(0, 4, (n_sites, dim)).astype(np.float32)  # integer terms: float32 sums are exact
    centres = rng.choice(phases, n_sites, p=[0.8, 0.15, 0.05])
    return table, centres


@pytest.mark.parametrize("mismatch", [0, 6])
def test_phase_nearest_is_each_phases_nearest_site(mismatch):
    """Against explicit loops over every site (float64), lowest index on a tie."""
    rng = np.random.default_rng(5)
    table, centres = _phase_table(rng)
    w = rng.integers(1, 3, table.shape[1]).astype(np.float64)
    got = phase_nearest(partial(ReferenceMatcher, weights=w), table, centres, w, mismatch)
    phases = np.unique(centres)
    assert got.shape == (table.shape[0], phases.size)
    for s in range(table.shape[0]):
        for j, phase in enumerate(phases):
            diff = table[s].astype(np.float64) - table.astype(np.float64)
            terms = diff ** 2
            if mismatch:
                a, b = table[s, :mismatch], table[:, :mismatch]
                terms[:, :mismatch] = (a != b) * (a + b)
            d = np.where(centres == phase, terms @ w, np.inf)
            assert got[s, j] == np.flatnonzero(d == d.min())[0]
            assert centres[got[s, j]] == phase


@pytest.mark.each_device
def test_phase_nearest_on_the_device_is_the_references(device):
    rng = np.random.default_rng(6)
    table, centres = _phase_table(rng, n_sites=500)
    w = np.ones(table.shape[1])
    want = phase_nearest(ReferenceMatcher, table, centres, w, 6)
    np.testing.assert_array_equal(phase_nearest(partial(CLMatcher, device), table, centres, w, 6), want)


@pytest.mark.slow
def test_a_minority_phase_survives_the_coherence_search(device):
    """composite4's 4.6 % phase: the neighbours' matches alone stop proposing it, and kopf's
    balance chooses only among proposed phases; with each phase's nearest site among the
    candidates every phase stays within a point (docs/design.md#coherence-levels)."""
    ex = gallery_exemplar("composite4", 64)
    vol = clsolid.synthesize(ex, (24, 24, 24), method="kopf", search="coherence", rng=1, device=device)
    values, counts = np.unique(ex, return_counts=True)
    got = np.array([(vol == v).mean() for v in values])
    assert np.abs(got - counts / counts.sum()).max() < 0.01, (values, got, counts / counts.sum())


def test_the_index_histogram_defaults_where_it_was_measured_better_and_is_checked():
    def resolved(n_values=256, **kw):
        return SearchParams(**kw).for_exemplar(n_values, is_categorical(n_values)).index_histogram

    assert SearchParams(method="kopf", search="coherence").index_histogram is None  # until the exemplar is known
    assert resolved(method="kopf", search="coherence") is True  # grey (docs/design.md#index-histogram)
    assert resolved(9, method="kopf", search="coherence") is True
    for phases in (2, 8):  # categorical: it copied more of the exemplar (docs/design.md#index-histogram)
        assert resolved(phases, method="kopf", search="coherence") is False
        assert resolved(phases, method="kopf", search="coherence", index_histogram=True) is True
    assert resolved(method="kopf", search="exact") is False  # no candidates to rank
    for n_values in (2, 256):  # better on both kinds (docs/design.md#index-histogram)
        assert resolved(n_values, method="wl", search="coherence") is True
    assert resolved(method="wl") is False
    assert resolved(method="wl", search="coherence", index_histogram=False) is False
    assert resolved(method="chen-wang", search="coherence") is False
    with pytest.raises(InputError, match="search='coherence'"):
        SearchParams(method="kopf", search="exact", index_histogram=True)
    with pytest.raises(InputError, match="its own index histogram"):
        SearchParams(method="chen-wang", search="coherence", index_histogram=True)
    with pytest.raises(InputError, match="index_histogram"):
        SearchParams(method="kopf", search="coherence", index_histogram=1)
    params = SearchParams(method="kopf", search="coherence", index_histogram=False)
    assert SearchParams.from_dict(params.to_dict()) == params


@pytest.mark.slow
def test_synthesize_and_cli_take_the_index_histogram(tmp_path):
    import json

    from clsolid.cli import main

    ex = tmp_path / "hrtem.npy"
    np.save(ex, gallery_exemplar("hrtem", 64)[:32, :32])
    common = dict(method="kopf", search="coherence", iterations=2, rng=1)
    on, off = (clsolid.synthesize(ex, (12, 12, 12), index_histogram=flag, **common) for flag in (True, False))
    assert not np.array_equal(on, off)
    np.testing.assert_array_equal(clsolid.synthesize(ex, (12, 12, 12), **common), on)  # the default
    out = tmp_path / "k.npy"
    assert main(["synth", str(ex), "-o", str(out), "--method", "kopf", "--search", "coherence", "--no-index-histogram",
                 "--shape", "12", "12", "12", "--iterations", "2", "--seed", "1", "-q"]) == 0
    assert json.loads((tmp_path / "k.json").read_text())["params"]["index_histogram"] is False
    np.testing.assert_array_equal(np.load(out), off)
    assert main(["synth", str(ex), "-o", str(out), "--method", "kopf", "--search", "exact", "--index-histogram",
                 "--shape", "12", "12", "12"]) != 0
    assert main(["synth", str(ex), "-o", str(out), "--index-histogram", "--shape", "12", "12", "12"]) != 0  # ml
