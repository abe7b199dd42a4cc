"""NP_CW (clsolid.search.chenwang): candidate sets, histogram weights and the discrete solver
against hand computations, live histograms against direct counts, the OpenCL run against
the float64 reference, and the promise that the block holds only exemplar pixels."""

from functools import partial

import numpy as np
import pytest
from conftest import slow_except

import clsolid
from clsolid.cli import main
from clsolid.gallery import gallery_exemplar
from clsolid.search import chenwang, driver, usage
from clsolid.search.driver import run_search
from clsolid.search.match import (CLMatcher, ReferenceMatcher, candidate_sets, exemplar_table,
                                  k_nearest_reference)
from clsolid.search.params import SearchParams


def test_candidate_sets_hold_the_site_first_then_its_nearest_others():
    ex = np.random.default_rng(0).integers(0, 256, (20, 20))
    table, _ = exemplar_table(ex, 5)
    cands = candidate_sets(ReferenceMatcher(table), table, 6, np.ones(25, np.float32))
    assert cands.shape == (table.shape[0], 6)
    assert np.array_equal(cands[:, 0], np.arange(table.shape[0]))
    near = k_nearest_reference(table, table, 6)[0]
    np.testing.assert_array_equal(cands[:, 1:], near[:, 1:])  # random grey levels: each site nearest to itself


def test_among_equal_neighbourhoods_the_site_is_still_its_own_first_candidate():
    ex = np.zeros((12, 12))
    ex[::5, ::5] = 255  # mostly flat: dozens of identical all-zero squares
    table, _ = exemplar_table(ex, 3)
    cands = candidate_sets(ReferenceMatcher(table), table, 4, np.ones(9, np.float32))
    assert np.array_equal(cands[:, 0], np.arange(table.shape[0]))
    assert all(len(set(row)) == 4 for row in cands.tolist())  # no site twice
    flat = np.flatnonzero(~table.any(axis=1))
    late = flat[-1]  # a flat site past the first three flat ones: they are its nearest others
    assert cands[late].tolist() == [late] + flat[:3].tolist()


def test_excess_factor_is_one_up_to_the_uniform_level():
    np.testing.assert_allclose(usage.excess_factor(np.array([0, 5, 10, 20, 40]), 10.0), [1, 1, 1, 2, 4])


def test_discrete_solver_takes_the_value_nearest_the_weighted_mean():
    values = np.array([[0.0, 10.0, 4.0], [10.0, 0.0, 6.0]])
    weights = np.array([[3.0, 1.0, 1.0], [1.0, 1.0, 1.0]])
    # means 2.5 -> 0 (row 0); 5 -> tie between 10 and 0, the first row; 5 -> tie, the first row
    assert chenwang.solve(values, weights).tolist() == [0, 0, 0]
    assert chenwang.solve(values, np.array([[1.0, 1.0, 1.0], [3.0, 3.0, 3.0]])).tolist() == [1, 1, 1]


def _levels_seen(monkeypatch):
    """Record the Level objects chen-wang's update is called with."""
    seen = []

    def spy(level, vol, coarse, voxels):
        seen.append(level)
        return chenwang.update(level, vol, coarse, voxels)

    monkeypatch.setitem(driver.UPDATES, "chen-wang", spy)
    return seen


@pytest.mark.slow
def test_histograms_are_live_counts_of_the_current_choices(device, monkeypatch):
    seen = _levels_seen(monkeypatch)
    ex = gallery_exemplar("grains", 64)[:32, :32].astype(np.float64)
    out = run_search(ex, (8, 10, 12), SearchParams(method="chen-wang", neighborhood=5, scales=2, iterations=3, views=2), 4,
                     partial(CLMatcher, device))
    src = seen[-1].sources
    n_sites = src.index.size
    assert (src.chosen >= 0).all() and (src.source >= 0).all()
    np.testing.assert_array_equal(src.index, np.bincount(src.chosen.ravel(), minlength=n_sites))
    np.testing.assert_array_equal(src.position, np.bincount(src.source, minlength=n_sites))
    assert src.theta == pytest.approx(8 * 10 * 12 / n_sites) and src.phi == pytest.approx(2 * src.theta)
    np.testing.assert_array_equal(out.volume.ravel(), seen[-1].centres[src.source])


@pytest.mark.parametrize("name", slow_except(["composite3", "gravel"], 1))
@pytest.mark.parametrize("scales, least", slow_except([(1, 1.0), (2, 0.9)], 0))
def test_opencl_run_matches_the_reference(device, name, scales, least):
    """One scale: whole grey levels, float32 distances exact, the same volume. Two: the coarser
    level's blurred values hold ties in exact arithmetic (composite3's three phases above all)
    that float32 sums break either way, each an equally good match, and a broken tie changes
    the voxels chosen after it: 90 % must agree."""
    ex = gallery_exemplar(name, 64)[:32, :32].astype(np.float64)
    params = SearchParams(method="chen-wang", neighborhood=5, scales=scales, iterations=2, candidates=7)
    ref = run_search(ex, (10, 12, 14), params, 3, ReferenceMatcher)
    got = run_search(ex, (10, 12, 14), params, 3, partial(CLMatcher, device))
    agree = np.mean(ref.volume == got.volume)
    assert agree >= least, f"only {agree:.2%} of voxels agree with the float64 reference"


@pytest.mark.slow
def test_block_holds_only_exemplar_pixels_and_the_source_map_says_which(device):
    ex = gallery_exemplar("gravel", 64)
    res = clsolid.synthesize(ex, (16, 16, 16), method="chen-wang", iterations=2, rng=5, device=device,
                             full_output=True, site_map=True)
    img = res.exemplar
    assert res.source.shape == (16, 16, 16, 2) and res.source.dtype == np.int64
    np.testing.assert_array_equal(img[res.source[..., 0], res.source[..., 1]], res.volume)
    assert np.isin(res.volume, img).all() and np.unique(res.volume).size > 16
    assert res.volume.dtype == np.uint8  # copies, in the exemplar's dtype (gravel's 8 bits)
    assert res.site_use[res.site_use >= 0].sum() == res.volume.size  # chen-wang's map: each voxel's source, once
    r, c = res.source.reshape(-1, 2).T
    np.testing.assert_array_equal(res.site_use[res.site_use >= 0],
                                  np.bincount(r * 64 + c, minlength=64 * 64).reshape(64, 64)[res.site_use >= 0])


@pytest.mark.slow
def test_same_seed_same_volume_and_another_seed_another(device):
    run = lambda seed: clsolid.synthesize("brick", (12, 12, 12), method="chen-wang", iterations=2, rng=seed,
                                          device=device)
    a, b, c = run(3), run(3), run(4)
    assert np.array_equal(a, b) and not np.array_equal(a, c)


@pytest.mark.slow
@pytest.mark.parametrize("search", ["exact", "coherence"])
def test_a_set_gathered_in_chunks_gives_the_same_volume(device, monkeypatch, search):
    """The host gathers a large set's neighbourhoods a chunk at a time (memory); a view's
    choices all see the same index histogram, so the volume is the one-chunk one."""
    run = lambda: clsolid.synthesize("brick", (12, 14, 16), method="chen-wang", iterations=2, rng=5,
                                     device=device, search=search)
    whole = run()
    monkeypatch.setattr(chenwang, "CHUNK", 7)
    np.testing.assert_array_equal(run(), whole)


@pytest.mark.slow
def test_more_candidates_use_the_exemplar_more_evenly(device):
    """The thesis's Fig. 5.7: a larger candidate set gives a more uniform position histogram
    (porous50, 24^3: spread of the counts 16.4 with k = 1, 6.8 with k = 15)."""
    spread = {}
    for k in (1, 15):
        res = clsolid.synthesize(gallery_exemplar("porous50", 64), (24, 24, 24), method="chen-wang", iterations=3,
                                 candidates=k, rng=2, views=2, device=device, full_output=True, site_map=True)
        spread[k] = res.site_use[res.site_use >= 0].std()
    assert spread[15] < 0.7 * spread[1], spread


@pytest.mark.parametrize("kwargs, word", [
    (dict(method="chen-wang", candidates=0), "candidates=0"),
    (dict(method="chen-wang", candidates=65), "candidates=65"),
    (dict(method="kopf", candidates=5), "chen-wang's candidate set"),
])
def test_bad_parameters_name_themselves(kwargs, word):
    with pytest.raises(clsolid.InputError, match=word):
        SearchParams(**kwargs)


def test_cli_writes_the_source_map(tmp_path, device):
    out = tmp_path / "v.npy"
    argv = ["synth", "brick", "-o", str(out), "--shape", "8", "8", "8", "--method", "chen-wang", "--iterations", "1",
            "--candidates", "5", "--source-map", str(tmp_path / "src.npy"), "--seed", "1", "-q"]
    assert main(argv) == 0
    src, vol = np.load(tmp_path / "src.npy"), np.load(out)
    assert src.shape == (8, 8, 8, 2)
    ex = clsolid.synthesize("brick", (8, 8, 8), method="chen-wang", iterations=1, candidates=5, rng=1,
                            full_output=True).exemplar
    np.testing.assert_array_equal(ex[src[..., 0], src[..., 1]], vol)


@pytest.mark.parametrize("argv, word", [
    (["--method", "kopf", "--source-map", "s.npy"], "--source-map not used by --method kopf"),
    (["--method", "chen-wang", "--source-map", "s.png"], "must end in .npy"),
    (["--candidates", "5"], "--candidates"),
])
def test_cli_refuses_a_misplaced_source_map_or_candidates(tmp_path, argv, word, capsys):
    assert main(["synth", "brick", "-o", str(tmp_path / "v.npy"), "--shape", "8", "8", "8", *argv]) != 0
    assert word in capsys.readouterr().err


def test_a_smaller_candidate_set_is_a_larger_ones_first_columns():
    """The driver computes one set for chen-wang and the coherence search and slices it."""
    ex = np.zeros((14, 14))
    ex[::4, ::3] = 255  # many equal squares: ties decide the order
    table, _ = exemplar_table(ex, 3)
    matcher, w = ReferenceMatcher(table), np.ones(9, np.float32)
    big = candidate_sets(matcher, table, 15, w)
    for count in (1, 4, 7):
        np.testing.assert_array_equal(candidate_sets(matcher, table, count, w), big[:, :count])
