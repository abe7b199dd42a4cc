"""Tests of clsolid.exemplar: built-ins, loading/validation and quantisation."""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
import skimage.data
import tifffile
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from clsolid.errors import InputError
from clsolid.exemplar import BUILTINS, builtin_exemplar, load_exemplar, quantise, window_grid


def _block_mean(name: str, region: int, size: int) -> np.ndarray:
    corner = getattr(skimage.data, name)()[:region, :region].astype(np.float64)
    k = region // size
    return corner.reshape(size, k, size, k).mean(axis=(1, 3))


# --------------------------------------------------------------------------- builtins


@pytest.mark.parametrize("name", BUILTINS)
def test_builtin_is_block_mean_of_corner(name):
    ex = builtin_exemplar(name)
    assert ex.shape == (64, 64)
    assert ex.dtype == np.float64
    np.testing.assert_array_equal(ex, _block_mean(name, 256, 64))
    assert 0.0 <= ex.min() and ex.max() <= 255.0


def test_builtin_size_and_region_options():
    ex = builtin_exemplar("brick", size=32, region=128)
    np.testing.assert_array_equal(ex, _block_mean("brick", 128, 32))
    full = builtin_exemplar("gravel", size=512, region=512)
    np.testing.assert_array_equal(full, skimage.data.gravel().astype(np.float64))


def test_builtin_non_divisible_is_area_average():
    # 100 -> 7: each output pixel averages a 100/7 px footprint; the overall mean is preserved.
    ex = builtin_exemplar("grass", size=7, region=100)
    corner = skimage.data.grass()[:100, :100].astype(np.float64)
    assert ex.shape == (7, 7)
    assert ex.mean() == pytest.approx(corner.mean(), rel=1e-12)
    assert corner.min() <= ex.min() and ex.max() <= corner.max()
    # The first output pixel covers rows/cols [0, 14.2857): 14 full pixels + 2/7 of the 15th.
    r = 100 / 7
    w = np.r_[np.ones(14), r - 14] / r
    assert ex[0, 0] == pytest.approx(w @ corner[:15, :15] @ w)


@pytest.mark.parametrize(
    "kwargs, param",
    [
        ({"name": "marble"}, "name"),
        ({"name": "brick", "size": 0}, "size"),
        ({"name": "brick", "size": 300}, "size"),
        ({"name": "brick", "size": 64, "region": 600}, "region"),
        ({"name": "brick", "size": True}, "size"),
        ({"name": "brick", "size": 8.0}, "size"),
    ],
)
def test_builtin_bad_input(kwargs, param):
    with pytest.raises(InputError, match=param):
        builtin_exemplar(**kwargs)


def test_builtin_unknown_name_lists_valid_names():
    with pytest.raises(InputError) as info:
        builtin_exemplar("marble")
    for name in BUILTINS:
        assert name in str(info.value)


# --------------------------------------------------------------------------- load_exemplar


def test_load_builtin_by_name_and_size():
    np.testing.assert_array_equal(load_exemplar("brick"), builtin_exemplar("brick"))
    assert load_exemplar("grass", builtin_size=32).shape == (32, 32)


def test_load_array_keeps_dtype_and_copies():
    a = np.arange(12, dtype=np.uint16).reshape(3, 4) * 1000
    out = load_exemplar(a)
    assert out.dtype == np.uint16
    np.testing.assert_array_equal(out, a)
    out[0, 0] = 7
    assert a[0, 0] == 0  # no aliasing with the caller's array


def test_load_array_squeezes_singleton_axes():
    a = np.arange(12, dtype=np.float32).reshape(3, 4)
    np.testing.assert_array_equal(load_exemplar(a[..., None]), a)
    np.testing.assert_array_equal(load_exemplar(a[None]), a)


def test_load_big_endian_becomes_native():
    a = np.arange(6, dtype=">f8").reshape(2, 3)
    out = load_exemplar(a)
    assert out.dtype == np.float64 and out.dtype.isnative
    np.testing.assert_array_equal(out, a)


@pytest.fixture
def grey8() -> np.ndarray:
    return np.random.default_rng(0).integers(0, 256, size=(20, 30), dtype=np.uint8)


@pytest.mark.parametrize("suffix", [".png", ".PNG"])
def test_load_png_uint8(tmp_path, grey8, suffix):
    path = tmp_path / f"ex{suffix}"
    Image.fromarray(grey8).save(path, format="PNG")
    out = load_exemplar(path)
    assert out.dtype == np.uint8
    np.testing.assert_array_equal(out, grey8)
    np.testing.assert_array_equal(load_exemplar(str(path)), grey8)


def test_load_png_uint16(tmp_path):
    a = (np.arange(600).reshape(20, 30) * 100).astype(np.uint16)
    path = tmp_path / "ex16.png"
    Image.fromarray(a).save(path)
    out = load_exemplar(path)
    assert out.dtype == np.uint16
    np.testing.assert_array_equal(out, a)


@pytest.mark.parametrize("suffix", [".tif", ".tiff", ".TIF"])
def test_load_tiff(tmp_path, suffix):
    a = np.random.default_rng(1).random((16, 24)).astype(np.float32)
    path = tmp_path / f"ex{suffix}"
    tifffile.imwrite(path, a)
    out = load_exemplar(path)
    assert out.dtype == np.float32
    np.testing.assert_array_equal(out, a)


def test_load_npy(tmp_path, grey8):
    path = tmp_path / "ex.npy"
    np.save(path, grey8.astype(np.int16))
    out = load_exemplar(path)
    assert out.dtype == np.int16
    np.testing.assert_array_equal(out, grey8)


def test_load_rgb_png_is_colour(tmp_path, grey8):
    path = tmp_path / "rgb.png"
    rgb = np.dstack([grey8, grey8 // 2, grey8 // 3])
    Image.fromarray(rgb).save(path)
    out = load_exemplar(path)
    assert out.shape == rgb.shape and out.dtype == np.uint8
    np.testing.assert_array_equal(out, rgb)


def test_load_rgba_png_is_refused_with_what_to_do(tmp_path, grey8):
    path = tmp_path / "rgba.png"
    Image.fromarray(np.dstack([grey8, grey8 // 2, grey8 // 3, grey8])).save(path)
    with pytest.raises(InputError, match=r"RGBA.*drop the alpha"):
        load_exemplar(path)


@pytest.mark.parametrize("mode", ["RGB", "P"])
def test_a_grey_png_saved_as_rgb_or_a_palette_is_grey(tmp_path, grey8, mode):
    path = tmp_path / f"grey-{mode}.png"
    Image.fromarray(grey8).convert(mode).save(path)
    out = load_exemplar(path)
    assert out.ndim == 2
    np.testing.assert_array_equal(out, grey8)


@pytest.mark.parametrize("axis", [-1, 0, 2])
def test_channel_axis_puts_the_channels_last(grey8, axis):
    rgb = np.dstack([grey8, 255 - grey8, grey8 // 2])
    given = np.moveaxis(rgb, -1, axis)
    np.testing.assert_array_equal(load_exemplar(given, channel_axis=axis), rgb)


@pytest.mark.parametrize("array, axis, needle", [
    (np.zeros((4, 5, 4)), -1, "RGBA"), (np.zeros((4, 5, 2)), -1, "2 channels"), (np.zeros((4, 5)), -1, "3 dimensions"),
    (np.zeros((4, 5, 3)), 3, "3 dimensions"), (np.zeros((4, 5, 3)), 1.0, "integer"),
    (np.zeros((4, 5, 3)), True, "integer"),
])
def test_bad_channel_axis_or_channels_are_refused(array, axis, needle):
    with pytest.raises(InputError, match=needle):
        load_exemplar(array, channel_axis=axis)


def test_load_tiff_stack_is_volume_error(tmp_path):
    path = tmp_path / "stack.tif"
    tifffile.imwrite(path, np.zeros((5, 8, 9), dtype=np.uint8))
    with pytest.raises(InputError, match="exemplar.*volume"):
        load_exemplar(path)


def _write_text(path: pathlib.Path) -> pathlib.Path:
    path.write_text("not an image")
    return path


@pytest.mark.parametrize(
    "make_source, needle",
    [
        (lambda d: d / "missing.png", "does not exist"),
        (lambda d: str(d / "missing.tif"), "does not exist"),
        (lambda d: _write_text(d / "ex.jpg"), ".png"),
        (lambda d: _write_text(d / "bad.png"), "PNG"),
        (lambda d: _write_text(d / "bad.tif"), "TIFF"),
        (lambda d: _write_text(d / "bad.npy"), ".npy"),
        (lambda d: d, "not a regular file"),
        (lambda d: "marble", "built-in"),
        (lambda d: 42, "int"),
        (lambda d: [[1, 2], [3, 4]], "list"),
    ],
)
def test_load_bad_sources(tmp_path, make_source, needle):
    source = make_source(tmp_path)
    if source is tmp_path:
        source = tmp_path / "dir.png"
        source.mkdir()
    with pytest.raises(InputError, match="exemplar") as info:
        load_exemplar(source)
    assert needle in str(info.value)


def test_unknown_string_mentions_both_possibilities():
    with pytest.raises(InputError) as info:
        load_exemplar("marble")
    msg = str(info.value)
    assert "'marble'" in msg and "file" in msg and "brick" in msg


@pytest.mark.parametrize(
    "array, needle",
    [
        (np.zeros((4, 5, 3)), "colour"),
        (np.zeros((4, 5, 4)), "colour"),
        (np.zeros((4, 5, 2)), "alpha"),
        (np.zeros((6, 5, 7)), "volume"),
        (np.zeros(5), "2D"),
        (np.zeros((2, 2, 2, 2)), "2D"),
        (np.array(3.0), "2D"),
        (np.zeros((0, 5)), "empty"),
        (np.zeros((5, 0)), "empty"),
        (np.zeros((3, 3), dtype=bool), "bool"),
        (np.zeros((3, 3), dtype=complex), "complex"),
        (np.zeros((3, 3), dtype=object), "object"),
        (np.full((3, 3), "a"), "<U1"),
        (np.array([[0.0, np.nan]]), "NaN"),
        (np.array([[0.0, np.inf]]), "infinite"),
        (np.array([[-np.inf, 1.0]], dtype=np.float32), "infinite"),
    ],
)
def test_load_bad_arrays(array, needle):
    with pytest.raises(InputError, match="exemplar") as info:
        load_exemplar(array)
    msg = str(info.value)
    assert needle in msg
    # The message names the offending value: its shape, its dtype or the count of bad values.
    assert str(array.shape) in msg or str(array.dtype) in msg or "1 NaN" in msg


@pytest.mark.parametrize("bad", [0, 257, True, 2.5])
def test_load_bad_builtin_size(bad):
    with pytest.raises(InputError, match="builtin_size"):
        load_exemplar("brick", builtin_size=bad)


# --------------------------------------------------------------------------- quantise


def test_quantise_range_and_all_levels_used():
    img = np.linspace(-3.0, 5.0, 1000).reshape(20, 50)
    q = quantise(img, 32)
    assert q.dtype == np.int32 and q.shape == img.shape
    assert q.min() == 0 and q.max() == 31
    assert set(np.unique(q)) == set(range(32))


def test_quantise_rule_examples():
    img = np.array([[0.0, 0.24, 0.25, 0.5, 0.99, 1.0]])
    np.testing.assert_array_equal(quantise(img, 4), [[0, 0, 1, 2, 3, 3]])


def test_quantise_integers_are_exact_on_boundaries():
    # 0..255 onto 256 levels: v * 256 // 255, so 255 -> 256 clipped to 255, and all levels used.
    img = np.arange(256, dtype=np.uint8).reshape(16, 16)
    q = quantise(img, 256)
    assert set(np.unique(q)) == set(range(256))
    img16 = np.arange(0, 65536, 1, dtype=np.uint16).reshape(256, 256)
    np.testing.assert_array_equal(quantise(img16, 256).ravel(), np.arange(65536) // 256)


def test_quantise_none_on_uint8_is_identity():
    img = np.random.default_rng(2).integers(10, 200, size=(8, 9), dtype=np.uint8)
    q = quantise(img, None)
    assert q.dtype == np.int32
    np.testing.assert_array_equal(q, img)


@pytest.mark.parametrize("dtype", [np.uint16, np.float64, np.int32])
def test_quantise_none_on_other_dtypes_is_error(dtype):
    with pytest.raises(InputError, match="levels") as info:
        quantise(np.zeros((3, 3), dtype=dtype), None)
    assert "uint8" in str(info.value)


@pytest.mark.parametrize("dtype", [np.uint8, np.float32, np.int64])
def test_quantise_constant_image_is_zero(dtype):
    q = quantise(np.full((4, 4), 7, dtype=dtype), 16)
    assert q.dtype == np.int32
    np.testing.assert_array_equal(q, 0)


@pytest.mark.parametrize("bad", [1, 0, -4, 65537, True, False, 2.0, "32"])
def test_quantise_bad_levels(bad):
    with pytest.raises(InputError, match="levels") as info:
        quantise(np.arange(4.0).reshape(2, 2), bad)
    assert repr(bad) in str(info.value)


def test_quantise_levels_bounds_accepted():
    img = np.arange(10.0)
    assert quantise(img, 2).max() == 1
    assert quantise(img, np.int64(65536)).max() == 65535


@pytest.mark.parametrize(
    "image, needle",
    [
        (np.zeros((0, 3)), "empty"),
        (np.array([[np.nan, 1.0]]), "NaN"),
        (np.zeros((2, 2), dtype=bool), "bool"),
        ([[1, 2]], "list"),
    ],
)
def test_quantise_bad_image(image, needle):
    with pytest.raises(InputError, match="image") as info:
        quantise(image, 8)
    assert needle in str(info.value)


def test_quantise_extreme_float_range():
    img = np.array([-1e308, 0.0, 1e308])
    np.testing.assert_array_equal(quantise(img, 4), [0, 2, 3])


@settings(max_examples=60, deadline=None)
@given(
    values=st.lists(st.floats(-1e6, 1e6, allow_nan=False), min_size=2, max_size=60),
    levels=st.integers(2, 300),
)
def test_quantise_is_monotone_and_in_range(values, levels):
    img = np.array(values)
    q = quantise(img, levels)
    assert q.min() >= 0 and q.max() <= levels - 1
    order = np.argsort(img, kind="stable")
    assert np.all(np.diff(q[order]) >= 0)
    if img.max() > img.min():
        assert q[np.argmin(img)] == 0 and q[np.argmax(img)] == levels - 1


def test_quantise_a_subnormal_span():
    """A span of one subnormal step: halving it underflowed to 0 and gave 0/0 (found by
    the property test above); the span is used whole wherever it is finite."""
    q = quantise(np.array([0.0, 5e-324, 0.0]), 300)
    np.testing.assert_array_equal(q, [0, 299, 0])
    np.testing.assert_array_equal(quantise(np.array([-1.7e308, 0.0, 1.7e308]), 4), [0, 2, 3])  # extreme span


@settings(max_examples=40, deadline=None)
@given(
    values=st.lists(st.integers(0, 65535), min_size=2, max_size=60),
    levels=st.integers(2, 65536),
)
def test_quantise_integer_matches_exact_rule(values, levels):
    img = np.array(values, dtype=np.uint16)
    lo, hi = int(img.min()), int(img.max())
    q = quantise(img, levels)
    if hi == lo:
        expected = [0] * len(values)
    else:
        expected = [min((v - lo) * levels // (hi - lo), levels - 1) for v in values]
    np.testing.assert_array_equal(q, expected)


def test_window_grid_counts_the_sites_whose_window_fits():
    assert window_grid((64, 40), 11) == (54, 30)  # centres 5..58 and 5..34
    assert window_grid((11, 11), 11) == (1, 1)
    assert window_grid((9, 64), 11) == (0, 54)  # no window fits a side shorter than the window
