"""Colour exemplars in the likelihood method: the kernels against the float64 reference on a
palette's distances, and the tables a colour scale is built from."""

import numpy as np
import pytest
from conftest import random_state

from clsolid.exemplar import level_map
from clsolid.ml.model import build_scale, difference, scale_exemplar
from clsolid.ml.opencl import CLBackend
from clsolid.ml.params import MLParams
from clsolid.ml.reference import ReferenceBackend, site_distances


@pytest.fixture(scope="module")
def colour_levels():
    """A 20x22 crop of scikit-image's coffee, its palette of 12 colours."""
    from skimage import data

    return level_map(np.ascontiguousarray(data.coffee()[180:200, 300:322]), 12)


def _pair(device, levels, shape, seed=0, **kw):
    params = MLParams(**{"scales": 1, **kw})
    model = build_scale(levels.labels, shape, params, kw.get("level", 0), levels.features)
    vol, temp = random_state(model, seed=seed)
    parent = None
    if model.parent_rows:
        parent = np.random.default_rng(seed + 1).choice(model.labels, size=model.shape)
    backends = CLBackend(device), ReferenceBackend()
    for b in backends:
        b.start_scale(model, vol, temp, params, parent=parent)
    return model, vol, temp, backends


def test_a_colour_scale_compares_every_channel(colour_levels):
    """The coded terms are each neighbour's three channels, so that the sum of squared
    differences over a window's coded rows is the colours' squared distance, as the
    reference's site distances take it."""
    model = build_scale(colour_levels.labels, (5, 6, 7), MLParams(neighborhood=3, scales=1), 0, colour_levels.features)
    assert model.channels == 3 and model.coded(model.patches).shape == (3 * model.patches.shape[0], model.n_sites)
    vol, temp = random_state(model, seed=4)
    temp[:] = 0.0
    voxels = np.arange(0, vol.size, 5)
    want = site_distances(model, vol, temp, voxels, 0)
    nb = model.neighbour_coords(voxels, 0)
    x = model.coded(vol.ravel()[nb].T)  # (R * 3, m)
    got = np.sum((x[:, :, None] - model.coded(model.patches)[:, None, :]) ** 2, axis=0)
    np.testing.assert_allclose(got, want, rtol=1e-12)
    # and the centre: the Parzen factor of a label is its colour's distance to the site's centre
    d = model.distance(np.array([0, 3]), np.array([5, 3]))
    np.testing.assert_allclose(d, [np.sum((colour_levels.features[0] - colour_levels.features[5]) ** 2), 0.0])


def test_phases_of_a_colour_exemplar_stay_names():
    """Compared as phases (mismatch), colour labels are names: the palette plays no part."""
    palette = np.array([[0.0, 0, 0], [50.0, 10, 10], [90.0, 0, 0]])
    np.testing.assert_array_equal(difference(np.array([0, 1]), np.array([2, 1]), True, None, palette), [1.0, 0.0])


def test_a_coarser_colour_exemplar_takes_the_nearest_palette_colour(colour_levels):
    """Smoothing each channel, then the nearest palette colour: inside a block of one colour
    it stays that colour, and every pixel is a palette label."""
    palette = colour_levels.features
    block = np.kron(np.array([[1, 4], [7, 2]]), np.ones((8, 8), int))
    np.testing.assert_array_equal(scale_exemplar(block, 1, palette=palette)[2::4, 2::4], [[1, 4], [7, 2]])
    coarse = scale_exemplar(colour_levels.labels, 2, palette=palette)
    assert coarse.shape == (5, 6) and set(np.unique(coarse)) <= set(range(len(palette)))


@pytest.mark.each_device
@pytest.mark.parametrize("kw", [dict(neighborhood=3, views=2), dict(neighborhood=5, views=3),
                                dict(neighborhood=3, views=3, falloff=1.0),
                                dict(neighborhood=3, views=3, scales=2, parent_weight=2.0, parent_min_side=0)],
                         ids=["k3-2views", "k5-3views", "falloff", "parents"])
def test_colour_log_lcpdf_matches_reference(device, colour_levels, kw):
    model, vol, temp, (cl_b, ref) = _pair(device, colour_levels, (5, 6, 7), **kw)
    assert model.channels == 3 and (model.parent_rows > 0) == ("parent_weight" in kw)
    voxels = np.arange(0, vol.size, 2)
    got, want = cl_b.lcpdf(voxels), ref.lcpdf(voxels)
    assert got.shape == want.shape == (model.offsets.shape[0], voxels.size, model.labels.size)
    np.testing.assert_allclose(got, want, atol=2e-3 * max(1.0, np.abs(want).max() / 100))


@pytest.mark.each_device
@pytest.mark.parametrize("heuristic", ["h2-product", "h1-lowest"])
def test_one_colour_icm_step_matches_reference(device, colour_levels, heuristic):
    model, vol, temp, backends = _pair(device, colour_levels, (6, 6, 8), seed=2, neighborhood=3, views=3,
                                       heuristic=heuristic)
    voxels = np.flatnonzero(model.colour.ravel() == 0)
    for b in backends:
        b.update(voxels)
    cl_b, ref = backends
    np.testing.assert_array_equal(cl_b.volume().ravel()[voxels], ref.volume().ravel()[voxels])
    np.testing.assert_allclose(cl_b.temperature(), ref.temperature(), atol=1e-6)


def _pruned_pair(device, levels, shape, seed, **kw):
    params = MLParams(scales=1, likelihood="pruned", **kw)
    model = build_scale(levels.labels, shape, params, 0, levels.features)
    rng = np.random.default_rng(seed)
    vol, temp = random_state(model, seed=seed)
    sources = rng.integers(0, model.n_sites, (model.offsets.shape[0], vol.size)).astype(np.int32)
    backends = CLBackend(device), ReferenceBackend()
    for b in backends:
        b.start_scale(model, vol, temp, params, sources=sources)
    return model, vol, temp, backends


@pytest.mark.each_device
@pytest.mark.parametrize("kw", [dict(neighborhood=3, views=3, prune_similar=4, prune_sample=0),
                                dict(neighborhood=5, views=2, prune_similar=8, prune_sample=17, falloff=1.0)],
                         ids=["candidates", "sample-falloff"])
def test_pruned_colour_log_lcpdf_matches_reference(device, colour_levels, kw):
    """The pruned sum over candidate windows, their similar windows by colour distance."""
    model, vol, temp, (cl_b, ref) = _pruned_pair(device, colour_levels, (5, 6, 7), 3, **kw)
    voxels = np.flatnonzero(model.colour.ravel() == 0)
    got, want = cl_b.lcpdf(voxels), ref.lcpdf(voxels)
    assert cl_b.pruned_visits == voxels.size
    np.testing.assert_allclose(got, want, atol=2e-3 * max(1.0, np.abs(want).max() / 100))
    assert (cl_b.sources()[:, voxels] == ref.sources()[:, voxels]).mean() > 0.98


def test_similar_colour_windows_are_near_in_colour(colour_levels):
    """The pruned sum's similar windows are the nearest by the colours' distance, not by the
    labels' numbers."""
    from clsolid.ml.pruned import window_table

    model = build_scale(colour_levels.labels, (5, 6, 7), MLParams(neighborhood=3, scales=1), 0,
                        colour_levels.features)
    table = window_table(model, 3)
    rows = model.coded(model.patches).T[table.first_site]
    d = np.sum((rows[:, None, :] - rows[None, :, :]) ** 2, axis=-1)
    k = table.similar.shape[1]
    got = np.sort(np.take_along_axis(d, table.similar, axis=1), axis=1)
    np.testing.assert_allclose(got, np.sort(d, axis=1)[:, :k], rtol=1e-9)


def test_colours_have_no_projected_candidates(colour_levels):
    from clsolid.errors import InputError
    from clsolid.ml.pruned import ProjectedWindows

    model = build_scale(colour_levels.labels, (5, 6, 7), MLParams(neighborhood=3, scales=1), 0,
                        colour_levels.features)
    with pytest.raises(InputError, match="colours, have no projection"):
        ProjectedWindows.of(model, 4)
    params = MLParams(prune_projected=None).for_exemplar(32, False, shape=(256, 256), colour=True)
    assert params.likelihood == "pruned" and params.prune_projected == 0
