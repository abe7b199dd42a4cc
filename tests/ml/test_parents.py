"""The likelihood's parent terms (``parent_weight``): the coarser scale's 3 x 3 in every
neighbourhood below the coarsest scale, as tables, as the reference's distance, on the kernels."""

import numpy as np
import pytest
from conftest import random_state, slow_except

import clsolid
from clsolid.errors import InputError
from clsolid.ml.model import build_scale, parent_block, scale_exemplar, wrapped_coords
from clsolid.ml.opencl import CLBackend
from clsolid.ml.params import MLParams
from clsolid.ml.reference import ReferenceBackend, site_distances

SHAPE = (7, 9, 11)


def _parent_state(model, seed):
    """A random state and a parent block made from a random coarser volume."""
    vol, temp = random_state(model, seed=seed)
    coarse = np.random.default_rng(seed + 100).choice(model.labels, size=tuple(-(-n // 2) for n in model.shape))
    return vol, temp, coarse, parent_block(coarse, model.shape)


def test_parent_rows_read_the_coarser_scale_around_the_parent(small_labels):
    """Row d of a voxel's parent square is the coarser volume at (its position // 2) + d, on
    the torus; of a site's, the coarser exemplar at (its centre // 2) + d."""
    params = MLParams(neighborhood=5, scales=2, parent_weight=2.0, parent_min_side=0)
    model = build_scale(small_labels, SHAPE, params, 0)
    plain = build_scale(small_labels, SHAPE, MLParams(neighborhood=5, scales=2), 0)
    assert model.parent_rows == 9 and model.offsets.shape[1] == plain.offsets.shape[1] + 9
    np.testing.assert_array_equal(model.patches[:-9], plain.patches)
    np.testing.assert_array_equal(model.union_offsets, plain.union_offsets)  # temperatures: the window only
    np.testing.assert_array_equal(model.term_weight, np.r_[np.ones(24), np.full(9, 2.0)])
    assert build_scale(small_labels, SHAPE, params, 1).parent_rows == 0  # the coarsest scale has none
    squares = [(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1)]
    coarse_ex = scale_exemplar(small_labels, 1, params.pyramid)
    half, cols = 2, small_labels.shape[1] - 4
    for site in (0, 7, model.n_sites - 1):
        r, c = divmod(site, cols)
        want = [coarse_ex[(r + half) // 2 + dr, (c + half) // 2 + dc] for dr, dc in squares]
        np.testing.assert_array_equal(model.patches[-9:, site], want)
    even = build_scale(small_labels, (8, 10, 12), params, 0)  # on even sides the torus is exact
    vol, temp, coarse, parent = _parent_state(even, 3)
    for voxel in range(0, vol.size, 13):
        z, y, x = np.unravel_index(voxel, vol.shape)
        for view, (ra, ca) in enumerate(((1, 2), (1, 0))):  # front: (y, x), right: (y, z)
            got = even.with_parent(vol, parent)[even.neighbour_coords(np.array([voxel]), view)[0, -9:]]
            want = []
            for dr, dc in squares:
                p = [z // 2, y // 2, x // 2]
                p[ra] += dr
                p[ca] += dc
                want.append(coarse[tuple(q % n for q, n in zip(p, coarse.shape))])
            np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("distance, falloff", [("squared", 0), ("weighted", 0), ("squared", 2.0), ("mismatch", 1.0)])
def test_parent_terms_add_their_weighted_distance(small_labels, distance, falloff):
    """The distance with parent terms is the window's plus parent_weight times the parent
    square's, at t = 0 (the parent block is trusted)."""
    kw = dict(neighborhood=5, scales=2, distance=distance, falloff=falloff)
    model = build_scale(small_labels, SHAPE, MLParams(parent_weight=3.0, parent_min_side=0, **kw), 0)
    plain = build_scale(small_labels, SHAPE, MLParams(**kw), 0)
    vol, temp, _, parent = _parent_state(model, 5)
    voxels = np.arange(0, vol.size, 4)
    for view in range(2):
        got = site_distances(model, model.with_parent(vol, parent), model.with_parent(temp, np.zeros(SHAPE)),
                             voxels, view)
        x = parent.ravel()[wrapped_coords(voxels, SHAPE, model.offsets[view, -9:])].astype(float)
        y = model.patches[-9:]
        if model.mismatch:
            costs = model.costs if model.costs is not None else np.full(model.labels.size, 0.5)
            d = (x[:, :, None] != y[None]) * (costs[x.astype(int)][:, :, None] + costs[y.astype(int)][None])
            d = d if model.costs is not None else (x[:, :, None] != y[None]).astype(float)
        else:
            d = (x[:, :, None] - y[None]) ** 2
        want = site_distances(plain, vol, temp, voxels, view) + 3.0 * d.sum(axis=1)
        np.testing.assert_allclose(got, want, rtol=1e-6)  # weighted: float32 costs


@pytest.mark.each_device
@pytest.mark.parametrize("kw", slow_except([
    dict(distance="squared"), dict(distance="weighted"), dict(distance="squared", falloff=2.0),
    dict(distance="squared", views=3, parent_weight=1.0),
    dict(distance="weighted", likelihood="pruned", prune_similar=8, prune_sample=17),
    dict(distance="squared", likelihood="pruned", prune_similar=4, prune_sample=0, prune_projected=8,
         prune_projected_k=20)], 1, 3, 4, 5))
def test_kernels_match_the_reference_with_parent_terms(device, small_labels, kw):
    params = MLParams(**{"neighborhood": 5, "scales": 2, "parent_weight": 4.0, "parent_min_side": 0, **kw})
    model = build_scale(small_labels, SHAPE, params, 0)
    vol, temp, _, parent = _parent_state(model, 7)
    rng = np.random.default_rng(1)
    sources = rng.integers(0, model.n_sites, (model.offsets.shape[0], vol.size)).astype(np.int32)
    cl_b, ref = CLBackend(device), ReferenceBackend()
    for b in (cl_b, ref):
        b.start_scale(model, vol, temp, params, sources=sources, parent=parent)
    voxels = np.flatnonzero(model.colour.ravel() == 0)
    got, want = cl_b.lcpdf(voxels), ref.lcpdf(voxels)
    np.testing.assert_allclose(got, want, atol=2e-3 * max(1.0, np.abs(want).max() / 100))
    assert (cl_b.sources()[:, voxels] == ref.sources()[:, voxels]).mean() > 0.98
    # the parent terms count: without them the sums differ
    bare = ReferenceBackend()
    bare_params = MLParams(**{"neighborhood": 5, "scales": 2, **kw, "parent_weight": 0})
    bare.start_scale(build_scale(small_labels, SHAPE, bare_params, 0), vol, temp, bare_params, sources=sources)
    assert not np.allclose(want, bare.lcpdf(voxels), atol=1e-3)


def test_a_model_with_parent_terms_refuses_a_state_without_its_parent(device, small_labels):
    params = MLParams(neighborhood=5, scales=2, parent_weight=4.0, parent_min_side=0)
    model = build_scale(small_labels, SHAPE, params, 0)
    vol, temp = random_state(model)
    with pytest.raises(ValueError, match="parent block"):
        CLBackend(device).start_scale(model, vol, temp, params)


@pytest.mark.parametrize("bad", [-1.0, float("nan"), "4", True])
def test_bad_parent_weight_is_refused(bad):
    with pytest.raises(InputError, match="parent_weight"):
        MLParams(parent_weight=bad)


@pytest.mark.slow
def test_runs_with_parent_terms_are_reproducible_and_tiles_change_nothing(tmp_path, device, small_labels):
    kw = dict(neighborhood=5, scales=2, parent_weight=4.0, parent_min_side=0, rng=3, device=device, output="labels")
    a = clsolid.synthesize(small_labels, (12, 12, 12), **kw)
    np.testing.assert_array_equal(a, clsolid.synthesize(small_labels, (12, 12, 12), **kw))
    np.testing.assert_array_equal(a, clsolid.synthesize(small_labels, (12, 12, 12), backend={"tile": 8}, **kw))
    np.testing.assert_array_equal(a, clsolid.synthesize(small_labels, (12, 12, 12), backend={"tile": 8, "scratch": tmp_path},
                                                             **kw))
    plain = clsolid.synthesize(small_labels, (12, 12, 12), **{**kw, "parent_weight": 0})
    assert (a != plain).mean() > 0.1


@pytest.mark.slow
def test_cli_gives_ml_its_parent_weight_and_the_sidecar_records_it(tmp_path, device):
    import json

    from clsolid.cli import main

    out = tmp_path / "v.npy"
    assert main(["synth", "brick", "-o", str(out), "--shape", "8", "10", "12", "--neighborhood", "3",
                 "--scales", "2", "--levels", "8", "--seed", "3", "--parent-weight", "4", "--parent-min-side", "0",
                 "--quiet",
                 "--device", device.device.name.strip()[:8]]) == 0
    assert json.loads((tmp_path / "v.json").read_text())["params"]["parent_weight"] == 4.0
    plain = tmp_path / "p.npy"
    assert main(["synth", "brick", "-o", str(plain), "--shape", "8", "10", "12", "--neighborhood", "3",
                 "--scales", "2", "--levels", "8", "--seed", "3", "--quiet",
                 "--device", device.device.name.strip()[:8]]) == 0
    assert json.loads((tmp_path / "p.json").read_text())["params"]["parent_weight"] == 0.0  # grey brick: none
    assert not np.array_equal(np.load(out), np.load(plain))


def test_the_reference_back_end_runs_with_parent_terms(small_labels):
    """The float64 reference takes the parent block as the kernels do (its sums are compared
    above); a whole run on it differs from one without parent terms."""
    kw = dict(neighborhood=3, scales=2, max_sweeps=2, rng=2, device="reference", output="labels")
    a = clsolid.synthesize(small_labels, (6, 6, 6), parent_weight=4.0, parent_min_side=0, **kw)
    assert set(np.unique(a)) <= set(np.unique(small_labels))
    assert (a != clsolid.synthesize(small_labels, (6, 6, 6), **kw)).any()


@pytest.mark.parametrize("name, weight", [("composite3", 4.0), ("fibres", 4.0), ("gravel", 0.0), ("brick", 0.0)])
def test_parent_terms_by_the_exemplar_where_the_coarser_one_is_wide_enough(name, weight):
    """parent_weight=None: 4 on categorical exemplars, 0 on grey ones; and only at the scales
    whose coarser exemplar is at least parent_min_side (64) wide: at 128^2 the finest scale's,
    at 64^2 none (so the 64^2 gallery's volumes are what they were)."""
    from clsolid.exemplar import level_map
    from clsolid.gallery import gallery_exemplar

    for size, with_parents in ((128, [True, False, False]), (64, [False, False, False])):
        levels = level_map(gallery_exemplar(name, size), MLParams().levels)
        params = MLParams().for_exemplar(levels.values.size, levels.exact, 0.0, levels.labels.shape)
        assert params.parent_weight == weight
        got = [build_scale(levels.labels, (64, 64, 64), params, lv).parent_rows > 0 for lv in range(3)]
        assert got == [w and weight > 0 for w in with_parents]
    assert MLParams(parent_weight=4.0).for_exemplar(4, False).parent_weight == 4.0  # given: kept
    assert MLParams.from_dict({"neighborhood": 11}).parent_weight == 0.0  # a record from before: none
