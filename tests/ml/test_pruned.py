"""The pruned likelihood (docs/design.md#pruned-likelihood): tables, kernels against the float64 reference,
and the exact sum where the pruned one cannot be trusted."""

import numpy as np
import pytest
from conftest import slow_except

import clsolid
from clsolid.errors import DeviceMemoryError, InputError
from clsolid.ml import pruned
from clsolid.ml.model import build_scale
from clsolid.ml.opencl import CLBackend
from clsolid.ml.params import MLParams
from clsolid.ml.reference import ReferenceBackend, site_distances

SHAPE = (6, 10, 12)


def _model(labels, **kw):
    params = MLParams(scales=1, **kw)
    return params, build_scale(labels, SHAPE, params, 0)


def _state(model, seed=0, hottest=0.3):
    """A random volume, temperatures in [0, hottest) and a random source for every voxel-view."""
    rng = np.random.default_rng(seed)
    vol = rng.choice(model.labels, size=model.shape)
    temp = rng.random(model.shape) * hottest
    sources = rng.integers(0, model.n_sites, (model.offsets.shape[0], vol.size)).astype(np.int32)
    return vol, temp, sources


def _backends(device, model, params, vol, temp, sources=None):
    out = CLBackend(device), ReferenceBackend()
    for b in out:
        b.start_scale(model, vol, temp, params, sources=sources)
    return out


@pytest.mark.parametrize("levels, offset", [(3, 0), (40, 0), (40, 10**4)])
def test_similar_windows_are_the_nearest_lowest_index_first(levels, offset):
    """Many ties (3 levels) and few; small whole numbers (summed in float32) and large ones
    (float64: an offset leaves every distance as it is)."""
    rows = np.random.default_rng(1).integers(0, levels, (300, 8))
    got = pruned.similar_windows(rows + offset, 6)
    d = ((rows[:, None, :] - rows[None, :, :]) ** 2).sum(-1).astype(float)
    np.fill_diagonal(d, np.inf)
    want = np.lexsort((np.broadcast_to(np.arange(300), d.shape), d), axis=1)[:, :5]
    np.testing.assert_array_equal(got[:, 0], np.arange(300))
    np.testing.assert_array_equal(got[:, 1:], want)


@pytest.mark.parametrize("n, k", [(2, 1), (5, 4), (70, 3), (1500, 7), (2500, 1)])
def test_nearest_columns_sort_by_value_then_column(n, k):
    """The bounded selection against a full sort of every row: few columns (groups of one),
    every column wanted, more rows than columns, and ties everywhere (values 0..3)."""
    d = np.random.default_rng(n).integers(0, 4, (40, n)).astype(float)
    d[np.arange(40) % n, np.arange(40) % n] = np.inf
    want = np.lexsort((np.broadcast_to(np.arange(n), d.shape), d), axis=1)[:, :k]
    np.testing.assert_array_equal(pruned.nearest_columns(d, k), want)


def test_similar_windows_across_blocks():
    """More windows than one block of the search (pruned._BLOCK), with ties across the cut."""
    rows = np.random.default_rng(2).integers(0, 2, (pruned._BLOCK + 300, 6))
    got = pruned.similar_windows(rows, 4)
    d = ((rows[:, None, :] - rows[None, :, :]) ** 2).sum(-1).astype(float)
    np.fill_diagonal(d, np.inf)
    want = np.lexsort((np.broadcast_to(np.arange(rows.shape[0]), d.shape), d), axis=1)[:, :3]
    np.testing.assert_array_equal(got[:, 1:], want)


def test_listed_similar_windows_reading_every_list_are_the_exact_ones(monkeypatch):
    """Above EXACT_SIMILAR_WINDOWS the search reads a few lists; reading them all it is the
    brute force, and reading a few it finds nearly the same windows."""
    rows = np.random.default_rng(3).integers(0, 3, (900, 10))
    exact = pruned.similar_windows(rows, 5)
    monkeypatch.setattr(pruned, "EXACT_SIMILAR_WINDOWS", 100)
    monkeypatch.setattr(pruned, "SIMILAR_PROBE", 10**6)
    np.testing.assert_array_equal(pruned.similar_windows(rows, 5), exact)
    monkeypatch.setattr(pruned, "SIMILAR_PROBE", 4)
    listed = pruned.similar_windows(rows, 5)
    monkeypatch.setattr(pruned, "_BLOCK_ENTRIES", 3000)  # a list's rows a few at a time: the same
    np.testing.assert_array_equal(pruned.similar_windows(rows, 5), listed)
    assert listed.shape == exact.shape and np.array_equal(listed[:, 0], np.arange(900))
    assert all(np.unique(r).size == 5 for r in listed)
    d = lambda m: ((rows[:, None, :] - rows[m[:, 1:]]) ** 2).sum(-1)  # noqa: E731
    got, best = d(listed), d(exact)
    assert np.all(np.diff(got, axis=1) >= 0) and np.all(got >= best)  # nearest first; never nearer than exact
    assert np.mean(got[:, 0] == best[:, 0]) > 0.8


def test_window_table_groups_identical_windows(small_labels):
    binary = (small_labels > 7).astype(int)
    _, model = _model(binary, neighborhood=5)
    t = pruned.window_table(model, 4)
    rows = np.column_stack([model.centres, model.patches.T])
    assert t.count.sum() == model.n_sites and t.n_windows < model.n_sites  # a binary image repeats windows
    for w in range(t.n_windows):
        members = np.flatnonzero(t.window_of == w)
        assert members[0] == t.first_site[w] and members.size == t.count[w]
        assert (rows[members] == rows[members[0]]).all()
    assert np.unique(rows[t.first_site], axis=0).shape[0] == t.n_windows
    # a window's source is the lowest site with its neighbourhood (centre excluded)
    same = (model.patches.T == model.patches.T[t.source][:, None, :]).all(-1)  # (U, n)
    np.testing.assert_array_equal(t.source, np.argmax(same[np.arange(t.n_windows)], axis=1))
    assert t.grid[0] * t.grid[1] == model.n_sites


@pytest.mark.each_device
def test_exact_kernel_records_the_nearest_site(device, small_labels):
    params, model = _model(small_labels, neighborhood=5)
    vol, temp, _ = _state(model)
    cl_b, ref = _backends(device, model, params, vol, temp)
    voxels = np.flatnonzero(model.colour.ravel() == 1)
    cl_b.group_log_sums(voxels)
    ref.lcpdf(voxels)
    for v in range(model.offsets.shape[0]):
        a = site_distances(model, vol, temp, voxels, v)
        got = a[np.arange(voxels.size), cl_b.sources()[v, voxels]]
        np.testing.assert_allclose(got, a.min(axis=1), rtol=1e-5, atol=1e-4)
        np.testing.assert_array_equal(np.isin(cl_b.sources()[v, voxels], pruned.source_of_site(model)), True)
    assert (cl_b.sources()[:, voxels] == ref.sources()[:, voxels]).mean() > 0.98


@pytest.mark.each_device
# the default run keeps a case of each distance, of a sample with fall-off, and of projected candidates
@pytest.mark.parametrize("k, views, similar, sample, distance, falloff, projected",
                         # projected: axes, or (axes, lists probed)
                         slow_except([(3, 2, 1, 0, "squared", 0, 0), (5, 3, 8, 0, "squared", 0, 0),
                                      (7, 2, 16, 0, "squared", 0, 0), (5, 2, 8, 64, "squared", 0, 0),
                                      (7, 3, 4, 17, "squared", 0, 0),
                                      (5, 3, 8, 0, "mismatch", 0, 0), (7, 2, 4, 17, "mismatch", 0, 0),
                                      (5, 2, 8, 17, "weighted", 0, 0), (7, 2, 8, 17, "squared", 2.0, 0),
                                      (5, 3, 4, 0, "weighted", 1.0, 0),
                                      # projected candidates (8 axes, 20 a voxel): with and without a sample and fall-off
                                      (5, 2, 4, 0, "squared", 0, 8), (7, 3, 8, 17, "squared", 2.0, 8),
                                      (5, 2, 4, 0, "squared", 2.0, (8, 2))], 0, 5, 7, 8, 10, 12))
def test_pruned_lcpdf_matches_reference(device, small_labels, k, views, similar, sample, distance, falloff,
                                        projected):
    axes, probe = projected if isinstance(projected, tuple) else (projected, 0)
    params, model = _model(small_labels, neighborhood=k, views=views, likelihood="pruned", prune_similar=similar,
                           prune_sample=sample, distance=distance, falloff=falloff, prune_projected=axes,
                           prune_projected_k=20, prune_projected_probe=probe)
    vol, temp, sources = _state(model, seed=k)
    cl_b, ref = _backends(device, model, params, vol, temp, sources)
    voxels = np.flatnonzero(model.colour.ravel() == 0)
    got, want = cl_b.lcpdf(voxels), ref.lcpdf(voxels)
    assert cl_b.pruned_visits == voxels.size and cl_b.exact_visits == 0
    np.testing.assert_allclose(got, want, atol=2e-3 * max(1.0, np.abs(want).max() / 100))
    # the new sources: the nearest candidate's (ties aside, the same)
    assert (cl_b.sources()[:, voxels] == ref.sources()[:, voxels]).mean() > 0.98
    exact = ReferenceBackend()
    exact.start_scale(model, vol, temp, MLParams(scales=1, neighborhood=k, views=views, distance=distance,
                                                 falloff=falloff))
    assert not np.allclose(want, exact.lcpdf(voxels), atol=1e-3)  # it is pruned: candidates, not every site


@pytest.mark.each_device
def test_a_sample_of_every_site_is_the_exact_sum(device, small_labels):
    params, model = _model(small_labels, neighborhood=5, likelihood="pruned", prune_sample=4096)
    vol, temp, sources = _state(model, seed=8)
    cl_b, ref = _backends(device, model, params, vol, temp, sources)
    exact = ReferenceBackend()
    exact.start_scale(model, vol, temp, MLParams(scales=1, neighborhood=5))
    voxels = np.flatnonzero(model.colour.ravel() == 1)
    want = exact.lcpdf(voxels)
    np.testing.assert_allclose(ref.lcpdf(voxels), want, atol=1e-9)
    np.testing.assert_allclose(cl_b.lcpdf(voxels), want, atol=2e-3 * max(1.0, np.abs(want).max() / 100))


def test_the_sample_follows_seed_and_sweep(small_labels):
    _, model = _model(small_labels, neighborhood=5)
    voxels = np.arange(50)
    a = pruned.sample_sites(1, 7, voxels, model.shape, 0, model.n_sites, 16)
    assert a.shape == (50, 16) and (np.diff(np.sort(a, axis=1), axis=1) > 0).all()  # distinct sites
    np.testing.assert_array_equal(a, pruned.sample_sites(1, 7, voxels, model.shape, 0, model.n_sites, 16))
    for other in (pruned.sample_sites(2, 7, voxels, model.shape, 0, model.n_sites, 16),
                  pruned.sample_sites(1, 8, voxels, model.shape, 0, model.n_sites, 16),
                  pruned.sample_sites(1, 7, voxels, model.shape, 1, model.n_sites, 16)):
        assert (other != a).any()


@pytest.mark.each_device
def test_pruned_sum_is_a_subset_of_the_exact_one(device, small_labels):
    """Unnormalised and without a sample, each label's pruned sum can only be below the exact one."""
    params, model = _model(small_labels, neighborhood=5, likelihood="pruned", prune_sample=0)
    vol, temp, sources = _state(model, seed=3)
    cl_b, _ = _backends(device, model, params, vol, temp, sources)
    exact = CLBackend(device)
    exact.start_scale(model, vol, temp, MLParams(scales=1, neighborhood=5))
    voxels = np.flatnonzero(model.colour.ravel() == 2)
    got, want = cl_b.group_log_sums(voxels), exact.group_log_sums(voxels)
    assert np.all(got <= want + 1e-3 * np.maximum(1, np.abs(want)))
    assert np.any(got < want - 1e-2)


@pytest.mark.each_device
def test_hot_or_sourceless_voxels_get_the_exact_sum(device, small_labels):
    params, model = _model(small_labels, neighborhood=5, likelihood="pruned", prune_min_weight=0.3, prune_sample=0)
    vol, temp, sources = _state(model, seed=4)
    voxels = np.flatnonzero(model.colour.ravel() == 0)
    hot, sourceless = voxels[::3], voxels[1::3]
    temp.ravel()[:] = 0.0
    for v in hot:  # every neighbour at t = 0.9: mean (1 - t)^2 = 0.01 < 0.3
        z, y, x = np.unravel_index(v, model.shape)
        temp[max(z - 2, 0): z + 3, max(y - 2, 0): y + 3, max(x - 2, 0): x + 3] = 0.9
    sources[1, sourceless] = -1
    flagged = pruned.needs_exact(sources[:, voxels], np.stack([
        pruned.mean_square_weight(temp, np.asarray(_nb(model, voxels, v))) for v in range(2)]), 0.3, 0)
    cl_b, ref = _backends(device, model, params, vol, temp, sources)
    exact = ReferenceBackend()
    exact.start_scale(model, vol, temp, MLParams(scales=1, neighborhood=5))
    got, want, full = cl_b.lcpdf(voxels), ref.lcpdf(voxels), exact.lcpdf(voxels)
    assert flagged[np.isin(voxels, hot)].all() and flagged[np.isin(voxels, sourceless)].all()
    assert cl_b.exact_visits == flagged.sum() < voxels.size
    np.testing.assert_allclose(got[:, flagged], full[:, flagged], atol=2e-3 * max(1.0, np.abs(full).max() / 100))
    np.testing.assert_allclose(want[:, flagged], full[:, flagged], atol=1e-9)
    np.testing.assert_allclose(got, want, atol=2e-3 * max(1.0, np.abs(want).max() / 100))
    assert (cl_b.sources()[:, voxels] >= 0).all()  # every visited voxel has a source now


def _nb(model, voxels, view):
    from clsolid.ml.reference import wrapped_coords

    return wrapped_coords(voxels, model.shape, model.offsets[view])


@pytest.mark.each_device
@pytest.mark.parametrize("distance", ["squared", "mismatch", "weighted"])
def test_one_pruned_gibbs_sweep_matches_reference(device, small_labels, distance):
    params, model = _model(small_labels, neighborhood=5, likelihood="pruned", distance=distance)
    vol, temp, sources = _state(model, seed=6)
    cl_b, ref = _backends(device, model, params, vol, temp, sources)
    for b in (cl_b, ref):
        b.start_sweep(3, 7, 1.0, np.zeros(model.labels.size))
    voxels = np.flatnonzero(model.colour.ravel() == 3)
    for b in (cl_b, ref):
        b.update(voxels)
    same = cl_b.volume().ravel()[voxels] == ref.volume().ravel()[voxels]
    assert same.mean() > 0.98  # a float32 near-tie may tip a draw
    np.testing.assert_allclose(cl_b.temperature(), ref.temperature(), atol=1e-6)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["porous50", "composite3", "gravel"])
def test_pruned_synthesis_keeps_the_material(device, name):
    """The pruned mode on gallery exemplars at 24^3: fractions, grey spread and mirror kept,
    and the same volume for the same seed."""
    from clsolid.gallery import gallery_exemplar
    from clsolid.metrics.symmetry import mirror_correlation

    ex = gallery_exemplar(name, 64)
    runs = [clsolid.synthesize(ex, (24, 24, 24), rng=5, device=device, likelihood="pruned") for _ in range(2)]
    np.testing.assert_array_equal(runs[0], runs[1])
    values = np.unique(ex)
    if values.size <= 4:
        frac = np.array([(runs[0] == v).mean() for v in values])
        assert np.abs(frac - np.array([(ex == v).mean() for v in values])).max() < 0.03
    assert mirror_correlation(runs[0].astype(float)) <= 0.2  # as the defaults' fast test
    assert abs(runs[0].astype(float).std() - ex.std()) < 0.15 * ex.std()


@pytest.mark.slow
@pytest.mark.parametrize("name", ["porous50", "composite3"])  # composite3: the weighted distance
def test_pruned_run_resumes_identically(tmp_path, device, name):
    from clsolid.gallery import gallery_exemplar

    ex = gallery_exemplar(name, 64)
    kw = dict(rng=2, device=device, likelihood="pruned", scales=2, full_output=True)
    whole = clsolid.synthesize(ex, (16, 16, 16), **kw)
    assert whole.params["distance"] == ("weighted" if name == "composite3" else "mismatch")
    seen = []

    def stop(info):
        seen.append(info)
        if info.scale == 2 and info.sweep == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        clsolid.synthesize(ex, (16, 16, 16), backend={"checkpoint": tmp_path / "ck"}, progress=stop, **kw)
    resumed = clsolid.resume(tmp_path / "ck", device=device, full_output=True)
    np.testing.assert_array_equal(resumed.volume, whole.volume)


@pytest.mark.parametrize("bad", [dict(likelihood="fast"), dict(prune_similar=0), dict(prune_similar=17),
                                 dict(prune_min_weight=1.5), dict(prune_min_weight="x"), dict(prune_sample=-1),
                                 dict(prune_sample=5000), dict(prune_projected=-1), dict(prune_projected=65),
                                 dict(prune_projected_k=0), dict(prune_projected=True),
                                 dict(prune_projected_probe=-1), dict(prune_projected_probe=2.0),
                                 dict(prune_projected_sweeps=-1), dict(prune_projected_sweeps=None)])
def test_bad_pruned_parameters_are_refused(bad):
    with pytest.raises(InputError, match=next(iter(bad))):
        MLParams(**bad)


@pytest.mark.parametrize("name, size, levels, want", slow_except([
    ("porous50", 64, 32, "pruned"), ("brick", 64, 32, "exact"), ("brick", 64, 8, "exact"),
    ("gravel", 128, 32, "pruned")], 0))
def test_auto_prunes_categorical_and_large_grey_exemplars(device, name, size, levels, want):
    from clsolid.gallery import gallery_exemplar

    image = name if name == "brick" else gallery_exemplar(name, size)
    res = clsolid.synthesize(image, (8, 8, 8), levels=levels, scales=1, neighborhood=3, rng=1, device=device,
                             full_output=True)
    assert res.params["likelihood"] == want
    assert res.params["prune_projected"] == (24 if name == "gravel" else 0)  # grey and large: projected
    if want == "pruned":  # and there, the sources' own windows and half the sample
        assert (res.params["prune_similar"], res.params["prune_sample"]) == ((1, 32) if name == "gravel" else (8, 64))
    forced = clsolid.synthesize(image, (8, 8, 8), levels=levels, scales=1, neighborhood=3, rng=1, device=device,
                                likelihood="exact" if want == "pruned" else "pruned", full_output=True)
    assert forced.params["likelihood"] != want


def test_projected_windows_with_every_axis_find_the_exact_nearest_sites():
    """All the axes keep every distance (the fall-off's scaling included): the projected
    nearest sites are the exact distance's at t = 0; one axis keeps less."""
    labels = np.random.default_rng(4).integers(0, 8, (14, 15))
    _, model = _model(labels, neighborhood=5, falloff=2.0)
    assert model.term_weight is not None
    vol, _, _ = _state(model)
    voxels = np.arange(0, vol.size, 7)
    exact = site_distances(model, vol, np.zeros(model.shape), voxels, 1)
    want = pruned.smallest(exact, 6)
    assert np.array_equal(pruned.ProjectedWindows.of(model, 24).nearest(model, vol, voxels, 1, 6), want)
    assert not np.array_equal(pruned.ProjectedWindows.of(model, 1).nearest(model, vol, voxels, 1, 6), want)


def test_auto_projects_grey_exemplars_from_ten_thousand_sites():
    from clsolid.ml.params import AUTO_PROJECTED_SITES

    assert AUTO_PROJECTED_SITES == 10_000
    side = 100 + 11 - 1  # 100 x 100 sites of an 11 x 11 window
    for shape, grey, want in [((side, side), True, ("pruned", 24)), ((side, side - 1), True, ("exact", 0)),
                              (None, True, ("exact", 0)), ((side, side), False, ("pruned", 0))]:
        got = MLParams().for_exemplar(32 if grey else 3, not grey, 0.0, shape)
        assert (got.likelihood, got.prune_projected) == want
    given = MLParams(prune_projected=0).for_exemplar(32, False, 0.0, (side, side))
    assert (given.likelihood, given.prune_projected) == ("pruned", 0)
    exact = MLParams(likelihood="exact").for_exemplar(32, False, 0.0, (side, side))
    assert (exact.likelihood, exact.prune_projected) == ("exact", 0)
    # similar windows a source: fewer with projected candidates, unless given
    assert MLParams().for_exemplar(32, False, 0.0, (side, side)).prune_similar == 1
    assert MLParams().for_exemplar(3, True, 0.0, (side, side)).prune_similar == 8
    assert MLParams(prune_similar=5).for_exemplar(32, False, 0.0, (side, side)).prune_similar == 5
    assert (MLParams().n_similar, MLParams(prune_projected=4).n_similar) == (8, 1)
    assert MLParams().for_exemplar(32, False, 0.0, (side, side)).prune_sample == 32
    assert MLParams().for_exemplar(3, True, 0.0, (side, side)).prune_sample == 64
    assert MLParams(prune_sample=0).for_exemplar(32, False, 0.0, (side, side)).prune_sample == 0
    assert (MLParams().n_sample, MLParams(prune_projected=4).n_sample) == (64, 32)
    assert MLParams(likelihood="pruned").for_exemplar(32, False, 0.0, (64, 64)).prune_projected == 0


def test_records_older_than_the_site_lists_resume_searching_every_site():
    """A checkpoint or sidecar written before ``prune_projected_probe`` existed searched every
    site; read back, it must run as it ran, not with today's 8 lists."""
    old = {k: v for k, v in MLParams(prune_projected=24).to_dict().items() if k != "prune_projected_probe"}
    assert MLParams.from_dict(old).prune_projected_probe == 0
    assert MLParams.from_dict(MLParams(prune_projected=24).to_dict()).prune_projected_probe == 8
    assert MLParams.from_dict({**old, "prune_projected": 0}).prune_projected_probe == 8  # unused: today's
    older = {k: v for k, v in old.items() if k != "prune_projected_sweeps"}
    assert MLParams.from_dict(older).prune_projected_sweeps == 0  # before it, every sweep searched
    assert MLParams.from_dict(MLParams(prune_projected=24).to_dict()).prune_projected_sweeps == 1


def test_projected_windows_refuse_mismatch_distances():
    _, model = _model(np.random.default_rng(0).integers(0, 3, (14, 15)), neighborhood=5, distance="weighted")
    with pytest.raises(ValueError, match="squared differences"):
        pruned.ProjectedWindows.of(model, 4)


def test_smallest_keeps_k_per_row_and_whole_rows_when_k_is_larger():
    a = np.array([[3.0, 1.0, 2.0], [0.0, 5.0, 4.0]])
    assert np.array_equal(pruned.smallest(a, 2), [[False, True, True], [True, False, True]])
    assert pruned.smallest(a, 9).all()


def test_site_lists_are_deterministic_nonempty_and_centred():
    sites = np.random.default_rng(3).normal(size=(500, 6))
    centres, list_of = pruned.site_lists(sites, 22)
    assert np.bincount(list_of).min() > 0 and centres.shape == (list_of.max() + 1, 6) and centres.shape[0] <= 22
    for c in range(centres.shape[0]):
        np.testing.assert_allclose(centres[c], sites[list_of == c].mean(axis=0))
    again = pruned.site_lists(sites, 22)
    assert np.array_equal(again[1], list_of) and np.array_equal(again[0], centres)
    assert np.array_equal(pruned.site_lists(sites[:5], 22)[1], np.arange(5))  # at most one list a site


def test_projected_lists_probed_all_find_what_every_site_finds():
    """Reading every list is the whole search; fewer lists read fewer sites and miss some."""
    labels = np.random.default_rng(4).integers(0, 8, (20, 21))
    _, model = _model(labels, neighborhood=5, falloff=2.0)
    vol, _, _ = _state(model)
    voxels = np.arange(0, vol.size, 5)
    whole = pruned.ProjectedWindows.of(model, 8)
    lists = pruned.ProjectedWindows.of(model, 8, probe=1)
    n_lists = lists.centres.shape[0]
    assert n_lists == round(np.sqrt(model.n_sites)) and whole.centres.shape[0] == 1
    every = pruned.ProjectedWindows.of(model, 8, probe=n_lists + 5)
    assert every.probe == n_lists
    np.testing.assert_allclose(every.distances(model, vol, voxels, 1), whole.distances(model, vol, voxels, 1))
    one = lists.distances(model, vol, voxels, 1)
    assert np.isfinite(one).sum(axis=1).max() < model.n_sites / 3
    near = np.isfinite(one)
    np.testing.assert_allclose(one[near], whole.distances(model, vol, voxels, 1)[near])


@pytest.mark.each_device
@pytest.mark.parametrize("probe", [0, 3])
def test_projected_candidates_are_the_references(device, small_labels, probe):
    """The kernel's projected nearest windows (top K by the projected distance among the
    sites searched, lower site first on a tie) are the float64 reference's, item by item."""
    params, model = _model(small_labels, neighborhood=5, likelihood="pruned", falloff=2.0, prune_projected=6,
                           prune_projected_k=12, prune_projected_probe=probe)
    vol, temp, sources = _state(model, seed=2)
    cl_b, ref = _backends(device, model, params, vol, temp, sources)
    voxels = np.flatnonzero(model.colour.ravel() == 1).astype(np.int32)
    cl_b.lcpdf(voxels)  # a visit computes them for every (voxel, view) item
    views = model.offsets.shape[0]
    got = np.empty(voxels.size * views * 12, np.int32)
    import pyopencl as cl

    cl.enqueue_copy(device.queue, got, cl_b.projected_out)
    got = got.reshape(voxels.size, views, 12)
    want = np.stack([ref.pruning.projected_windows(ref.vol, voxels, v) for v in range(views)], axis=1)
    assert (np.sort(got, axis=2) == np.sort(want, axis=2)).all(axis=2).mean() > 0.98  # float32 near-ties aside
    assert (got >= 0).all()


@pytest.mark.each_device
@pytest.mark.parametrize("every", [0, 2])
def test_projected_candidates_only_in_the_first_sweeps(device, small_labels, every):
    """With ``prune_projected_sweeps=N`` the sweeps after the first N of a scale take no
    projected candidates, kernel and reference alike; with 0 every sweep takes them."""
    from clsolid.core.philox import relax_tag

    params, model = _model(small_labels, neighborhood=5, likelihood="pruned", prune_projected=8,
                           prune_projected_k=20, prune_projected_sweeps=every, prune_similar=4, prune_sample=16)
    plain = MLParams(**{**params.to_dict(), "prune_projected": 0})
    vol, temp, sources = _state(model, seed=4)
    voxels = np.flatnonzero(model.colour.ravel() == 2)
    for sweep in (1, 2, 3):
        cl_b, ref = _backends(device, model, params, vol, temp, sources)
        without = ReferenceBackend()
        without.start_scale(model, vol, temp, plain, sources=sources)
        for b in (cl_b, ref, without):
            b.start_sweep(5, relax_tag(0, sweep), 1.0, np.zeros(model.labels.size))
        want = ref.lcpdf(voxels)
        np.testing.assert_allclose(cl_b.lcpdf(voxels), want, atol=2e-3 * max(1.0, np.abs(want).max() / 100))
        assert np.allclose(want, without.lcpdf(voxels), atol=1e-9) == (every and sweep > every)


def test_projected_candidates_need_squared_differences(small_labels):
    params = MLParams(scales=1, neighborhood=5, likelihood="pruned", distance="mismatch", prune_projected=4)
    with pytest.raises(InputError, match="squared differences"):
        pruned.Pruning(build_scale(small_labels, SHAPE, params, 0), params)


@pytest.mark.slow
def test_projected_candidates_run_is_reproducible_and_tiles_alike(device):
    from clsolid.gallery import gallery_exemplar

    ex = gallery_exemplar("gravel", 64)[:40, :40]
    kw = dict(rng=1, likelihood="pruned", prune_projected=8, prune_projected_k=16, neighborhood=5, scales=2,
              device=device.device.name.strip()[:8])
    one = clsolid.synthesize(ex, (12, 12, 12), **kw)
    assert np.array_equal(one, clsolid.synthesize(ex, (12, 12, 12), **kw))
    assert np.array_equal(one, clsolid.synthesize(ex, (12, 12, 12), backend={"tile": 7}, **kw))
    assert not np.array_equal(one, clsolid.synthesize(ex, (12, 12, 12), **{**kw, "prune_projected": 0}))


@pytest.mark.parametrize("projected", [0, 6])
def test_memory_check_counts_the_pruned_tables(device, small_labels, monkeypatch, projected):
    """The pruned sum's buffers are counted before they are allocated, each at least as large
    as what is then allocated, and they can make a run not fit."""
    import pyopencl as cl

    params, model = _model(small_labels, neighborhood=5, likelihood="pruned", falloff=2.0,
                           prune_projected=projected, prune_projected_probe=3)
    backend = CLBackend(device)
    plain = backend.buffer_sizes(model, model.labels.size)
    sizes = backend.buffer_sizes(model, model.labels.size, None, params)
    assert {k: sizes[k] for k in plain} == plain
    assert ("projected sites" in sizes) == bool(projected)
    vol, temp, sources = _state(model)
    backend.start_scale(model, vol, temp, params, sources=sources)
    w = backend.windows
    allocated = {"pruned windows": w[2].size, "pruned window tables": sum(b.size for b in (w[0], w[1], *w[3:6])),
                 "pruned flags": backend.flags_buf.size, "projected candidates": backend.projected_out.size}
    if projected:
        allocated["projected sites"] = sum(b.size for b in backend.projection if isinstance(b, cl.Buffer)) - w[0].size
    assert set(allocated) == set(sizes) - set(plain)
    for name, nbytes in allocated.items():
        assert 0 < nbytes <= sizes[name], name
    monkeypatch.setattr(type(device), "global_mem", property(lambda self: sum(plain.values())))
    backend.check_memory(model)  # the exact sum's buffers alone fit
    with pytest.raises(DeviceMemoryError, match="all buffers together"):
        backend.check_memory(model, None, params)
