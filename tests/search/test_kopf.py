"""NP_K (clsolid.search.kopf): its weights, vote and histogram against hand computations,
the OpenCL run against the float64 reference, and a categorical exemplar kept in phases."""

from functools import partial

import numpy as np
import pytest
from conftest import slow_except

import clsolid
from clsolid.gallery import gallery_exemplar
from clsolid.search.driver import run_search
from clsolid.search.kopf import vote
from clsolid.search.level import LevelHistogram
from clsolid.search.match import CLMatcher, ReferenceMatcher, best_match_reference
from clsolid.search.params import SearchParams
from clsolid.search.specify import specify_histogram


def test_vote_takes_the_value_with_most_weight():
    values = np.array([[0.0, 1.0, 2.0, 5.0], [1.0, 1.0, 3.0, 5.0], [1.0, 0.0, 2.0, 6.0]])
    weights = np.array([[3.0, 1.0, 1.0, 1.0], [1.0, 1.0, 5.0, 1.0], [1.0, 5.0, 1.0, 1.0]])
    # column 0: 0 has 3, 1 has 2; column 1: 1 has 2, 0 has 5; column 2: 2 has 2, 3 has 5; column 3: 5 has 2
    assert vote(values, weights).tolist() == [0.0, 0.0, 3.0, 5.0]


def test_level_histogram_bins_and_follows_changes():
    finest = np.array([[0.0, 85.0], [170.0, 255.0]])
    vol = np.array([0.0, 0.0, 100.0, 250.0])
    h = LevelHistogram(finest, np.array([10.0, 80.0, 90.0, 240.0]), vol)
    assert h.exemplar.tolist() == [0.25, 0.5, 0.0, 0.25]  # nearest of 0, 85, 170, 255
    assert h.volume.tolist() == [0.5, 0.25, 0.0, 0.25]
    h.replace(np.array([0.0]), np.array([200.0]))
    assert h.volume.tolist() == [0.25, 0.25, 0.25, 0.25]


@pytest.mark.parametrize("name, views", slow_except([("composite3", 2), ("gravel", 3)], 1))
def test_opencl_run_matches_the_reference(device, name, views):
    ex = gallery_exemplar(name, 64)[:32, :32].astype(np.float64)
    # without the histogram specification: it ranks the voxels, and a float32 difference in
    # the last bits of two near-equal means swaps their ranks and so their values
    # the exact search, the reference path (the coherence search's run: tests/search/test_coherence.py)
    params = SearchParams(method="kopf", neighborhood=5, scales=2, iterations=2, views=views, specify=False,
                          search="exact")
    ref = run_search(ex, (10, 12, 14), params, 3, ReferenceMatcher)[0]
    got = run_search(ex, (10, 12, 14), params, 3, partial(CLMatcher, device))[0]
    # weighted means: float32 distances move the weights in their last bits, so the values
    # agree to a thousandth of a grey level, not exactly
    agree = np.mean(np.isclose(ref, got, rtol=0, atol=1e-3))
    assert agree >= 0.99, f"only {agree:.2%} of voxels agree with the float64 reference"


@pytest.mark.slow
def test_a_categorical_exemplar_stays_in_phases_and_a_grey_one_blends(device):
    vol = clsolid.synthesize(gallery_exemplar("composite3", 64), (16, 16, 16), method="kopf", iterations=2,
                             rng=1, device=device)
    assert set(np.unique(vol)) <= {0, 128, 255} and np.unique(vol).size == 3
    assert vol.dtype == np.uint8  # phases, in the exemplar's dtype
    grey = clsolid.synthesize("gravel", (16, 16, 16), method="kopf", iterations=2, specify=False, rng=1,
                              device=device)
    assert np.unique(grey).size > 64 and grey.dtype == np.float64  # weighted means of 32 levels
    specified = clsolid.synthesize(gallery_exemplar("gravel", 64), (16, 16, 16), method="kopf", iterations=2,
                                   rng=1, device=device, full_output=True)
    # mapped onto the exemplar's histogram: its 32 levels' values, in its dtype
    assert specified.volume.dtype == np.uint8 and np.isin(specified.volume, specified.level_values).all()


@pytest.mark.slow
def test_kopf_keeps_the_minority_phase_better_than_wl(device):
    """porous80: the histogram re-weighting pulls the pore fraction toward the exemplar's."""
    ex = gallery_exemplar("porous80", 64)
    want = np.mean(ex == 0)
    err = {m: abs(np.mean(clsolid.synthesize(ex, (24, 24, 24), method=m, iterations=3, rng=1,
                                             device=device) < 128) - want) for m in ("wl", "kopf")}
    assert err["kopf"] < err["wl"], err


# --------------------------------------------------------------------------- Kopf's own rule


def _slow_support(level, vol, coarse):
    """overlap_support by explicit loops: every voxel, view and offset, one proposal at a time."""
    from clsolid.core.views import VIEW_AXES
    from clsolid.phases import MAX_PHASES
    from clsolid.search.kopf import histogram_factor, robust_weights
    from clsolid.search.match import square_offsets
    from clsolid.search.wl import matches

    sites, ssd = matches(level, vol, coarse, np.arange(vol.size), level.w_first)
    hist = level.histogram
    w = robust_weights(ssd, float(hist.values[-1] - hist.values[0]))
    phases = level.values if level.values.size <= MAX_PHASES else None
    num = np.zeros((1 if phases is None else phases.size,) + vol.shape)
    den = np.zeros(vol.shape)
    for u in range(vol.size):
        pos = np.unravel_index(u, vol.shape)
        for i, view in enumerate(level.params.view_names):
            for j, (dr, dc) in enumerate(square_offsets(level.params.neighborhood)):
                v = list(pos)
                ra, ca = VIEW_AXES[view]
                v[ra], v[ca] = (v[ra] + dr) % vol.shape[ra], (v[ca] + dc) % vol.shape[ca]
                value = level.patches[sites[i, u], j]
                weight = w[i, u] * histogram_factor(level, hist.bin(np.array([value])))[0]
                den[tuple(v)] += weight
                if phases is None:
                    num[(0, *v)] += weight * value
                else:
                    num[(int(np.flatnonzero(phases == value)[0]), *v)] += weight
    return phases, num, den


@pytest.mark.parametrize("name", ["composite3", "gravel"])
def test_overlap_support_matches_explicit_loops(name):
    from clsolid.search.features import centre_weights, exemplar_features
    from clsolid.search.kopf import overlap_support
    from clsolid.search.level import Level

    ex = gallery_exemplar(name, 64)[:20, :20].astype(np.float64)
    k = 3
    table, centres = exemplar_features(ex, None, k)
    params = SearchParams(method="kopf", neighborhood=k, scales=1, rule="overlap")
    vol = np.random.default_rng(0).choice(ex.ravel(), size=(4, 5, 6))
    level = Level(params=params, matcher=ReferenceMatcher(table), centres=centres,
                  patches=table[:, : k * k].astype(np.float64), values=np.unique(ex),
                  w_first=centre_weights(k, False, centre=False), w_again=centre_weights(k, False, centre=True),
                  span=float(ex.max() - ex.min()), categorical=name == "composite3",
                  histogram=LevelHistogram(ex, ex, vol))
    phases, num, den, searches = overlap_support(level, vol, None)
    slow = _slow_support(level, vol, None)
    assert searches == len(params.view_names) * vol.size and (phases is None) == (name == "gravel")
    np.testing.assert_allclose(num, slow[1], rtol=1e-12)
    np.testing.assert_allclose(den, slow[2], rtol=1e-12)
    assert np.allclose(num.sum(axis=0), den) == (phases is not None)  # votes share out all the weight


def test_balanced_vote_meets_the_target_and_leaves_unproposed_phases_out():
    from clsolid.search.kopf import vote_balanced

    rng = np.random.default_rng(1)
    support = rng.gamma(2.0, size=(3, 4000)) * np.array([[4.0], [1.0], [1.0]])  # phase 0 favoured
    target = np.array([0.2, 0.5, 0.3])
    got = np.bincount(vote_balanced(support, target), minlength=3) / 4000
    assert np.abs(got - target).max() < 0.02, got
    assert np.bincount(np.argmax(support, axis=0), minlength=3)[0] / 4000 > 0.6  # unbalanced: the majority
    support[2] = 0.0
    assert 2 not in vote_balanced(support, target)


@pytest.mark.slow
def test_overlap_rule_keeps_fractions_and_is_reproducible(device):
    ex = gallery_exemplar("porous80", 64)
    # The minority phase is proposed by more voxels' squares pass after pass (6 % of the
    # voxels have any pore proposed at the first finest pass, 27 % by the tenth): 10 passes.
    run = lambda seed: clsolid.synthesize(ex, (24, 24, 24), method="kopf", rule="overlap", iterations=10,  # noqa: E731
                                          rng=seed, device=device)
    a = run(1)
    assert set(np.unique(a)) <= {0.0, 255.0}
    assert abs(np.mean(a == 0) - np.mean(ex == 0)) < 0.02
    np.testing.assert_array_equal(a, run(1))
    with pytest.raises(clsolid.InputError, match="rule"):
        clsolid.synthesize(ex, (8, 8, 8), method="wl", rule="overlap")


def test_cli_passes_the_rule(tmp_path, device):
    import json

    from clsolid.cli import main

    out = tmp_path / "k.npy"
    assert main(["synth", "brick", "-o", str(out), "--method", "kopf", "--rule", "overlap", "--shape", "8", "8", "8",
                 "--scales", "1", "--neighborhood", "5", "--iterations", "1", "--seed", "2", "-q"]) == 0
    assert json.loads((tmp_path / "k.json").read_text())["params"]["rule"] == "overlap"


@pytest.mark.parametrize("flag, want", [([], True), (["--no-specify"], False)])
def test_cli_passes_specify(tmp_path, device, flag, want):
    import json

    from clsolid.cli import main

    out = tmp_path / "k.npy"
    assert main(["synth", "gravel", "-o", str(out), "--method", "kopf", "--shape", "8", "8", "8", "--scales", "1",
                 "--neighborhood", "5", "--iterations", "1", "-q", *flag]) == 0
    assert json.loads((tmp_path / "k.json").read_text())["params"]["specify"] is want


@pytest.mark.parametrize("method, flags, want", [
    ("kopf", [], (4.0, "weighted")), ("kopf", ["--parent-weight", "2", "--distance", "squared"], (2.0, "squared")),
    ("wl", [], (1.0, "squared")), ("chen-wang", ["--distance", "weighted"], (1.0, "weighted"))])
def test_cli_passes_the_parent_weight_and_the_distance(tmp_path, device, method, flags, want):
    """The sidecar records them resolved (composite3: three phases)."""
    import json

    from clsolid.cli import main

    ex = tmp_path / "composite3.npy"
    np.save(ex, gallery_exemplar("composite3", 64))
    out = tmp_path / "k.npy"
    assert main(["synth", str(ex), "-o", str(out), "--method", method, "--shape", "8", "8", "8", "--scales",
                 "2", "--neighborhood", "3", "--iterations", "1", "--inner", "1", "-q", *flags]) == 0
    params = json.loads((tmp_path / "k.json").read_text())["params"]
    assert (params["parent_weight"], params["distance"]) == want


def test_cli_refuses_mls_parent_min_side_for_kopf(tmp_path, capsys):
    """--parent-weight is every method's (ml's since its parent terms); --parent-min-side is ml's."""
    from clsolid.cli import main

    assert main(["synth", "brick", "-o", str(tmp_path / "m.npy"), "--method", "kopf", "--parent-min-side", "0",
                 "-q"]) == 2
    assert "--parent-min-side not used by --method kopf" in capsys.readouterr().err


# --------------------------------------------------------------------------- position histogram


def test_site_use_counts_every_voxel_and_view(device):
    from clsolid.search.features import valid_sites

    ex = gallery_exemplar("porous50", 64)[:24, :24]
    res = clsolid.synthesize(ex, (8, 10, 12), method="kopf", neighborhood=5, scales=2, iterations=2, rng=1,
                             device=device, full_output=True, site_map=True)
    use = res.site_use
    assert use.shape == ex.shape and "site_use" not in res.timings
    assert use[use > 0].sum() == 3 * 8 * 10 * 12  # every voxel, every view, once
    r, c = valid_sites(ex.shape, (12, 12), 5)
    valid = np.zeros(ex.shape, bool)
    valid[r, c] = True
    assert np.all((use == -1) == ~valid)  # the border (and the parent's border) cannot be matched
    assert np.all(use[:2] == -1) and np.all(use[:, -2:] == -1)
    with pytest.raises(clsolid.InputError, match="full_output"):
        clsolid.synthesize(ex, (8, 8, 8), method="kopf", scales=1, site_map=True)
    with pytest.raises(clsolid.InputError, match="site_map"):
        clsolid.synthesize(ex, (8, 8, 8), site_map=True)  # not an ml option


def test_site_map_png_marks_unused_and_unmatchable_pixels(tmp_path):
    from PIL import Image

    from clsolid.preview import NO_SITE_RGB, UNUSED_RGB, save_site_map

    use = np.array([[-1, -1, -1], [-1, 0, 4], [-1, 1, 0]])
    img = np.asarray(Image.open(save_site_map(tmp_path / "m.png", use)))
    k = img.shape[0] // 3
    assert img.shape[0] >= 256 and tuple(img[0, 0]) == NO_SITE_RGB and tuple(img[k, k]) == UNUSED_RGB
    assert tuple(img[k, 2 * k]) == (255, 255, 255) and tuple(img[2 * k, k]) == (128, 128, 128)  # sqrt(1/4)
    with pytest.raises(clsolid.InputError, match="counts"):
        save_site_map(tmp_path / "bad.png", np.zeros((2, 2, 2), int))


def test_cli_writes_the_site_map(tmp_path, device):
    from clsolid.cli import main

    out = tmp_path / "k.npy"
    assert main(["synth", "brick", "-o", str(out), "--method", "kopf", "--shape", "8", "8", "8", "--scales", "1",
                 "--neighborhood", "5", "--iterations", "1", "--site-map", str(tmp_path / "map.png"), "-q"]) == 0
    assert (tmp_path / "map.png").stat().st_size > 100


def test_per_slice_histograms_follow_changes():
    finest = np.array([[0.0, 255.0]])
    vol = np.array([0.0, 255.0, 255.0, 0.0, 0.0, 0.0, 255.0, 0.0]).reshape(2, 2, 2)
    h = LevelHistogram(finest, finest, vol, ("front", "right"))

    def direct(view):
        axis = {"front": 0, "right": 2}[view]
        return np.stack([[np.sum(np.take(vol, d, axis=axis) == v) for v in (0.0, 255.0)] for d in range(2)])

    for view in ("front", "right"):
        np.testing.assert_array_equal(h.slices[view], direct(view))
    flat = vol.reshape(-1)
    voxels = np.array([1, 4])
    old, flat[voxels] = flat[voxels].copy(), [0.0, 255.0]
    h.replace(old, flat[voxels], voxels)
    for view in ("front", "right"):
        np.testing.assert_array_equal(h.slices[view], direct(view))
    np.testing.assert_allclose(h.slice_fractions("front", np.array([0, 7])), direct("front") / 4)


@pytest.mark.slow
def test_slice_histogram_option_runs_and_is_kopfs(device):
    ex = gallery_exemplar("porous80", 64)
    kw = dict(method="kopf", scales=2, iterations=2, rng=1, device=device)
    a = clsolid.synthesize(ex, (12, 12, 12), histogram="slice", **kw)
    b = clsolid.synthesize(ex, (12, 12, 12), **kw)
    assert set(np.unique(a)) <= {0.0, 255.0} and not np.array_equal(a, b)
    with pytest.raises(clsolid.InputError, match="histogram"):
        clsolid.synthesize(ex, (8, 8, 8), method="wl", histogram="slice")


def test_specify_histogram_keeps_the_order_and_takes_the_exemplars_quantiles():
    ex = np.arange(16.0).reshape(4, 4) * 10  # 0, 10, ..., 150
    block = np.array([[[3.0, -1.0], [7.0, 2.0]], [[2.0, 9.0], [0.5, 5.0]]])  # 8 voxels, 2.0 twice
    got = specify_histogram(block, ex)
    # rank i of 8 takes the exemplar's sorted value at (i + 1/2) * 16 / 8 = 1, 3, 5, ...
    want_by_rank = np.arange(1, 16, 2) * 10.0
    ranks = np.argsort(np.argsort(block.ravel(), kind="stable"), kind="stable")
    assert got.ravel().tolist() == want_by_rank[ranks].tolist()
    assert got[0, 1, 1] < got[1, 0, 0]  # the tie (2.0 at flat 3 and 4) goes to the lower flat index first


@pytest.mark.slow
def test_specify_restores_the_grey_levels_that_blending_narrows(device):
    ex = gallery_exemplar("gravel", 64)  # uint8
    kw = dict(method="kopf", iterations=2, levels=None, rng=1, device=device)  # the exemplar as it is
    plain = clsolid.synthesize(ex, (16, 16, 16), specify=False, **kw)  # the thesis's kopf
    spec = clsolid.synthesize(ex, (16, 16, 16), **kw)  # kopf's default
    assert plain.std() < 0.8 * ex.std()  # the means of matches pull every voxel to the middle
    quantiles = np.sort(ex.ravel()).astype(np.float64)[((np.arange(spec.size) + 0.5) * ex.size / spec.size).astype(int)]
    assert np.array_equal(np.sort(spec.ravel()), quantiles)


@pytest.mark.slow
def test_specify_leaves_a_categorical_exemplars_phases_alone(device):
    vol = clsolid.synthesize(gallery_exemplar("composite3", 64), (16, 16, 16), method="kopf", iterations=2,
                             specify=True, rng=1, device=device)
    assert set(np.unique(vol)) == {0.0, 128.0, 255.0}


@pytest.mark.parametrize("kw", [dict(method="chen-wang", specify=True), dict(method="kopf", specify=1)])
def test_specify_is_checked(kw):
    with pytest.raises(clsolid.InputError, match="specify"):
        SearchParams(**kw)


def test_specify_defaults_on_for_kopf_only():
    assert [SearchParams(method=m).specify for m in ("wl", "kopf", "chen-wang")] == [False, True, False]


def test_balanced_set_vote_moves_the_disputed_voxels_toward_the_exemplars_fractions():
    from types import SimpleNamespace

    from clsolid.search.kopf import balanced_set_vote

    ex = np.array([[0.0, 255.0], [0.0, 255.0]])  # 50/50
    block = np.zeros((1, 2, 4))  # 8 voxels, all phase 0
    hist = LevelHistogram(ex, ex, block)
    level = SimpleNamespace(histogram=hist, params=SimpleNamespace(balance=1.0))
    # a set of 4 voxels: the first view says 0 (weight 2), the second 255 (weight 1)
    values = np.array([[0.0] * 4, [255.0] * 4])
    weights = np.array([[2.0] * 4, [1.0] * 4])
    assert vote(values, weights).tolist() == [0.0] * 4  # the plain vote keeps the majority
    new = balanced_set_vote(level, values, weights, np.zeros(4))
    assert np.sum(new == 255.0) == 4  # the other 4 voxels are 0: these must all be 255 for 50/50
    level.params.balance = 0.0  # off: the bias has no target to move toward but the unbiased one
    assert np.sum(balanced_set_vote(level, values, weights, np.zeros(4)) == 255.0) < 4
    # a phase no view proposes is never chosen
    assert set(balanced_set_vote(level, np.zeros((2, 4)), weights, np.zeros(4))) == {0.0}


@pytest.mark.slow
def test_balance_keeps_kopfs_phase_fractions(device):
    ex = gallery_exemplar("composite3", 64)
    want = np.array([np.mean(ex == v) for v in (0, 128, 255)])
    err = {}
    for balance in (0.0, 1.0):
        vol = clsolid.synthesize(ex, (24, 24, 24), method="kopf", iterations=3, balance=balance, rng=1,
                                 device=device)
        err[balance] = np.abs(np.array([np.mean(vol == v) for v in (0, 128, 255)]) - want).max()
    assert err[1.0] < 0.02 and err[1.0] < err[0.0] / 2, err  # kopf's stricter target: within 2 points


@pytest.mark.parametrize("kw", [dict(method="wl", balance=1.0), dict(method="kopf", balance=1.5),
                                dict(method="kopf", balance=True)])
def test_balance_is_checked(kw):
    with pytest.raises(clsolid.InputError, match="balance"):
        SearchParams(**kw)
    assert SearchParams(method="kopf").balance == 1.0 and SearchParams(method="wl").balance == 0.0


def test_parent_weight_defaults_and_is_checked():
    from clsolid.search.params import KOPF_PARENT_WEIGHT

    assert SearchParams(method="kopf").parent_weight == KOPF_PARENT_WEIGHT
    assert SearchParams(method="wl").parent_weight == SearchParams(method="chen-wang").parent_weight == 1.0
    for bad in (0, -1.0, float("inf"), True, "4"):
        with pytest.raises(clsolid.InputError, match="parent_weight"):
            SearchParams(method="kopf", parent_weight=bad)


@pytest.mark.slow
def test_the_parent_weight_scales_the_parent_terms_as_a_weight_would(device):
    """The table's parent terms and the voxels' parent squares are scaled by sqrt(w): each
    parent term weighs w in every distance (the matcher's weights stay 1)."""
    from clsolid.search import driver
    from clsolid.search.features import centre_weights, exemplar_features

    ex = gallery_exemplar("gravel", 64).astype(np.float64)
    table, _ = exemplar_features(ex[:32, :32], ex[::2, ::2][:16, :16], 5)
    searched = driver._searched_table(table, None, 5, 4.0)
    np.testing.assert_array_equal(searched[:, :25], table[:, :25])
    np.testing.assert_array_equal(searched[:, 25:], 2.0 * table[:, 25:])
    queries = table[::7] + np.random.default_rng(0).integers(-9, 10, table[::7].shape)
    scaled = queries.copy()
    scaled[:, 25:] *= 2.0
    w = centre_weights(5, True, centre=False)
    weighted = w.copy()
    weighted[25:] = 4.0
    by_scale = best_match_reference(scaled, searched, w)
    by_weight = best_match_reference(queries, table, weighted)
    np.testing.assert_array_equal(by_scale[0], by_weight[0])
    np.testing.assert_allclose(by_scale[1], by_weight[1])
    seen = []  # (block, parent) of every set: the coarser level's block, then the finer's with it as parent
    inner = driver.UPDATES["kopf"]

    def spy(level, vol, coarse, voxels):
        seen.append((vol, coarse))
        return inner(level, vol, coarse, voxels)

    driver.UPDATES["kopf"] = spy
    try:
        clsolid.synthesize(ex, (8, 8, 8), method="kopf", scales=2, iterations=1, neighborhood=3, rng=1,
                           device="reference", insert_spacing=0)
    finally:
        driver.UPDATES["kopf"] = inner
    assert seen[0][1] is None  # the coarser level comes first, without a parent
    coarse_block = seen[0][0]
    finer = [c for _, c in seen if c is not None]
    assert finer
    for parent in finer:
        np.testing.assert_array_equal(parent, 2.0 * coarse_block)


def test_distance_resolves_per_exemplar_and_is_checked():
    assert SearchParams(method="kopf").distance == "auto"
    kopf = SearchParams(method="kopf")
    assert [kopf.for_exemplar(n, n <= 8).distance for n in (2, 3, 8, 9, 256)] == \
        ["squared", "weighted", "weighted", "squared", "squared"]
    assert kopf.for_exemplar(4, False).distance == "squared"  # 4 grey levels of a quantised image: not phases
    assert SearchParams(method="kopf", distance="squared").for_exemplar(4, True).distance == "squared"
    assert SearchParams(method="wl").for_exemplar(4, True).distance == SearchParams(method="chen-wang").for_exemplar(
        4, True).distance == "squared"
    assert SearchParams(method="wl", distance="weighted").for_exemplar(4, True).distance == "weighted"
    with pytest.raises(clsolid.InputError, match="distance"):
        SearchParams(method="kopf", distance="mismatch")


@pytest.mark.parametrize("method", ["wl", "kopf", "chen-wang"])
def test_weighted_distance_on_a_constant_exemplar_is_squared(method):
    # one phase has no codes: phase_codes raised ValueError("phase codes need at least two phases")
    assert SearchParams(method=method, distance="weighted").for_exemplar(1, True).distance == "squared"
    with pytest.warns(clsolid.ExemplarWarning, match="constant"):
        volume = clsolid.synthesize(np.full((8, 8), 3, np.uint8), (4, 4, 4), method=method, device="reference",
                                    rng=1, scales=1, neighborhood=3, distance="weighted")
    assert (volume == 3).all()


@pytest.mark.slow
def test_phase_codes_make_kopf_blind_to_the_phases_grey_values(device):
    """With weighted mismatches the finest level's matches do not depend on which grey value
    names which phase: renaming composite4's phases changes the result far less than it does
    with squared differences (the coarser levels still blend grey values)."""
    ex = gallery_exemplar("composite4", 64)
    values = np.unique(ex)
    renamed = values[[0, 3, 1, 2]][np.searchsorted(values, ex)]  # a permutation of the names
    back = {float(a): float(b) for a, b in zip(values[[0, 3, 1, 2]], values)}
    changed = {}
    for distance in ("weighted", "squared"):
        a = clsolid.synthesize(ex, (16, 16, 16), method="kopf", scales=1, iterations=3, rng=2, distance=distance,
                               device=device)
        b = clsolid.synthesize(renamed, (16, 16, 16), method="kopf", scales=1, iterations=3, rng=2,
                               distance=distance, device=device)
        changed[distance] = np.mean(a != np.vectorize(back.get)(b))
    assert changed["weighted"] == 0.0 and changed["squared"] > 0.2, changed
