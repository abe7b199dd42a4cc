"""An exemplar per view: the tables each view sums over, the kernels against the float64
reference, the API's rules, and a statistical check that each view follows its own exemplar."""

import numpy as np
import pytest

import clsolid
from clsolid.errors import InputError
from clsolid.exemplar import level_map, load_exemplars
from clsolid.ml.model import build_scale
from clsolid.ml.opencl import CLBackend, group_tables
from clsolid.ml.params import MLParams
from clsolid.ml.reference import ReferenceBackend
from tests.ml.test_kernels import random_state


def _stripes(shape, period, axis, phase=0):
    """Binary stripes across *axis* of a 2D image (0 and 1), *period* pixels."""
    idx = np.indices(shape)[axis]
    return (((idx + phase) // (period // 2)) % 2).astype(np.uint8)


@pytest.fixture
def three(small_labels):
    """Three exemplars of different sizes on one level set: the brick corner, its transpose cut,
    and a smaller crop."""
    return {"front": small_labels, "right": small_labels.T[:20, :22].copy(), "top": small_labels[2:20, 3:21].copy()}


def test_each_view_has_its_own_sites(three):
    params = MLParams(neighborhood=5, scales=1)
    model = build_scale(three, (6, 8, 10), params, 0)
    assert model.per_view
    for v, view in enumerate(params.view_names):
        rows, cols = (n - 4 for n in three[view].shape)
        sites = model.sites_of(v)
        assert sites.stop - sites.start == rows * cols
        np.testing.assert_array_equal(model.centres[sites], three[view][2:-2, 2:-2].ravel())
    single = build_scale(three["front"], (6, 8, 10), params, 0)
    assert not single.per_view and single.sites_of(2) == slice(0, single.n_sites)


def test_group_tables_keep_each_views_sites_in_its_chunks(three):
    model = build_scale(three, (6, 8, 10), MLParams(neighborhood=5, scales=1), 0)
    patches, chunk_group, chunk_valid, values, chunk_site, view_chunks = group_tables(model, 8)
    np.testing.assert_array_equal(values, np.unique(model.centres))
    for v in range(3):
        lo, hi = view_chunks[v]
        real = (np.arange(8)[None, :] < chunk_valid[lo:hi, None]).ravel()
        sites = chunk_site[lo * 8: hi * 8][real]
        want = model.sites_of(v)
        np.testing.assert_array_equal(np.sort(sites), np.arange(want.start, want.stop))
        assert np.all(values[chunk_group[lo:hi]] == values[chunk_group[lo:hi]])  # groups index one value set


@pytest.mark.each_device
@pytest.mark.parametrize("views, distance, parents", [
    (3, "squared", 0.0), (3, "weighted", 0.0), ("front+top", "squared", 0.0), ("right+top", "mismatch", 0.0),
    (3, "squared", 0.5)])
def test_per_view_lcpdf_matches_reference(device, three, views, distance, parents):
    names = MLParams(views=views).view_names
    images = {v: three[v] for v in names}
    if distance != "squared":  # phases: labels 0..L-1 shared by every view
        images = {v: (im > 7).astype(np.int32) + (im > 11) for v, im in images.items()}
    scales = 2 if parents else 1
    params = MLParams(neighborhood=5, views=views, scales=scales, distance=distance, parent_weight=parents,
                      parent_min_side=4)
    shape = (7, 9, 11)
    model = build_scale(images, shape, params, 0)
    assert model.parent_rows == (9 if parents else 0)
    vol, temp = random_state(model)
    parent = vol if parents else None
    cl_b, ref = CLBackend(device, voxels_per_item=4), ReferenceBackend()
    for b in (cl_b, ref):
        b.start_scale(model, vol, temp, params, parent=parent)
    voxels = np.arange(0, vol.size, 3)
    got, want = cl_b.lcpdf(voxels), ref.lcpdf(voxels)
    assert got.shape == want.shape == (len(names), voxels.size, model.labels.size)
    np.testing.assert_allclose(got, want, atol=2e-3 * max(1.0, np.abs(want).max() / 100))


@pytest.mark.each_device
def test_per_view_icm_step_matches_reference(device, three):
    params = MLParams(neighborhood=5, scales=1, relaxation="icm")
    shape = (6, 8, 10)
    model = build_scale(three, shape, params, 0)
    vol, temp = random_state(model, seed=2)
    cl_b, ref = CLBackend(device), ReferenceBackend()
    for b in (cl_b, ref):
        b.start_scale(model, vol, temp, params)
    voxels = np.flatnonzero(model.colour.ravel() == 0)
    for b in (cl_b, ref):
        b.update(voxels)
    np.testing.assert_array_equal(cl_b.volume().ravel()[voxels], ref.volume().ravel()[voxels])


def test_levels_are_shared_by_every_view():
    grey = {"front": np.linspace(0, 100, 400).reshape(20, 20), "top": np.linspace(50, 200, 400).reshape(20, 20)}
    lm = level_map(load_exemplars(grey), 8)
    assert set(lm.labels) == {"front", "top"}
    # one set of levels over the pooled range: the front's top half and the top's bottom half meet
    assert lm.labels["front"].min() == 0 and lm.labels["top"].max() == 7
    assert lm.labels["front"].max() < 7 and lm.labels["top"].min() > 0


@pytest.mark.parametrize("source, match", [
    ({"front": "brick"}, "two or three"),
    ({"front": "brick", "side": "brick"}, "not views"),
    ({"front": np.zeros((16, 16), np.uint8), "top": np.zeros((16, 16), np.float32)}, "one dtype"),
    ({"front": np.zeros((16, 16, 3), np.uint8), "top": np.zeros((16, 16), np.uint8)}, "the front exemplar"),
])
def test_bad_sets_of_exemplars_are_refused(source, match):
    with pytest.raises(InputError, match=match):
        load_exemplars(source)


def test_the_api_refuses_what_does_not_fit():
    a = _stripes((24, 24), 6, 0)
    b = _stripes((24, 24), 6, 1)
    with pytest.raises(InputError, match="lacks phase 2"):
        three_phases = (a + 2 * (a == 0) * (np.arange(24) < 3)).astype(np.uint8)
        clsolid.synthesize({"front": three_phases, "top": b}, (8, 8, 8), device="reference")
    with pytest.raises(InputError, match="views=2 but the exemplars are for front and top"):
        clsolid.synthesize({"front": a, "top": b}, (8, 8, 8), views=2, device="reference")
    with pytest.raises(InputError, match="likelihood='pruned' takes one exemplar"):
        clsolid.synthesize({"front": a, "top": b}, (8, 8, 8), likelihood="pruned", device="reference")


def test_each_view_follows_its_own_exemplar(device):
    """Sheets normal to x every 8 voxels, crossed with sheets normal to z every 12 (their XOR):
    the front view (y, x) shows stripes 8 apart across x, the right view (y, z) stripes 12 apart
    across z. Given those two exemplars, the volume must change phase every 4 voxels along x,
    every 6 along z, and not along y; one exemplar for both views could not tell x from z."""
    front = _stripes((36, 36), 8, 1)    # rows y, columns x
    right = _stripes((36, 36), 12, 1)   # rows y, columns z
    res = clsolid.synthesize({"front": front, "right": right}, (24, 24, 24), rng=1, device=device, scales=2,
                             neighborhood=9, full_output=True)  # a window that spans a stripe and its gap
    assert res.params["views"] == 2 and res.params["likelihood"] == "exact"
    vol = res.volume

    def changes(axis: int) -> float:
        """Phase changes per voxel along *axis* (binary stripes with period P: 2 / P)."""
        return float(np.mean(vol != np.roll(vol, 1, axis)))

    assert changes(1) < 0.08                   # y: no stripes in either exemplar
    assert 0.2 < changes(2) < 0.32             # x: the front's period 8, 0.25
    assert 0.12 < changes(0) < 0.22            # z: the right's period 12, 0.167
    assert changes(2) > 1.3 * changes(0)


def _sections(side=40, seed=3):
    from clsolid.groundtruth import ground_truth, sections

    return {v: np.ascontiguousarray(c) for v, c in sections(ground_truth("aniso3", side, seed=seed)).items()}


KW = dict(scales=2, neighborhood=7)


def test_a_per_view_run_resumes_identically(tmp_path, device):
    cuts = _sections()
    whole = clsolid.synthesize(cuts, (16, 16, 16), rng=4, device=device, **KW)

    def stop(info):
        if info.scale == 2 and info.sweep == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        clsolid.synthesize(cuts, (16, 16, 16), rng=4, device=device, backend={"checkpoint": tmp_path / "ck"},
                           progress=stop, **KW)
    resumed = clsolid.resume(tmp_path / "ck", device=device)
    np.testing.assert_array_equal(resumed, whole)


def test_a_per_view_run_in_tiles_is_the_run_in_one_piece(device):
    cuts = _sections()
    whole = clsolid.synthesize(cuts, (16, 16, 16), rng=5, device=device, **KW)
    tiled = clsolid.synthesize(cuts, (16, 16, 16), rng=5, device=device, backend={"tile": 8}, **KW)
    np.testing.assert_array_equal(tiled, whole)


def test_a_pair_of_views_by_name():
    assert MLParams(views="top+front").view_names == ("front", "top")
    assert MLParams(views=("front", "right")).views == 2  # recorded as before
    with pytest.raises(InputError, match="views="):
        MLParams(views="front+front")
    with pytest.raises(InputError, match="shared_weight < 1"):
        build_scale(np.arange(64).reshape(8, 8) % 3, (8, 8, 8), MLParams(neighborhood=3, scales=1,
                                                                         views="right+top", shared_weight=0.5), 0)


def test_the_cli_takes_an_exemplar_per_view_and_its_sidecar_grows_it_again(tmp_path, device):
    import json

    import tifffile

    from clsolid.cli import EXIT_USAGE, main

    cuts = _sections()
    for view, image in cuts.items():
        tifffile.imwrite(tmp_path / f"{view}.tif", image)
    flags = ["--front", str(tmp_path / "front.tif"), "--top", str(tmp_path / "top.tif")]
    out, name = tmp_path / "v.npy", device.device.name.strip()[:8]
    assert main(["synth", *flags, "-o", str(out), "--shape", "12", "12", "12", "--seed", "2", "-q",
                 "--device", name, "--scales", "2", "--neighborhood", "7",
                 "--preview", str(tmp_path / "p.png")]) == 0
    meta = json.loads((tmp_path / "v.json").read_text())
    assert meta["exemplar"] == {"front": flags[1], "top": flags[3]} and meta["params"]["views"] == "front+top"
    again = tmp_path / "w.npy"
    assert main(["synth", "--config", str(tmp_path / "v.json"), "-o", str(again), "-q", "--device", name]) == 0
    np.testing.assert_array_equal(np.load(again), np.load(out))
    assert main(["synth", "brick", *flags, "-o", str(tmp_path / "x.npy")]) == EXIT_USAGE


def test_evaluate_compares_each_view_with_its_own_exemplar(tmp_path, capsys):
    from clsolid import metrics
    from clsolid.cli import EXIT_USAGE, main

    cuts = _sections(side=32)
    vol = np.stack([cuts["front"][:16, :16]] * 16)  # every front slice the front section: the front view fits
    report = metrics.evaluate({"front": cuts["front"][:16, :16], "top": cuts["top"]}, vol, reference_repeats=2)
    assert list(report["views"]) == ["front", "top"] and set(report["exemplars"]) == {"front", "top"}
    assert "views right" in report["settings"]["skipped"]  # no exemplar of its own
    rows = {(r["view"], r["metric"]): r["value"] for r in report["summary"]}
    assert rows[("front", "histogram_kl")] < rows[("top", "histogram_kl")] + 1e-9
    np.save(tmp_path / "v.npy", vol)
    for view in ("front", "top"):
        np.save(tmp_path / f"{view}.npy", cuts[view])
    flags = ["--front", str(tmp_path / "front.npy"), "--top", str(tmp_path / "top.npy")]
    assert main(["evaluate", *flags, str(tmp_path / "v.npy"), "--repeats", "2"]) == 0
    assert "exemplars front 32x32, top 32x32" in capsys.readouterr().out
    assert main(["evaluate", str(tmp_path / "front.npy"), str(tmp_path / "v.npy"), *flags]) == EXIT_USAGE
