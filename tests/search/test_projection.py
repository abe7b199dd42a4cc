"""The seeding passes' search on principal components (clsolid.search.projection): the
float64 reference by hand, the device against it, and what seed_components does to a run."""

from functools import partial

import numpy as np
import pytest

import clsolid
from clsolid.gallery import gallery_exemplar
from clsolid.search.block import DeviceBlock
from clsolid.search.driver import run_search
from clsolid.search.features import centre_weights, exemplar_features, voxel_features
from clsolid.search.match import CLMatcher, ReferenceMatcher, best_match_reference
from clsolid.search.params import SearchParams
from clsolid.search.projection import Projection
from clsolid.search.pyramid import gaussian_pyramid


def _level(parent=True, k=5):
    pyr = gaussian_pyramid(gallery_exemplar("gravel", 64)[:28, :30].astype(np.float64), 2)
    table, _ = exemplar_features(pyr[0], pyr[1] if parent else None, k)
    return table.astype(np.float64), centre_weights(k, parent, centre=False)


def test_the_reference_is_the_nearest_site_on_the_components_measured_on_every_term():
    table, w = _level()
    rng = np.random.default_rng(0)
    queries = table[rng.integers(0, table.shape[0], 50)] + rng.normal(0, 20, (50, table.shape[1]))
    proj = Projection(table, w, 6)
    assert proj.components == 6
    np.testing.assert_allclose(proj.basis @ proj.basis.T, np.eye(6), atol=1e-9)  # orthonormal
    site, dist = proj.best_reference(queries)
    # by hand: the weighted, centred rows on the six leading right singular vectors
    rows = table * np.sqrt(w)
    centred = rows - rows.mean(axis=0)
    vt = np.linalg.svd(centred, full_matrices=False)[2][:6]
    on = ((queries * np.sqrt(w) - rows.mean(axis=0)) @ vt.T)[:, None, :] - (centred @ vt.T)[None]
    np.testing.assert_array_equal(site, np.argmin((on**2).sum(-1), axis=1))
    np.testing.assert_allclose(dist, ((queries - table[site]) ** 2 @ w), rtol=1e-6)
    # every component: the exact search (distances are kept, a rotation)
    exact, least = best_match_reference(queries, table, w)
    full_site, full_dist = Projection(table, w, table.shape[1]).best_reference(queries)
    np.testing.assert_array_equal(full_site, exact)
    np.testing.assert_allclose(full_dist, least, rtol=1e-5)
    # fewer: never nearer than the exact match, and mostly it
    assert (dist >= least * (1 - 1e-6)).all() and np.mean(site == exact) >= 0.5


@pytest.mark.each_device
@pytest.mark.parametrize("parent", [False, True])
def test_the_device_projects_and_searches_as_the_reference(device, parent):
    """Queries gathered and projected on the device (float32) against NumPy's gathers and
    float64 projections: the same site for nearly every voxel (a float32 sum can tip a near
    tie), and where the site is the same, the same distance."""
    table, w = _level(parent)
    rng = np.random.default_rng(1)
    shape, k = (9, 10, 11), 5
    vol = np.round(rng.random(shape) * 255)
    coarse = np.round(rng.random((5, 5, 6)) * 255) if parent else None
    matcher = CLMatcher(device, table, max_batch=200)  # several launches
    proj = Projection(matcher.table, w, 8)
    voxels = rng.permutation(vol.size)[:700]
    for view in ("front", "right", "top"):
        got_site, got_dist = DeviceBlock(matcher).best_projected(view, voxels, vol, coarse, k, proj)
        want_site, want_dist = proj.best_reference(voxel_features(vol, coarse, voxels, view, k))
        same = got_site == want_site
        assert same.mean() >= 0.98, same.mean()
        np.testing.assert_allclose(got_dist[same], want_dist[same], rtol=1e-6)


@pytest.mark.slow
def test_seed_components_change_only_the_seeding_passes(device):
    """0: the exhaustive seeding pass (every pass exhaustive = the exact search, bit for
    bit). 16 on a grey exemplar: another block, as near the exemplar; on the float64
    reference as on the device. On phase codes (kopf's categorical exemplars) the passes
    compare every term whatever it is."""
    ex = gallery_exemplar("gravel", 64)[:32, :32].astype(np.float64)
    common = dict(method="kopf", neighborhood=5, scales=1, iterations=3, specify=False, search="coherence")
    make = partial(CLMatcher, device)

    def grow(make_matcher=make, exemplar=ex, **kw):
        return run_search(exemplar, (10, 12, 14), SearchParams(**{**common, **kw}), 3, make_matcher).volume

    exact = run_search(ex, (10, 12, 14), SearchParams(**{**common, "search": "exact"}), 3, make).volume
    np.testing.assert_array_equal(grow(exact_passes=3, seed_components=0), exact)
    every, projected = grow(exact_passes=1, seed_components=0), grow(exact_passes=1, seed_components=16)
    assert not np.array_equal(every, projected)
    reference = grow(ReferenceMatcher, exact_passes=1, seed_components=16)  # float64 weights: means within 1e-3
    assert np.mean(np.isclose(reference, projected, rtol=0, atol=1e-3)) >= 0.9
    phases = gallery_exemplar("composite3", 64)[:32, :32].astype(np.float64)
    np.testing.assert_array_equal(grow(exemplar=phases, exact_passes=1, seed_components=16),
                                  grow(exemplar=phases, exact_passes=1, seed_components=0))


def test_seed_components_defaults_and_checks(tmp_path):
    import json

    from clsolid.cli import main

    assert [SearchParams(method=m, search="coherence").seed_components for m in ("kopf", "wl", "chen-wang")] == [
        16, 0, 0]
    assert SearchParams(method="kopf", search="exact").seed_components is None
    with pytest.raises(clsolid.InputError, match="seed_components"):
        SearchParams(method="kopf", search="exact", seed_components=8)
    with pytest.raises(clsolid.InputError, match="seed_components"):
        SearchParams(method="kopf", seed_components=-1)
    out = tmp_path / "k.npy"
    assert main(["synth", "brick", "-o", str(out), "--method", "kopf", "--seed-components", "8", "--shape", "8", "8",
                 "8", "--iterations", "2", "--seed", "1", "-q"]) == 0
    assert json.loads((tmp_path / "k.json").read_text())["params"]["seed_components"] == 8
    np.testing.assert_array_equal(np.load(out), clsolid.synthesize("brick", (8, 8, 8), method="kopf",
                                                                   seed_components=8, iterations=2, rng=1))
    assert main(["synth", "brick", "-o", str(out), "--seed-components", "8", "--shape", "8", "8", "8"]) != 0  # ml
