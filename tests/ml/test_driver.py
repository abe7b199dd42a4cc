"""Whole runs: OpenCL against the float64 reference, determinism, the driver's rules."""

from dataclasses import replace

import numpy as np
import pytest
from conftest import slow_except

from clsolid.ml.opencl import CLBackend
from clsolid.ml.params import MLParams
from clsolid.ml.reference import ReferenceBackend
from clsolid.ml.driver import run_ml

CASES = [  # (neighborhood, views, heuristic, shape, scales, polish_sweeps)
    (3, 2, "h2-product", (12, 12, 12), 2, 0),
    (5, 2, "h2-product", (16, 12, 10), 2, 0),
    (5, 3, "h2-min", (10, 12, 14), 2, 0),
    (3, 3, "h2-max", (8, 8, 8), 2, 0),
    (5, 2, "h1-lowest", (12, 12, 12), 2, 0),
    (3, 2, "h1-highest", (12, 12, 12), 2, 0),
    (3, 3, "h1-mean", (8, 10, 12), 2, 0),
    (5, 2, "h2-product", (9, 13, 11), 1, 0),
    (3, 2, "h2-product", (12, 12, 12), 2, 2),
    (3, 3, "h1-lowest", (10, 12, 8), 2, 1),
]


@pytest.mark.parametrize("k, views, heuristic, shape, scales, polish", slow_except(CASES, 6, 8))
def test_whole_run_matches_reference(device, small_labels, k, views, heuristic, shape, scales, polish):
    # without the balance: its per-set fit turns float32's last bits into other biases
    # (see tests/ml/test_relaxation.py, test_balance_runs_alike)
    params = MLParams(neighborhood=k, views=views, heuristic=heuristic, scales=scales, insert_slices=1, balance=0.0,
                      polish_sweeps=polish)
    ref, ref_t, _ = run_ml(small_labels, shape, params, 11, ReferenceBackend())
    got, got_t, _ = run_ml(small_labels, shape, params, 11, CLBackend(device))
    agree = np.mean(ref == got)
    assert agree >= 0.99, f"only {agree:.3%} of voxels agree with the float64 reference"
    # the run really relaxed something: not just the initial noise
    assert [s["sweeps"] for s in got_t["scales"]] == [s["sweeps"] for s in ref_t["scales"]]
    # the polish sweeps end the finest scale only
    assert [s["polish_sweeps"] for s in got_t["scales"]] == [0] * (scales - 1) + [polish]


@pytest.mark.slow
def test_polish_sweeps_follow_the_relaxation_and_change_nothing_before(device, small_labels):
    """polish_sweeps=0 is the run without the option; with N, the finest scale's relaxation
    ends where it did, on the same volume, and N sweeps over every voxel follow."""
    shape, params = (12, 14, 16), MLParams(neighborhood=5, scales=2, insert_slices=1)
    plain, plain_t, _ = run_ml(small_labels, shape, params, 3, CLBackend(device))
    np.testing.assert_array_equal(run_ml(small_labels, shape, replace(params, polish_sweeps=0), 3,
                                         CLBackend(device))[0], plain)
    seen = {}
    polished, t, _ = run_ml(small_labels, shape, replace(params, polish_sweeps=2), 3, CLBackend(device),
                            progress=lambda i: seen.setdefault((i.scale, i.sweep), i.volume()))
    coarse, fine = plain_t["scales"]
    relaxed = fine["sweeps"]
    assert t["scales"][0]["visited"] == coarse["visited"]
    assert t["scales"][1]["visited"] == fine["visited"] + [np.prod(shape)] * 2  # the cooled voxels too
    assert t["scales"][1]["polish_sweeps"] == 2
    np.testing.assert_array_equal(seen[(2, relaxed)].reshape(shape), plain)
    assert np.mean(polished != plain) > 0.001  # the polish changed some labels


def test_every_runtime_grows_nearly_the_same_volume(small_labels):
    """PoCL and Intel's CPU runtime (and any other that compiles) agree as each does with float64."""
    from conftest import ALL_DEVICE_SPECS, _DEVICES

    from clsolid.core.device import select_device

    specs = [s for s in ALL_DEVICE_SPECS if not s.startswith("!")]
    if len(specs) < 2:
        pytest.skip(f"only {len(specs)} OpenCL runtime compiles here: nothing to compare")
    params = MLParams(neighborhood=5, scales=2, insert_slices=1, balance=0.0)  # as above
    volumes = [run_ml(small_labels, (16, 12, 14), params, 5, CLBackend(_DEVICES.get(s) or select_device(s)))[0]
               for s in specs]
    for spec, vol in zip(specs[1:], volumes[1:]):
        agree = np.mean(vol == volumes[0])
        assert agree >= 0.99, f"{spec} and {specs[0]} agree on only {agree:.3%} of voxels"


def _run(device, labels, seed, **backend):
    params = MLParams(neighborhood=5, scales=2)
    return run_ml(labels, (12, 16, 20), params, seed, CLBackend(device, **backend))[0]


@pytest.mark.slow
def test_same_seed_same_volume_whatever_the_work_group(device, small_labels):
    a = _run(device, small_labels, 3)
    b = _run(device, small_labels, 3, local_size=1, voxels_per_item=2, max_batch=97)
    c = _run(device, small_labels, 3, local_size=64, voxels_per_item=8)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, c)
    d = _run(device, small_labels, 4)
    # ICM is mode-seeking (most voxels end on the dominant level), so seeds differ on a
    # minority of voxels; their initial noise differs almost everywhere
    assert np.mean(a != d) > 0.03
    px = np.arange(16.0)
    b3, b4 = CLBackend(device).init_volume((8, 8, 8), 3, px), CLBackend(device).init_volume((8, 8, 8), 4, px)
    assert np.mean(b3 != b4) > 0.8


def test_temperature_stop_rule(device, small_labels):
    params = MLParams(neighborhood=3, scales=2, stop_fraction=0.5)
    _, timings, _ = run_ml(small_labels, (8, 8, 8), params, 1, CLBackend(device))
    for s in timings["scales"]:
        t0, ts = s["initial_temperature"], s["temperatures"]
        assert ts[-1] <= 0.5 * t0 or s["sweeps"] == params.max_sweeps
        assert all(t > 0.5 * t0 for t in ts[:-1])  # no sweep after the target was reached
        assert all(b <= a for a, b in zip(ts, ts[1:]))  # cooling is monotone


def test_max_sweeps_bounds_a_scale(device, small_labels):
    params = MLParams(neighborhood=3, scales=1, max_sweeps=2, stop_fraction=1.0, insert_slices=0)
    _, timings, _ = run_ml(small_labels, (8, 8, 8), params, 1, CLBackend(device))
    assert timings["scales"][0]["sweeps"] == 2


@pytest.mark.parametrize("polish", [0, 1])
def test_fixed_inherited_voxels_keep_coarse_values(small_labels, polish):
    """Through the polish sweeps too, which visit every other voxel."""
    params = MLParams(neighborhood=3, scales=2, inherited="fixed", upsampling="1/8", insert_slices=0,
                      polish_sweeps=polish)
    seen = {}

    class Spy(ReferenceBackend):
        def start_scale(self, model, vol, temp, p, sources=None, parent=None):
            seen.setdefault("starts", []).append(vol.copy())
            super().start_scale(model, vol, temp, p, sources, parent)

    out, timings, _ = run_ml(small_labels, (8, 8, 8), params, 2, Spy())
    coarse_start = seen["starts"][1][::2, ::2, ::2]
    np.testing.assert_array_equal(out[::2, ::2, ::2], coarse_start)  # never revisited
    if polish:
        assert timings["scales"][1]["visited"][-1] == 8**3 - 4**3


def test_8_of_8_upsampling_copies_into_all_children(small_labels):
    params = MLParams(neighborhood=3, scales=2, upsampling="8/8", max_sweeps=1, insert_slices=0)
    starts = []

    class Spy(ReferenceBackend):
        def start_scale(self, model, vol, temp, p, sources=None, parent=None):
            starts.append((vol.copy(), temp.copy()))
            super().start_scale(model, vol, temp, p, sources, parent)

        def volume(self):
            return super().volume()

    run_ml(small_labels, (8, 8, 8), params, 2, Spy())
    fine, temp = starts[1]
    blocks = fine.reshape(4, 2, 4, 2, 4, 2)
    assert (blocks == blocks[:, :1, :, :1, :, :1]).all()
    assert (temp[::2, ::2, ::2] == 0).all() and temp.sum() == temp.size * 7 / 8


def test_exact_ties_go_to_the_lowest_label():
    from clsolid.ml.reference import decide

    labels = np.arange(5.0)
    lam = np.arange(5.0)
    # two views, each one Gaussian bump: centred on 2 and on 1 -> product peaks at 1.5
    logl = np.stack([-(lam - 2) ** 2, -(lam - 1) ** 2])[:, None, :] * 0.3
    assert decide(0, logl, labels).tolist() == [1.0]
    logl[1, 0, 2] += 5e-5  # below the tolerance: still a tie
    assert decide(0, logl, labels).tolist() == [1.0]
    logl[1, 0, 2] += 1e-2  # a real difference wins
    assert decide(0, logl, labels).tolist() == [2.0]


@pytest.mark.slow
def test_large_window_whole_run_matches_reference(device, brick_labels):
    """13x13 (beyond the thesis's 11x11), where one-site views create many exact ties."""
    from clsolid.exemplar import quantise

    ex = quantise(brick_labels[:40, :40], 16)
    params = MLParams(neighborhood=13, scales=1, balance=0.0)  # see test_whole_run_matches_reference
    ref = run_ml(ex, (12, 12, 12), params, 1, ReferenceBackend())[0]
    got = run_ml(ex, (12, 12, 12), params, 1, CLBackend(device))[0]
    assert np.mean(ref == got) >= 0.99
