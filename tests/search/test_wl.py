"""NP_WL (clsolid.search.wl): features and pyramid against direct loops, the OpenCL run
against the float64 reference, determinism by seed, the inner repetition, and a statistic
that the published method must improve on its noise start."""

from functools import partial

import numpy as np
import pytest
from conftest import slow_except

from clsolid import InputError
from clsolid.core.views import VIEW_AXES
from clsolid.gallery import gallery_exemplar
from clsolid.search.features import centre_weights, exemplar_features, voxel_features
from clsolid.search.match import CLMatcher, ReferenceMatcher
from clsolid.search.params import SearchParams
from clsolid.search.pyramid import gaussian_pyramid
from clsolid.search.driver import level_shapes, run_search as run_wl


def _exemplar(size=24, seed=0):
    return np.random.default_rng(seed).integers(0, 256, (size, size)).astype(np.float64)


def test_exemplar_features_are_the_windows_and_their_parents():
    fine, coarse = _exemplar(20), _exemplar(10, 1)
    table, centres = exemplar_features(fine, coarse, 5)
    # valid sites: the 5x5 window inside fine and the 3x3 parent window inside coarse
    sites = [(r, c) for r in range(2, 18) for c in range(2, 18) if 1 <= r // 2 <= 8 and 1 <= c // 2 <= 8]
    assert table.shape == (len(sites), 25 + 9)
    for s in (0, 5, len(sites) - 1):
        r, c = sites[s]
        np.testing.assert_array_equal(table[s, :25], fine[r - 2 : r + 3, c - 2 : c + 3].ravel())
        np.testing.assert_array_equal(table[s, 25:], coarse[r // 2 - 1 : r // 2 + 2, c // 2 - 1 : c // 2 + 2].ravel())
        assert centres[s] == fine[r, c]


@pytest.mark.parametrize("view", ["front", "right", "top"])
def test_voxel_features_wrap_in_the_view_plane(view):
    rng = np.random.default_rng(2)
    vol, coarse = rng.random((6, 7, 8)), rng.random((3, 3, 4))
    voxels = np.arange(vol.size)  # squares inside the block and squares that wrap
    got = voxel_features(vol, coarse, voxels, view, 3)
    ra, ca = VIEW_AXES[view]
    for row, v in zip(got, voxels):
        pos = np.unravel_index(v, vol.shape)
        want = []
        for src, p, side in ((vol, pos, 3), (coarse, tuple(q // 2 for q in pos), 3)):
            for dr in (-1, 0, 1):
                for dc in (-1, 0, 1):
                    q = [a % n for a, n in zip(p, src.shape)]  # odd sides: the parent wraps too
                    q[ra] = (q[ra] + dr) % src.shape[ra]
                    q[ca] = (q[ca] + dc) % src.shape[ca]
                    want.append(src[tuple(q)])
        np.testing.assert_array_equal(row, want)


def test_pyramid_filters_then_halves():
    ex = _exemplar(32)
    pyr = gaussian_pyramid(ex, 3)
    assert [p.shape for p in pyr] == [(32, 32), (16, 16), (8, 8)]
    np.testing.assert_allclose(gaussian_pyramid(np.full((16, 16), 7.0), 2)[1], 7.0)
    impulse = np.zeros((9, 9))
    impulse[4, 4] = 256.0
    blurred = gaussian_pyramid(impulse, 2)[1]  # the [1 4 6 4 1]/16 kernel, sampled on even pixels
    np.testing.assert_allclose(blurred[2, 1:4], 256 * (6 / 16) * np.array([1, 6, 1]) / 16)
    assert level_shapes((10, 12, 14), 3) == [(10, 12, 14), (5, 6, 7), (2, 3, 3)]


def test_centre_weights():
    w = centre_weights(3, True, centre=False)
    assert w.size == 18 and w[4] == 0 and w.sum() == 17
    assert centre_weights(3, False, centre=True).tolist() == [1.0] * 9


@pytest.mark.parametrize("views, k, parent", slow_except([(2, 5, True), (3, 3, True), (2, 3, False)], 2))
def test_opencl_run_matches_the_reference(device, views, k, parent):
    ex = _exemplar(24)
    params = SearchParams(neighborhood=k, scales=2, iterations=2, views=views, parent=parent)
    ref, ref_t = run_wl(ex, (10, 12, 14), params, 3, ReferenceMatcher)[:2]
    got, got_t = run_wl(ex, (10, 12, 14), params, 3, partial(CLMatcher, device))[:2]
    agree = np.mean(np.isclose(ref, got, rtol=0, atol=1e-9))
    assert agree >= 0.99, f"only {agree:.2%} of voxels agree with the float64 reference"
    if views == 2:  # halves of integers: every distance exact in float32, so the runs are equal
        np.testing.assert_array_equal(got, ref)
        assert [lv["searches"] for lv in got_t["levels"]] == [lv["searches"] for lv in ref_t["levels"]]


def test_same_seed_same_volume(device):
    ex = _exemplar(24)
    params = SearchParams(neighborhood=3, scales=2, iterations=2)
    run = lambda seed: run_wl(ex, (8, 8, 8), params, seed, partial(CLMatcher, device))[0]  # noqa: E731
    a = run(5)
    np.testing.assert_array_equal(a, run(5))
    assert np.mean(a != run(6)) > 0.5


def test_inner_repetition_counts_its_searches():
    ex = _exemplar(20)
    once = run_wl(ex, (8, 8, 8), SearchParams(neighborhood=3, scales=1, iterations=2, inner=1), 1, ReferenceMatcher)[1]
    assert once["levels"][0]["searches"] == 3 * 512 * 2  # views x voxels x passes
    again = run_wl(ex, (8, 8, 8), SearchParams(neighborhood=3, scales=1, iterations=2, inner=4), 1, ReferenceMatcher)[1]
    assert 3 * 512 * 2 < again["levels"][0]["searches"] <= 4 * 3 * 512 * 2


@pytest.mark.slow
def test_wl_grows_structure_from_noise(device):
    """porous80 (23 % pores): WL keeps some pores, in blobs (neighbours on different phases
    far rarer than in noise of the same fractions). From noise at every level (the
    Wei-Levoy reading) it collapses to the matrix: the reason the default up-samples."""
    ex = (gallery_exemplar("porous80", 64) > 0).astype(np.float64)

    def grow(init):
        return run_wl(ex, (16, 16, 16), SearchParams(iterations=3, init=init), 1, partial(CLMatcher, device))[0]

    def jumps(img):  # fraction of horizontal neighbours on different phases
        return np.mean(np.abs(np.diff(img, axis=-1)) > 0.5)

    vol = grow("upsample")
    pores = np.mean(vol < 0.5)
    assert 0.03 < pores < 0.5, pores  # not collapsed (measured 0.07: WL favours the majority)
    noise = np.random.default_rng(0).permutation(vol.ravel()).reshape(vol.shape)
    assert jumps(vol) < 0.5 * jumps(noise), (jumps(vol), jumps(noise))
    assert np.mean(grow("noise") < 0.5) < 0.01  # the collapse the default avoids


@pytest.mark.parametrize("kwargs, word", [
    (dict(method="tsvq"), "method"), (dict(neighborhood=6), "odd"), (dict(scales=0), "scales"),
    (dict(iterations=0), "iterations"), (dict(views=4), "views"), (dict(inner=0), "inner"),
    (dict(parent=1), "parent"), (dict(init="zeros"), "init"),
])
def test_bad_parameters_name_themselves(kwargs, word):
    with pytest.raises(InputError, match=word):
        SearchParams(**kwargs)


def test_too_many_levels_for_the_exemplar_is_an_input_error():
    with pytest.raises(InputError, match="fewer scales"):
        run_wl(_exemplar(16), (16, 16, 16), SearchParams(neighborhood=7, scales=3), 1, ReferenceMatcher)


@pytest.mark.slow
def test_synthesize_runs_wl(device):
    import clsolid

    got = clsolid.synthesize("brick", (12, 12, 12), method="wl", scales=2, iterations=1, rng=4, device=device)
    assert got.shape == (12, 12, 12) and got.dtype == np.float64
    res = clsolid.synthesize("brick", (12, 12, 12), method="wl", scales=2, iterations=1, rng=4,
                             device="reference", full_output=True)
    np.testing.assert_array_equal(res.volume, got)  # 32 levels' values: halves of sums exact in float32
    assert res.labels is None and res.params["method"] == "wl" and res.params["neighborhood"] == 7
    assert res.params["levels"] == 32 and res.timings["levels"][-1]["level"] == 0


@pytest.mark.slow
def test_wl_with_specify_keeps_the_exemplars_values_and_dtype(device):
    import clsolid

    res = clsolid.synthesize(gallery_exemplar("gravel", 64), (12, 12, 12), method="wl", scales=2, iterations=1,
                             specify=True, rng=4, device=device, full_output=True)
    assert res.volume.dtype == np.uint8 and np.isin(res.volume, res.level_values).all()


@pytest.mark.parametrize("kwargs, word", [
    (dict(output="labels"), "no level indices"), (dict(xi=-2.0), "an option of method 'ml', not of 'wl'"),
    (dict(relaxaton="icm"), "unknown option"), (dict(iteratons=3), "did you mean 'iterations'"),
    (dict(neighborhood=8), "odd"), (dict(iterations=0), "iterations"), (dict(heuristic="h2-min"), "heuristic"),
])
def test_synthesize_refuses_what_wl_cannot_do(kwargs, word):
    import clsolid

    with pytest.raises(InputError, match=word):
        clsolid.synthesize("brick", (8, 8, 8), method="wl", device="reference", **kwargs)


def test_cli_wl_writes_volume_sidecar_and_preview(tmp_path, device):
    import json

    from clsolid.cli import main

    out = tmp_path / "v.npy"
    assert main(["synth", "brick", "-o", str(out), "--method", "wl", "--shape", "12", "12", "12", "--scales", "2",
                 "--iterations", "1", "--inner", "2", "--init", "noise", "--seed", "3", "--device", device.device.name.strip()[:8],
                 "--preview", str(tmp_path / "v.png"), "-q"]) == 0
    meta = json.loads((tmp_path / "v.json").read_text())
    assert meta["params"]["method"] == "wl" and meta["params"]["inner"] == 2 and meta["seed"] == 3
    assert meta["params"]["init"] == "noise"
    assert np.load(out).shape == (12, 12, 12) and (tmp_path / "v.png").stat().st_size > 0


@pytest.mark.parametrize("argv, word", [
    (["--method", "wl", "--xi", "-2"], "--xi not used by --method wl"),
    (["--method", "wl", "--indices"], "--indices not used by --method wl"),
    (["--iterations", "3"], "--iterations not used by --method ml"),
    (["--rule", "overlap"], "--rule not used by --method ml"),
    (["--method", "wl", "--rule", "overlap", "--shape", "8", "8", "8"], "rule='overlap' is kopf's"),
])
def test_cli_refuses_flags_the_method_ignores(tmp_path, capsys, argv, word):
    from clsolid.cli import EXIT_USAGE, main

    assert main(["synth", "-o", str(tmp_path / "v.npy"), *argv]) == EXIT_USAGE
    assert word in capsys.readouterr().err
