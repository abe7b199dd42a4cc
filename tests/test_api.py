"""The public API: inputs, errors, results, and that import touches no OpenCL."""

import subprocess
import sys

import numpy as np
import pytest

import clsolid
from clsolid import DeviceMemoryError, InputError, NoDeviceError
from clsolid.ml.params import HEURISTICS, MLParams, canonical_heuristic

SMALL = dict(neighborhood=3, scales=1, levels=8)


def test_import_does_not_touch_opencl():
    code = "import sys, clsolid; assert 'pyopencl' not in sys.modules, 'imported pyopencl'"
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.parametrize("name, canonical", [
    ("NP_ML_H2c", "h2-product"), ("ml_h2b", "h2-product"), ("ML_H1b", "h1-mean"), ("NP_ML_H1c", "h1-mean"),
    ("NP_ML_H2b", "h2-max"), ("ML_H2a", "h2-min"), ("np_ml_h1a", "h1-lowest"), ("NP_ML_H1b", "h1-highest"),
])
def test_both_tag_sets_are_aliases(name, canonical):
    assert canonical_heuristic(name) == canonical
    assert set(HEURISTICS) == {"h1-lowest", "h1-highest", "h1-mean", "h2-min", "h2-max", "h2-product"}


@pytest.mark.parametrize("kwargs, word", [
    (dict(neighborhood=4), "neighborhood"), (dict(neighborhood=1), "neighborhood"),
    (dict(scales=0), "scales"), (dict(views=1), "views"), (dict(levels=1), "levels"),
    (dict(heuristic="best"), "heuristic"), (dict(xi=1.0), "xi"), (dict(stop_fraction=0), "stop_fraction"),
    (dict(upsampling="2/8"), "upsampling"), (dict(inherited="maybe"), "inherited"),
    (dict(bandwidth=(1.0,)), "bandwidth"), (dict(bandwidth_factor=-1), "bandwidth_factor"),
    (dict(bandwidth=2.0, bandwidth_factor=1.0), "not both"), (dict(bandwidth_factor=(1.0, 0.5)), "bandwidth_factor"),
    (dict(bandwidth_factor=True), "bandwidth_factor"), (dict(bandwidth_factor="0.2"), "bandwidth_factor"),
    (dict(initial_temperature=0), "initial_temperature"),
    (dict(region=-1), "region"), (dict(region=2.5), "region"),
])
def test_bad_parameters_name_themselves(kwargs, word):
    with pytest.raises(InputError, match=word):
        MLParams(**kwargs)


def test_bandwidth_is_a_fraction_of_silverman_per_scale(brick_labels):
    """Silverman (sigma and site count of each scale, d = k^2) times the factor of the scale:
    0.2 by default, 1 = the thesis."""
    from clsolid.ml.model import build_scale, scale_exemplar, silverman

    cases = (((0.2, 0.2, 0.2), MLParams()), ((1.0, 1.0, 1.0), MLParams(bandwidth_factor=1)),
             ((0.5, 0.3, 2.0), MLParams(bandwidth_factor=[0.5, 0.3, 2])))
    for factors, params in cases:
        assert params.bandwidth_factor == factors
        for level in range(3):
            ex = scale_exemplar(brick_labels, level, params.pyramid)
            k = params.neighborhood
            n = (ex.shape[0] - k + 1) * (ex.shape[1] - k + 1)
            h = build_scale(brick_labels, (16, 16, 16), params, level).bandwidth
            assert h == pytest.approx(factors[level] * silverman(float(ex.std()), n, k * k), rel=1e-12)
    fixed = MLParams(bandwidth=2.0)
    assert fixed.bandwidth == (2.0, 2.0, 2.0) and fixed.bandwidth_factor is None
    assert MLParams(scales=1).bandwidth_factor == (0.2,)


@pytest.mark.parametrize("exemplar, shape, word", [
    (np.zeros((4, 4, 4, 4)), (4, 4, 4), "exemplar"),
    (np.zeros((0, 8)), (4, 4, 4), "exemplar"),
    (np.full((16, 16), np.nan), (4, 4, 4), "exemplar"),
    (np.zeros((16, 16), bool), (4, 4, 4), "exemplar"),
    (np.zeros((16, 16), complex), (4, 4, 4), "exemplar"),
    (np.zeros((16, 16), object), (4, 4, 4), "exemplar"),
    (np.zeros((16, 16, 3), np.uint8), (4, 4, 4), "colour"),
    (np.arange(256.0).reshape(16, 16), (4, 0, 4), "shape"),
    (np.arange(256.0).reshape(16, 16), (4, -2, 4), "shape"),
    (np.arange(256.0).reshape(16, 16), (4, 4), "shape"),
    (np.arange(256.0).reshape(16, 16), (16, 16, True), "shape"),
    (np.arange(256.0).reshape(16, 16), (16, 16, 2.5), "shape"),
    (np.arange(256.0).reshape(16, 16), "444", "shape"),  # int() reads each character: it grew 4x4x4
    ("no-such-texture", (4, 4, 4), "exemplar"),
])
def test_bad_input_is_refused_clearly(exemplar, shape, word):
    with pytest.raises(InputError, match=word):
        clsolid.synthesize(exemplar, shape, device="reference", **SMALL)


def test_exemplar_too_small_for_coarsest_scale():
    with pytest.raises(InputError, match="too small.*coarsest"):
        clsolid.synthesize(np.arange(400.0).reshape(20, 20), (8, 8, 8), neighborhood=9, scales=3,
                           device="reference")


def test_unknown_option_and_method():
    ex = np.arange(256.0).reshape(16, 16)
    with pytest.raises(InputError, match="unknown option 'relaxaton' .*did you mean 'relaxation'"):
        clsolid.synthesize(ex, (4, 4, 4), device="reference", relaxaton="icm", **SMALL)
    with pytest.raises(InputError, match="method='tsvq' is not available"):
        clsolid.synthesize(ex, (4, 4, 4), method="tsvq", device="reference", **SMALL)
    with pytest.raises(InputError, match="iterations=3 is an option of method 'wl', not of 'ml'"):
        clsolid.synthesize(ex, (4, 4, 4), device="reference", iterations=3, **SMALL)
    with pytest.raises(InputError, match="heuristic='h1-mean' is an option of method 'ml', not of 'kopf'"):
        clsolid.synthesize(ex, (4, 4, 4), method="kopf", device="reference", heuristic="h1-mean")
    with pytest.raises(InputError, match="backend= is the likelihood method's"):
        clsolid.synthesize(ex, (4, 4, 4), method="kopf", device="reference", backend={"tile": 4})
    with pytest.raises(InputError, match="unknown option 'tiles' .*did you mean 'tile'"):
        clsolid.synthesize(ex, (4, 4, 4), device="reference", backend={"tiles": 4}, **SMALL)


def test_params_object_and_options_together():
    ex = np.arange(256.0).reshape(16, 16)
    params = MLParams(neighborhood=3, scales=1, levels=8)
    a = clsolid.synthesize(ex, (4, 4, 4), device="reference", rng=1, params=params, relaxation="icm")
    b = clsolid.synthesize(ex, (4, 4, 4), device="reference", rng=1, relaxation="icm", **SMALL)
    np.testing.assert_array_equal(a, b)
    with pytest.raises(InputError, match="are not method 'kopf'"):
        clsolid.synthesize(ex, (4, 4, 4), method="kopf", device="reference", params=params)


def test_a_device_that_is_not_a_name_is_refused_clearly():
    with pytest.raises(InputError, match="device=0 must be a string"):
        clsolid.synthesize("brick", (16, 16, 16), device=0)


def test_a_constant_exemplar_warns():
    with pytest.warns(clsolid.ExemplarWarning, match="constant"):
        volume = clsolid.synthesize(np.full((16, 16), 7, np.uint8), (4, 4, 4), device="reference", **SMALL)
    assert (volume == 7).all()


@pytest.mark.slow
def test_memory_is_checked_before_allocating(device, monkeypatch):
    """A volume too large for the device's max buffer fails up front, naming the buffer."""
    monkeypatch.setattr(type(device), "max_alloc", property(lambda self: 1 << 20))
    with pytest.raises(DeviceMemoryError, match="volume") as info:
        clsolid.synthesize("brick", (128, 128, 128), device=device, **SMALL)
    assert info.value.nbytes == 128**3 * 4 and info.value.limit == 1 << 20
    assert isinstance(info.value, MemoryError)


def test_no_platform_says_how_to_install(monkeypatch):
    import pyopencl as cl

    monkeypatch.setattr(cl, "get_platforms", lambda: [])
    with pytest.raises(NoDeviceError, match=r"pip install \"clsolid\[cpu\]\""):
        clsolid.select_device()
    with pytest.raises(NoDeviceError, match=r"pip install \"clsolid\[cpu\]\""):
        clsolid.list_devices()


def test_select_device_by_syntax_and_name(device):
    assert clsolid.select_device(device) is device
    name = device.device.name.strip()
    assert clsolid.select_device(name[:6]).device.int_ptr == device.device.int_ptr
    assert clsolid.select_device("0:0").device is not None
    with pytest.raises(NoDeviceError, match="no OpenCL device matches"):
        clsolid.select_device("definitely-not-a-device")
    with pytest.raises(NoDeviceError, match="index 99"):
        clsolid.select_device("0:99")


def test_list_devices_describes_each_device(device):
    devices = clsolid.list_devices()
    assert devices and {"index", "platform", "name", "type", "compute_units", "global_mem", "max_alloc",
                        "fp64", "driver", "opencl_c", "compiles", "probe_message"} <= set(devices[0])
    assert {d["type"] for d in devices} <= {"CPU", "GPU", "ACCELERATOR", "CUSTOM", "OTHER"}


def test_result_object_reports_everything(device):
    r = clsolid.synthesize("brick", (8, 10, 12), rng=5, device=device, full_output=True, **SMALL)
    assert r.labels.shape == (8, 10, 12) and r.labels.dtype == np.uint8
    assert r.labels.max() < 8 and r.seed == 5 and not r.values_exact
    # brick is float64 (area-averaged): the volume holds its level means, in its dtype
    assert r.volume.dtype == np.float64 and r.level_values.size == 8
    np.testing.assert_array_equal(r.volume, r.level_values[r.labels])
    np.testing.assert_array_equal(r.exemplar, r.level_values[r.exemplar_labels])
    assert r.params["neighborhood"] == 3 and r.params["heuristic"] == "h2-product"
    assert len(r.params["bandwidth_effective"]) == 1 and r.params["bandwidth_effective"][0] > 0
    assert r.timings["total_s"] > 0 and r.timings["scales"][0]["sweeps"] >= 1
    np.testing.assert_array_equal(clsolid.synthesize("brick", (8, 10, 12), rng=5, device=device, **SMALL), r.volume)
    np.testing.assert_array_equal(
        clsolid.synthesize("brick", (8, 10, 12), rng=5, device=device, output="labels", **SMALL), r.labels)
    with pytest.raises(InputError, match="output"):
        clsolid.synthesize("brick", (8, 10, 12), device=device, output="indices", **SMALL)


def test_progress_reports_every_sweep(device):
    seen = []
    r = clsolid.synthesize("brick", (8, 8, 8), rng=1, device=device, progress=seen.append, full_output=True,
                           neighborhood=3, scales=2, levels=8)
    assert len(seen) == sum(s["sweeps"] for s in r.timings["scales"])
    last = seen[-1]
    assert last.scale == 2 and last.volume().shape == (8, 8, 8) and last.elapsed > 0
    assert [i.temperature for i in seen if i.scale == 2] == r.timings["scales"][1]["temperatures"]


@pytest.mark.parametrize("method", ["ml", "kopf"])
def test_a_progress_that_is_not_a_function_is_refused_before_the_run(method):
    # it failed at the first sweep's report, with TypeError: 'int' object is not callable
    with pytest.raises(InputError, match="progress=1 must be a function"):
        clsolid.synthesize(np.arange(256.0).reshape(16, 16), (4, 4, 4), method=method, device="reference",
                           progress=1, **SMALL)


@pytest.mark.parametrize("option", [{"bandwidth_factor": 1e308}, {"bandwidth": 1e-308}])
def test_a_bandwidth_the_kernels_cannot_hold_is_refused(device, option):
    # 1 / (2 h^2) overflowed (OverflowError) or divided by zero (ZeroDivisionError) on building the scale
    ex = np.arange(256.0).reshape(16, 16)
    for dev in ("reference", device):
        with pytest.raises(InputError, match=f"{next(iter(option))}=.* gives a Parzen bandwidth of"):
            clsolid.synthesize(ex, (4, 4, 4), device=dev, rng=1, **SMALL, **option)


def test_rng_generator_and_none():
    ex = np.arange(256.0).reshape(16, 16)
    a = clsolid.synthesize(ex, (4, 4, 4), device="reference", full_output=True,
                           rng=np.random.default_rng(3), **SMALL)
    b = clsolid.synthesize(ex, (4, 4, 4), device="reference", full_output=True, rng=None, **SMALL)
    assert a.seed != b.seed
    with pytest.raises(InputError, match="rng"):
        clsolid.synthesize(ex, (4, 4, 4), device="reference", rng=-1, **SMALL)


def test_level_means_stand_for_each_level():
    from clsolid.exemplar import level_map, quantise

    img = np.linspace(10.0, 250.0, 400).reshape(20, 20)
    m = level_map(img, 16)
    np.testing.assert_array_equal(m.labels, quantise(img, 16))
    assert not m.exact and m.values.dtype == np.float64
    for level in range(16):  # each value is the mean of the exemplar pixels of its level
        assert m.values[level] == pytest.approx(img[m.labels == level].mean())
    assert np.abs(m.to_values(m.labels) - img).max() <= (250 - 10) / 16  # within a bin
    assert level_map(img.astype(np.uint8), None).values.tolist() == list(range(256))


@pytest.mark.parametrize("name, image, exact", [
    ("binary", np.where(np.add.outer(np.arange(16), np.arange(16)) % 5 < 2, 255, 0).astype(np.uint8), True),
    ("3-phase", (np.add.outer(np.arange(16), 2 * np.arange(16)) % 3).astype(np.uint8), True),
    ("8-bit", (np.arange(256).reshape(16, 16)).astype(np.uint8), False),
    ("16-bit", (np.arange(256).reshape(16, 16) * 257).astype(np.uint16), False),
    ("float", np.linspace(-1.5, 2.5, 256).reshape(16, 16).astype(np.float32), False),
])
def test_volume_in_the_exemplar_units(name, image, exact):
    """The volume comes back in the exemplar's dtype; few-valued exemplars keep their exact values."""
    r = clsolid.synthesize(image, (6, 6, 6), rng=2, device="reference", full_output=True,
                           neighborhood=3, scales=1, levels=8)
    assert r.volume.dtype == image.dtype and r.values_exact == exact, name
    np.testing.assert_array_equal(r.volume, r.level_values[r.labels])
    if exact:  # only values that occur in the exemplar, and the exemplar unchanged
        assert set(np.unique(r.volume)) <= set(np.unique(image))
        np.testing.assert_array_equal(r.exemplar, image)
    else:  # one value per level, each the mean of the exemplar pixels of that level
        for level in np.unique(r.exemplar_labels):
            mean = image[r.exemplar_labels == level].astype(np.float64).mean()
            tol = 0.5 if image.dtype.kind in "iu" else 1e-6
            assert abs(float(r.level_values[level]) - mean) <= tol
        assert r.volume.min() >= image.min() and r.volume.max() <= image.max()


@pytest.mark.parametrize("option, value", [("voxels_per_item", 3), ("vector_width", 32), ("local_size", 0),
                                           ("max_batch", -5)])
def test_bad_tuning_options(device, option, value):
    with pytest.raises(InputError, match=option):
        clsolid.synthesize("brick", (8, 8, 8), device=device, backend={option: value}, **SMALL)


def test_progress_carries_the_scale_exemplar(device):
    seen = []
    clsolid.synthesize("brick", (8, 8, 8), rng=1, device=device, progress=seen.append, neighborhood=3,
                       scales=2, levels=8)
    from clsolid.exemplar import builtin_exemplar, quantise
    from clsolid.ml.model import scale_exemplar

    labels = quantise(builtin_exemplar("brick"), 8)
    np.testing.assert_array_equal(seen[0].exemplar, scale_exemplar(labels, 1, "binomial"))
    np.testing.assert_array_equal(seen[-1].exemplar, labels)
