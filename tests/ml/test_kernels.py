"""The OpenCL kernels against the float64 NumPy reference, on small inputs."""

import numpy as np
import pytest
from conftest import random_state, slow_except

import clsolid
from clsolid.errors import InputError
from clsolid.gallery import gallery_exemplar
from clsolid.ml.opencl import CLBackend, group_tables, kernel_tables
from clsolid.ml.model import build_scale
from clsolid.ml.params import MLParams
from clsolid.ml.reference import ReferenceBackend


def _pair(device, labels_img, shape, vol, temp, **kw):
    params = MLParams(**kw)
    model = build_scale(labels_img, shape, params, 0)
    cl_b, ref = CLBackend(device), ReferenceBackend()
    for b in (cl_b, ref):
        b.start_scale(model, vol, temp, params)
    return model, cl_b, ref


@pytest.mark.each_device
# the default run keeps a case of each window side, view count, distance, fall-off and shared weight
@pytest.mark.parametrize("k, views, distance, falloff, shared", slow_except([
    (3, 2, "squared", 0, 1), (5, 3, "squared", 0, 1), (7, 2, "squared", 0, 1), (11, 2, "squared", 0, 1),
    (5, 3, "mismatch", 0, 1), (11, 2, "mismatch", 0, 1), (5, 3, "weighted", 0, 1), (11, 2, "weighted", 0, 1),
    (11, 2, "squared", 3.0, 1), (5, 3, "squared", 1.0, 1), (7, 2, "mismatch", 2.0, 1), (5, 3, "weighted", 1.5, 1),
    (11, 2, "weighted", 0, 0), (7, 2, "squared", 2.0, 0.5), (5, 3, "mismatch", 0, 0)], 0, 4, 6, 8, 12, 13))
def test_per_label_log_lcpdf_matches_reference(device, small_labels, k, views, distance, falloff, shared):
    shape = (7, 9, 11)
    params = dict(neighborhood=k, views=views, scales=1, distance=distance, falloff=falloff, shared_weight=shared)
    model = build_scale(small_labels, shape, MLParams(**params), 0)
    vol, temp = random_state(model)
    model, cl_b, ref = _pair(device, small_labels, shape, vol, temp, **params)
    voxels = np.arange(0, vol.size, 3)
    got, want = cl_b.lcpdf(voxels), ref.lcpdf(voxels)
    assert got.shape == want.shape == (views, voxels.size, model.labels.size)
    # float32 with max-subtraction: absolute error on log-probabilities
    np.testing.assert_allclose(got, want, atol=2e-3 * max(1.0, np.abs(want).max() / 100))


@pytest.mark.each_device
def test_no_underflow_for_11x11_and_256_levels(device):
    """Distances far beyond float32's exp range still give finite, exact log-LCPDFs."""
    rng = np.random.default_rng(5)
    labels_img = rng.integers(0, 256, (24, 24))
    shape = (5, 12, 12)
    params = MLParams(neighborhood=11, scales=1, levels=None, bandwidth=2.0)
    model = build_scale(labels_img, shape, params, 0)
    vol = rng.integers(0, 256, shape).astype(float)
    temp = np.zeros(shape)
    model, cl_b, ref = _pair(device, labels_img, shape, vol, temp, neighborhood=11, scales=1,
                             levels=None, bandwidth=2.0)
    voxels = np.arange(0, vol.size, 7)
    want = ref.lcpdf(voxels)
    assert want.min() < -1000  # exp() underflows below about -104 in float32
    got = cl_b.lcpdf(voxels)
    assert np.isfinite(got).all()
    np.testing.assert_allclose(got, want, rtol=2e-5, atol=1e-2)


@pytest.mark.parametrize("distance", ["squared", "mismatch", "weighted"])
def test_kernel_tables_hold_the_gaussian_factor_and_its_log(small_labels, distance):
    """decide's tables: exp(L) then L, L = -difference / (2 h^2) for every (group, label), padded
    with 1 and 0 so that a padding lane never takes the exact path."""
    from clsolid.ml.model import difference

    model = build_scale(small_labels, (6, 7, 8), MLParams(scales=1, distance=distance), 0)
    values = model.labels[::-1].copy()
    table = kernel_tables(model, values, 16)
    n = model.labels.size
    want = -difference(values[:, None], model.labels[None, :], model.mismatch, model.costs) / (2 * model.bandwidth**2)
    assert table.shape == (2, values.size, 16) and table.dtype == np.float32
    np.testing.assert_allclose(table[1, :, :n], want, rtol=1e-6)
    np.testing.assert_allclose(table[0, :, :n], np.exp(want), rtol=1e-6, atol=1e-37)  # float32 underflows
    assert (table[0, :, n:] == 1).all() and (table[1, :, n:] == 0).all()


@pytest.mark.parametrize("sigma", [1e-200, 5e-324])
def test_a_falloff_too_small_to_weigh_keeps_the_nearest_neighbours(sigma):
    # every Gaussian weight underflowed to 0 (sigma^2 to 0 as well): 0 / 0 gave NaN weights
    from clsolid.ml.model import falloff_weights, view_offsets

    off = view_offsets("front", 2)
    g = falloff_weights(off, sigma)
    nearest = np.sum(off**2, axis=1) == 1
    assert np.isfinite(g).all() and (g[nearest] == g.max()).all() and (g[~nearest] == 0).all()
    assert g.mean() == pytest.approx(1.0)


def test_falloff_weighs_each_term_by_its_gaussian(small_labels):
    """The reference's distance with a fall-off is the plain one with neighbour r's term times
    exp(-d_r^2 / (2 sigma^2)), scaled to a mean of 1; without one every term counts alike."""
    from clsolid.ml.reference import site_distances

    shape = (6, 7, 8)
    plain = build_scale(small_labels, shape, MLParams(neighborhood=5, scales=1, falloff=0), 0)
    assert plain.term_weight is None
    model = build_scale(small_labels, shape, MLParams(neighborhood=5, scales=1, falloff=1.5), 0)
    vol, temp = random_state(model, seed=4)
    voxels = np.arange(0, vol.size, 5)
    for view in range(2):
        off = model.offsets[view]
        d2 = np.sum(off.astype(float) ** 2, axis=1)
        g = np.exp(-d2 / (2 * 1.5**2))
        g /= g.mean()
        np.testing.assert_allclose(model.term_weight, g, rtol=1e-12)
        assert model.term_weight.mean() == pytest.approx(1.0)
        # the row-major window: the four nearest neighbours weigh most, the corners least
        assert np.argmax(model.term_weight) in np.flatnonzero(d2 == 1) and d2[np.argmin(model.term_weight)] == 8
        # term by term, against the plain distance of one-neighbour models
        want = np.zeros((voxels.size, model.n_sites))
        one = build_scale(small_labels, shape, MLParams(neighborhood=5, scales=1, falloff=0), 0)
        for r in range(off.shape[0]):
            one.offsets = model.offsets[:, r:r + 1]
            one.patches = model.patches[r:r + 1]
            want += g[r] * site_distances(one, vol, temp, voxels, view)
        np.testing.assert_allclose(site_distances(model, vol, temp, voxels, view), want, rtol=1e-10)


@pytest.mark.parametrize("views, lines", [(2, ["column"]), (3, ["column", "row"])])
def test_shared_weight_weighs_terms_by_their_direction_along_a_shared_axis(small_labels, views, lines):
    """With front and right the voxels above and below (a view's centre column, dc = 0) are in
    both windows; with the top view too, each view's centre row as well. shared_weight W
    weighs a term 1 - (1 - W) cos^2 of its angle to each such line: W on the line, 1 across
    it (with one shared line), all scaled to a mean of 1, on top of the fall-off."""
    from clsolid.ml.model import direction_weights, falloff_weights, shared_axes

    shape = (6, 7, 8)
    model = build_scale(small_labels, shape, MLParams(neighborhood=5, scales=1, views=views, falloff=0), 0)
    assert model.term_weight is None  # shared_weight None reaches build_scale as 1: every term alike
    assert shared_axes(model.offsets) == ([1] if views == 2 else [0, 1, 2])
    dr, dc = np.divmod(np.delete(np.arange(25), 12), 5)
    dr, dc = dr - 2, dc - 2  # each term's (row, column) offset in its view, row-major, centre left out
    on_line = np.zeros(24, bool)
    on_line |= dc == 0 if "column" in lines else False
    on_line |= dr == 0 if "row" in lines else False
    for v in range(views):  # the lines are the very voxels another view's window holds
        others = {tuple(o) for w in range(views) if w != v for o in model.offsets[w]}
        assert [tuple(o) in others for o in model.offsets[v]] == on_line.tolist()
    cos2_row, cos2_col = dr**2 / (dr**2 + dc**2), dc**2 / (dr**2 + dc**2)
    for shared in (0.0, 0.3):
        want = 1 - (1 - shared) * cos2_row  # the column's direction is the rows' axis
        if views == 3:
            want = want * (1 - (1 - shared) * cos2_col)
        np.testing.assert_allclose(direction_weights(model.offsets, shared), want, rtol=1e-12)
    w = build_scale(small_labels, shape, MLParams(neighborhood=5, scales=1, views=views, shared_weight=0), 0).term_weight
    assert (w[on_line] == 0).all() and (w[~on_line] > 0).all() and w.mean() == pytest.approx(1)
    if views == 2:  # across the shared axis the most, as the centre row's terms
        assert np.flatnonzero(w == w.max()).tolist() == np.flatnonzero(dr == 0).tolist()
    both = build_scale(small_labels, shape, MLParams(neighborhood=5, scales=1, views=views, falloff=1.5,
                                                     shared_weight=0.5), 0).term_weight
    g = falloff_weights(model.offsets[0], 1.5) * direction_weights(model.offsets, 0.5)
    np.testing.assert_allclose(both, g / g.mean(), rtol=1e-12)
    line = build_scale(small_labels, shape, MLParams(neighborhood=5, scales=1, views=views, shared_weight=0,
                                                     shared_profile="line"), 0).term_weight
    assert (line[on_line] == 0).all() and np.allclose(line[~on_line], 24 / np.sum(~on_line))  # the rest alike


def test_a_record_from_before_the_shared_profiles_weighed_the_line():
    """A checkpoint or sidecar with shared_weight but no shared_profile ran with the line alone."""
    old = {k: v for k, v in MLParams(shared_weight=0.0).to_dict().items() if k != "shared_profile"}
    assert MLParams.from_dict(old).shared_profile == "line"
    assert MLParams.from_dict(MLParams(shared_weight=0.0).to_dict()).shared_profile == "direction"
    with pytest.raises(InputError, match="shared_profile"):
        MLParams(shared_profile="diagonal")


@pytest.mark.parametrize("name, views, given, want", [("composite3", 2, None, 0.0), ("composite3", 3, None, 1.0),
                                                      ("brick", 2, None, 1.0), ("composite3", 2, 0.5, 0.5)])
def test_auto_shared_weight_on_categorical_exemplars_with_two_views(device, name, views, given, want):
    res = clsolid.synthesize(gallery_exemplar(name, 64), (8, 8, 8), rng=1, device=device, scales=1, neighborhood=3,
                             views=views, max_sweeps=1, full_output=True,
                             **({} if given is None else {"shared_weight": given}))
    assert res.params["shared_weight"] == want


@pytest.mark.parametrize("bad", [-0.5, 1.5, float("nan"), "0", True])
def test_bad_shared_weight_is_refused(bad):
    with pytest.raises(InputError, match="shared_weight"):
        MLParams(shared_weight=bad)


def test_group_tables_cover_every_site_once(small_labels):
    model = build_scale(small_labels, (8, 8, 8), MLParams(neighborhood=5, scales=1), 0)
    patches, chunk_group, chunk_valid, values, chunk_site, view_chunks = group_tables(model, 16)
    assert chunk_valid.sum() == model.n_sites
    real = (np.arange(16)[None, :] < chunk_valid[:, None]).ravel()
    np.testing.assert_array_equal(np.sort(chunk_site[real]), np.arange(model.n_sites))  # each site's lane
    np.testing.assert_array_equal(patches.transpose(0, 2, 1).reshape(-1, patches.shape[1])[real],
                                  model.patches.T[chunk_site[real]])
    np.testing.assert_array_equal(values, np.unique(model.centres))
    # the real lanes of every group's chunks hold exactly that group's sites
    for g, v in enumerate(values):
        lanes = np.concatenate([patches[c, :, : chunk_valid[c]].T for c in np.flatnonzero(chunk_group == g)])
        want = model.patches[:, model.centres == v].T
        assert sorted(map(tuple, lanes)) == sorted(map(tuple, want))


@pytest.mark.each_device
@pytest.mark.parametrize("heuristic, distance", [(h, "squared") for h in ("h2-product", "h2-min", "h2-max", "h1-lowest",
                                                                          "h1-highest", "h1-mean")]
                         + [("h2-product", "mismatch"), ("h1-lowest", "mismatch"), ("h2-product", "weighted")])
def test_one_icm_step_matches_reference(device, small_labels, heuristic, distance):
    shape = (6, 8, 10)
    params = dict(neighborhood=5, views=3, scales=1, heuristic=heuristic, distance=distance)
    model = build_scale(small_labels, shape, MLParams(**params), 0)
    vol, temp = random_state(model, seed=2)
    model, cl_b, ref = _pair(device, small_labels, shape, vol, temp, **params)
    voxels = np.flatnonzero(model.colour.ravel() == 0)
    for b in (cl_b, ref):
        b.update(voxels)
    np.testing.assert_array_equal(cl_b.volume().ravel()[voxels], ref.volume().ravel()[voxels])
    np.testing.assert_allclose(cl_b.temperature(), ref.temperature(), atol=1e-6)
    untouched = np.setdiff1d(np.arange(vol.size), voxels)
    np.testing.assert_array_equal(cl_b.volume().ravel()[untouched], vol.ravel()[untouched])


@pytest.mark.each_device
def test_scalar_block_has_the_kernels_layout(device):
    """The host's ml_scalars (read from kernels/ml/common.cl) lands field for field where the
    kernels read it: each field written distinct and echoed back by a kernel."""
    import pyopencl as cl

    from clsolid.core import programs
    from clsolid.ml.opencl import scalar_dtype

    dtype = scalar_dtype()
    assert dtype.itemsize == 4 * len(dtype.names)  # 4-byte fields, no padding
    echo = "\n".join(f"    out[{i}] = as_int(P->{name});" for i, name in enumerate(dtype.names))
    source = programs.read_source("ml/common.cl") + (
        "\n__kernel void echo(__constant const ml_scalars *P, __global int *out)\n{\n"
        f"{echo}\n    out[{len(dtype.names)}] = sizeof(ml_scalars);\n}}\n")
    defines = ["-DVW=4", "-DNR=8", "-DNLV=1", "-DMISMATCH=0", "-DTERM_WEIGHTS=0"]
    kernel = cl.Program(device.context, source).build(options=programs.include_options() + defines).echo
    record = np.zeros(1, dtype)
    for i, name in enumerate(dtype.names):
        record[name] = i + 1.5 if dtype[name] == np.float32 else i + 1
    mf = cl.mem_flags
    scalars = cl.Buffer(device.context, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=record)
    out = np.empty(len(dtype.names) + 1, np.int32)
    out_buf = cl.Buffer(device.context, mf.WRITE_ONLY, out.nbytes)
    kernel(device.queue, (1,), None, scalars, out_buf)
    cl.enqueue_copy(device.queue, out, out_buf)
    np.testing.assert_array_equal(out[:-1], record.view(np.int32))
    assert out[-1] == dtype.itemsize


def test_a_second_exemplar_builds_nothing(device):
    """The exemplar's tables (label costs, term weights) are buffers, not compiled in: a second
    exemplar with the same options reuses the first's programs, and each still gets its own
    volume (the tables are not left over from the other)."""
    kw = dict(neighborhood=5, scales=1, distance="weighted", rng=3, device=device)
    three, four = (gallery_exemplar(name, 64)[:32, :32] for name in ("composite3", "composite4"))
    first = clsolid.synthesize(three, (8, 8, 8), **kw)
    built = len(device.programs)
    other = clsolid.synthesize(four, (8, 8, 8), **kw)
    again = clsolid.synthesize(three, (8, 8, 8), **kw)
    assert len(device.programs) == built
    np.testing.assert_array_equal(again, first)
    assert set(np.unique(other)) == set(np.unique(four)) and set(np.unique(first)) == set(np.unique(three))
