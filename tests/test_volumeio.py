"""Tests of clsolid.volumeio: volume save/load round trips and the preview image."""

from __future__ import annotations

import shutil
import struct
import tracemalloc
import warnings
import zlib

import numpy as np
import pytest
import tifffile
from PIL import Image

from clsolid.core.hostmemory import available_bytes
from clsolid.errors import InputError, LargeTiffWarning
from clsolid import volumeio
from clsolid.volumeio import check_calibration, image_pixel_size, load_volume, save_volume


@pytest.fixture
def labels() -> np.ndarray:
    return np.random.default_rng(0).integers(0, 32, size=(6, 7, 8)).astype(np.int32)


# --------------------------------------------------------------------------- TIFF


def test_tif_round_trip_with_voxel_size(tmp_path, labels):
    path = save_volume(tmp_path / "sub" / "dir" / "vol.tif", labels, voxel_size=(2.0, 0.5, 0.5))
    assert path == tmp_path / "sub" / "dir" / "vol.tif" and path.is_file()
    data, info = load_volume(path)
    assert data.shape == (6, 7, 8) and data.dtype == np.uint8
    np.testing.assert_array_equal(data, labels)
    assert info["voxel_size"] == pytest.approx((2.0, 0.5, 0.5))
    assert info["unit"] == "um"


def test_tif_anisotropic_xy_and_unit(tmp_path, labels):
    path = save_volume(tmp_path / "vol.TIFF", labels, voxel_size=(3.0, 0.25, 0.125), unit="mm")
    _, info = load_volume(path)
    assert info["voxel_size"] == pytest.approx((3.0, 0.25, 0.125))
    assert info["unit"] == "mm"


def test_tif_scalar_voxel_size_is_isotropic(tmp_path, labels):
    _, info = load_volume(save_volume(tmp_path / "iso.tif", labels, voxel_size=0.75))
    assert info["voxel_size"] == pytest.approx((0.75, 0.75, 0.75))


def test_tif_without_voxel_size(tmp_path, labels):
    _, info = load_volume(save_volume(tmp_path / "plain.tif", labels))
    assert info["voxel_size"] is None and info["unit"] is None and info["metadata"] is None


def test_tif_is_imagej_zyx_hyperstack(tmp_path, labels):
    path = save_volume(tmp_path / "ij.tif", labels, voxel_size=(2.0, 0.5, 0.5))
    with tifffile.TiffFile(path) as tif:
        assert tif.is_imagej
        assert tif.series[0].axes == "ZYX"
        assert tif.imagej_metadata["slices"] == 6
        assert tif.imagej_metadata["spacing"] == pytest.approx(2.0)


def test_tif_metadata_round_trip(tmp_path, labels):
    meta = {"seed": 7, "levels": 32, "exemplar": "brick", "weights": [0.5, 0.25]}
    _, info = load_volume(save_volume(tmp_path / "m.tif", labels, metadata=meta))
    assert info["metadata"] == meta


def test_tif_single_slice_stays_3d(tmp_path, labels):
    data, _ = load_volume(save_volume(tmp_path / "one.tif", labels[:1]))
    assert data.shape == (1, 7, 8)
    np.testing.assert_array_equal(data, labels[:1])


@pytest.mark.parametrize(
    "dtype, values, expected",
    [
        (np.int32, (0, 255), np.uint8),
        (np.int64, (0, 256), np.uint16),
        (np.uint32, (3, 65535), np.uint16),
        (np.int8, (0, 100), np.uint8),
        (np.uint8, (0, 255), np.uint8),
        (np.uint16, (0, 10), np.uint16),  # kept: already an ImageJ type
        (np.bool_, (False, True), np.uint8),
        (np.float64, (-1.5, 2.25), np.float32),
        (np.float16, (-1.5, 2.25), np.float32),
        (np.float32, (-1.5, 2.25), np.float32),
    ],
)
def test_tif_dtype_conversion(tmp_path, dtype, values, expected):
    vol = np.zeros((2, 3, 4), dtype=dtype)
    vol[0, 0, 0], vol[1, 2, 3] = values
    data, _ = load_volume(save_volume(tmp_path / "d.tif", vol))
    assert data.dtype == expected
    np.testing.assert_array_equal(data, vol.astype(expected))


@pytest.mark.parametrize("values", [(-1, 3), (0, 65536)])
def test_tif_labels_out_of_range(tmp_path, values):
    vol = np.zeros((2, 2, 2), dtype=np.int64)
    vol[0, 0, 0], vol[1, 1, 1] = values
    with pytest.raises(InputError, match="volume") as info:
        save_volume(tmp_path / "bad.tif", vol)
    assert str(values[0]) in str(info.value) and ".npy" in str(info.value)


def test_small_tif_writes_no_warning(tmp_path, labels):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        save_volume(tmp_path / "v.tif", labels, voxel_size=0.5)


def test_tifffile_large_file_note_becomes_ours(tmp_path, labels, monkeypatch):
    """tifffile's "truncating ImageJ file" (its large-file form) reaches the user as a
    LargeTiffWarning saying who can read the file; its other warnings pass unchanged."""
    real = tifffile.imwrite

    def noisy(*args, **kwargs):
        warnings.warn("<TiffWriter> truncating ImageJ file", UserWarning)
        warnings.warn("something else", RuntimeWarning)
        return real(*args, **kwargs)

    monkeypatch.setattr(tifffile, "imwrite", noisy)
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        save_volume(tmp_path / "v.tif", labels)
    assert [w.category for w in record] == [LargeTiffWarning, RuntimeWarning]
    assert "first plane" in str(record[0].message) and "truncating" not in str(record[0].message)
    assert str(record[1].message) == "something else"


@pytest.mark.parametrize("name, dtype", [("f.tif", np.float64), ("i.tif", np.int32), ("i.npy", np.int32),
                                         ("u.npy", np.uint8), ("f.ome.tif", np.float64)])
def test_volumes_are_written_a_plane_at_a_time(tmp_path, name, dtype):
    """No whole copy of the volume (converted or not) is made: a memory-mapped result larger
    than memory can be saved (the traced peak is below half a byte a voxel, the smallest
    whole copy would be one or four; it was four for a float64 TIFF)."""
    vol = np.arange(64**3, dtype=dtype).reshape(64, 64, 64) % 200
    tracemalloc.start()
    try:
        save_volume(tmp_path / name, vol, voxel_size=0.5)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < vol.size // 2
    np.testing.assert_array_equal(load_volume(tmp_path / name)[0], vol)


def test_ome_tif_round_trips_with_voxel_size_and_metadata(tmp_path, labels):
    path = save_volume(tmp_path / "v.OME.tiff", labels, voxel_size=(2.0, 0.5, 0.25), metadata={"seed": 3})
    data, info = load_volume(path)
    np.testing.assert_array_equal(data, labels)
    assert info == {"voxel_size": (2.0, 0.5, 0.25), "unit": "\u00b5m", "metadata": {"seed": 3}}  # OME's symbol
    assert image_pixel_size(path) == ((0.5, 0.25), "\u00b5m")  # an exemplar's pixel size, as any OME file's
    with tifffile.TiffFile(path) as tif:
        assert tif.is_ome and not tif.is_imagej and not tif.is_bigtiff and len(tif.pages) == labels.shape[0]
    angstrom = save_volume(tmp_path / "a.ome.tif", labels, voxel_size=1.0, unit="angstrom")
    assert load_volume(angstrom)[1]["unit"] == "\u00c5"


def test_ome_tif_one_plane_stays_3d_and_other_ome_images_2d(tmp_path, labels):
    data, info = load_volume(save_volume(tmp_path / "one.ome.tif", labels[:1]))
    assert data.shape == (1,) + labels.shape[1:] and info["voxel_size"] is None
    tifffile.imwrite(tmp_path / "micrograph.ome.tif", labels[0], ome=True)  # another program's 2D image
    assert load_volume(tmp_path / "micrograph.ome.tif")[0].shape == labels.shape[1:]


@pytest.mark.parametrize("shape", [(5, 6, 3), (2, 3, 4), (1, 6, 4)])
def test_ome_tif_with_three_or_four_columns_is_a_volume_not_colour(tmp_path, shape):
    # tifffile took the last axis for RGB(A) samples: "axes do not match stored shape", a file half written
    volume = np.arange(np.prod(shape), dtype=np.uint8).reshape(shape)
    data, _ = load_volume(save_volume(tmp_path / "v.ome.tif", volume))
    np.testing.assert_array_equal(data, volume)


def test_ome_tif_refuses_a_unit_ome_does_not_know_before_writing(tmp_path, labels):
    with pytest.raises(InputError, match="OME-XML's length units"):
        save_volume(tmp_path / "v.ome.tif", labels, voxel_size=1.0, unit="furlong")
    assert not (tmp_path / "v.ome.tif").exists()
    with pytest.raises(InputError, match="OME-XML's length units"):
        check_calibration(1.0, "furlong", tmp_path / "v.ome.tif")
    check_calibration(1.0, "furlong", tmp_path / "v.tif")  # ImageJ takes any unit
    check_calibration(None, "furlong", tmp_path / "v.ome.tif")  # no voxel size: no unit written


def test_ome_tif_is_bigtiff_above_4_gib(tmp_path, labels, monkeypatch):
    monkeypatch.setattr(volumeio, "_CLASSIC_TIFF_BYTES", labels.size - 1)  # a small volume stands for a large one
    path = save_volume(tmp_path / "big.ome.tif", labels, voxel_size=0.5)
    with tifffile.TiffFile(path) as tif:
        assert tif.is_bigtiff and tif.is_ome and len(tif.pages) == labels.shape[0]
    np.testing.assert_array_equal(load_volume(path)[0], labels)


def _room(path, need: int) -> bool:
    free_ram = available_bytes()
    return free_ram is not None and shutil.disk_usage(path).free > need * 1.2 and free_ram > need * 2.5


@pytest.mark.slow
@pytest.mark.parametrize("name", ["big.tif", "big.ome.tif"])
def test_tif_above_4_gib_round_trips(tmp_path, name):
    """A volume above a classic TIFF's 4 GiB is written (ImageJ's large-file form, with the
    warning; or an OME BigTIFF) and read back whole, voxel size included."""
    shape = (1040, 2048, 2048)  # 4.06 GiB of uint8
    need = int(np.prod(shape))
    if not _room(tmp_path, need):
        pytest.skip("needs about 10 GiB of free memory and 5 GiB of disk")
    vol = np.zeros(shape, np.uint8)
    vol[0, 0, 0], vol[-1, -1, -1], vol[shape[0] // 2, 7, 9] = 1, 2, 3
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        save_volume(tmp_path / name, vol, voxel_size=(2.0, 0.5, 0.5))
    assert [w.category for w in caught] == ([] if "ome" in name else [LargeTiffWarning])
    del vol
    if "ome" in name:
        with tifffile.TiffFile(tmp_path / name) as tif:
            assert tif.is_bigtiff and len(tif.pages) == shape[0]
    back, meta = load_volume(tmp_path / name)
    assert back.shape == shape
    assert (back[0, 0, 0], back[-1, -1, -1], back[shape[0] // 2, 7, 9]) == (1, 2, 3)
    assert np.count_nonzero(back) == 3
    assert meta["voxel_size"] == pytest.approx((2.0, 0.5, 0.5))


def test_overwrite_is_allowed(tmp_path, labels):
    path = tmp_path / "o.tif"
    save_volume(path, labels)
    save_volume(path, labels + 1)
    np.testing.assert_array_equal(load_volume(path)[0], labels + 1)


# --------------------------------------------------------------------------- NPY / PNG


def test_npy_round_trip_narrows_labels(tmp_path, labels):
    path = save_volume(tmp_path / "v.npy", labels, voxel_size=1.0)
    data, info = load_volume(path)
    assert data.dtype == np.uint8
    np.testing.assert_array_equal(data, labels)
    assert info == {"voxel_size": None, "unit": None, "metadata": None}


@pytest.mark.parametrize(
    "dtype, values, expected",
    [
        (np.int32, (0, 1000), np.uint16),
        (np.int64, (-5, 3), np.int64),  # does not fit: kept as is
        (np.float64, (-1.5, 2.25), np.float64),
        (np.float32, (-1.5, 2.25), np.float32),
        (np.bool_, (False, True), np.uint8),
    ],
)
def test_npy_dtype(tmp_path, dtype, values, expected):
    vol = np.zeros((2, 3, 4), dtype=dtype)
    vol[0, 0, 0], vol[1, 2, 3] = values
    data, _ = load_volume(save_volume(tmp_path / "d.NPY", vol))
    assert data.dtype == expected
    np.testing.assert_array_equal(data, vol.astype(expected))


def test_load_png_slice(tmp_path):
    img = np.arange(200, dtype=np.uint8).reshape(10, 20)
    path = tmp_path / "s.png"
    Image.fromarray(img).save(path)
    data, info = load_volume(path)
    assert data.ndim == 2 and data.dtype == np.uint8
    np.testing.assert_array_equal(data, img)
    assert info["voxel_size"] is None


def test_load_colour_png_is_error(tmp_path):
    rgb = np.zeros((4, 5, 3), dtype=np.uint8)
    rgb[..., 0] = 200
    path = tmp_path / "c.png"
    Image.fromarray(rgb).save(path)
    with pytest.raises(InputError, match="path.*colour"):
        load_volume(path)


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize("name", ["v.png", "v.raw", "v", "v.jpg"])
def test_save_unsupported_extension(tmp_path, labels, name):
    with pytest.raises(InputError, match="path") as info:
        save_volume(tmp_path / name, labels)
    assert ".tif" in str(info.value) and ".npy" in str(info.value)


@pytest.mark.parametrize(
    "volume, needle",
    [
        (np.zeros((3, 4)), "(3, 4)"),
        (np.zeros((2, 3, 4, 5)), "(2, 3, 4, 5)"),
        (np.zeros((0, 3, 4)), "empty"),
        (np.zeros((2, 2, 2), dtype=complex), "complex"),
        ([[[1]]], "list"),
    ],
)
def test_save_bad_volume(tmp_path, volume, needle):
    with pytest.raises(InputError, match="volume") as info:
        save_volume(tmp_path / "v.tif", volume)
    assert needle in str(info.value)


@pytest.mark.parametrize("bad", [0, -1.0, float("nan"), float("inf"), (1.0, 2.0), (1.0, 0.0, 1.0), "1", True])
def test_save_bad_voxel_size(tmp_path, labels, bad):
    with pytest.raises(InputError, match="voxel_size") as info:
        save_volume(tmp_path / "v.tif", labels, voxel_size=bad)
    assert repr(bad) in str(info.value)


@pytest.mark.parametrize("bad", ["", "u\nm", "a=b", 3])
def test_save_bad_unit(tmp_path, labels, bad):
    with pytest.raises(InputError, match="unit"):
        save_volume(tmp_path / "v.tif", labels, voxel_size=1.0, unit=bad)


@pytest.mark.parametrize("bad", [[1, 2], {"a": object()}, {"a": float("nan")}])
def test_save_bad_metadata(tmp_path, labels, bad):
    with pytest.raises(InputError, match="metadata"):
        save_volume(tmp_path / "v.tif", labels, metadata=bad)


def test_nothing_written_on_bad_input(tmp_path, labels):
    with pytest.raises(InputError):
        save_volume(tmp_path / "new" / "v.tif", labels, voxel_size=-1)
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize(
    "make_path, needle",
    [
        (lambda d: d / "missing.tif", "does not exist"),
        (lambda d: d / "v.jpg", ".npy"),
        (lambda d: 5, "int"),
    ],
)
def test_load_bad_path(tmp_path, make_path, needle):
    with pytest.raises(InputError, match="path") as info:
        load_volume(make_path(tmp_path))
    assert needle in str(info.value)


@pytest.mark.parametrize("name", ["bad.tif", "bad.npy", "bad.png"])
def test_load_corrupt_file(tmp_path, name):
    path = tmp_path / name
    path.write_bytes(b"garbage, not image data")
    with pytest.raises(InputError, match="path"):
        load_volume(path)


def test_load_pickled_npy_is_error(tmp_path):
    path = tmp_path / "obj.npy"
    np.save(path, np.array([{"a": 1}], dtype=object), allow_pickle=True)
    with pytest.raises(InputError, match="path"):
        load_volume(path)


def _npy_with_header(path, header: str, data: bytes = bytes(42)):
    """A version 1.0 ``.npy`` file with this header text (padded as numpy pads it) and data."""
    text = header.ljust(117) + "\n"
    path.write_bytes(b"\x93NUMPY\x01\x00" + len(text).to_bytes(2, "little") + text.encode("latin1") + data)
    return path


@pytest.mark.parametrize("header, needle", [
    # a header cut short inside its dict: numpy's parser let tokenize's TokenError through
    ("{'descr': '|u1', 'fortran_order': False, 'shape': (1, 6, 7), \x00", "could not be read"),
    # a damaged shape declaring 931 GiB: numpy tried to allocate it (MemoryError)
    ("{'descr': '|u1', 'fortran_order': False, 'shape': (1000000000000,), }", "truncated"),
])
def test_load_npy_with_damaged_header_is_error(tmp_path, header, needle):
    path = _npy_with_header(tmp_path / "damaged.npy", header)
    with pytest.raises(InputError, match="path") as info:
        load_volume(path)
    assert needle in str(info.value)


def _patched_tiff(path, shape, **fields):
    """A uint8 TIFF of *shape* whose tags named in *fields* are overwritten with these 32-bit values
    (a tag's value field, or ``"<tag>.count"`` its count)."""
    tifffile.imwrite(path, np.zeros(shape, np.uint8))
    data = bytearray(path.read_bytes())
    with tifffile.TiffFile(path) as tif:
        tags = tif.pages.first.tags
        for name, value in fields.items():
            tag, _, part = name.partition(".")
            at = tags[tag].offset + 4 if part == "count" else tags[tag].valueoffset
            data[at:at + 4] = int(value).to_bytes(4, "little")
    path.write_bytes(bytes(data))
    return path


def test_load_damaged_tiffs_is_error(tmp_path):
    (tmp_path / "cut.tif").write_bytes(b"II")  # tifffile's struct.error
    with pytest.raises(InputError, match="could not be read as a TIFF"):
        load_volume(tmp_path / "cut.tif")
    # 2^31 x 2^31 pixels declared in a 70 kB file: tifffile tried to allocate 4 EiB (MemoryError)
    huge = _patched_tiff(tmp_path / "huge.tif", (1, 70000), ImageWidth=2**31, ImageLength=2**31)
    with pytest.raises(InputError, match="larger than the memory"):
        load_volume(huge)


def test_load_png_declaring_a_billion_pixels_is_error(tmp_path):
    path = tmp_path / "bomb.png"
    Image.fromarray(np.zeros((4, 5), np.uint8)).save(path)
    data = path.read_bytes()
    ihdr = struct.pack(">IIBBBBB", 1680603714, 8, 16, 4, 0, 0, 1)  # 13 Gpixels, with a valid checksum
    path.write_bytes(data[:16] + ihdr + struct.pack(">I", zlib.crc32(b"IHDR" + ihdr)) + data[33:])
    with pytest.raises(InputError, match="more pixels than Pillow opens"):  # was Pillow's DecompressionBombError
        load_volume(path)


def test_image_pixel_size_of_a_damaged_tiff_is_none(tmp_path):
    # a ResolutionUnit of two values reads as a tuple, which int() refused (TypeError)
    path = _patched_tiff(tmp_path / "unit.tif", (4, 5), **{"ResolutionUnit.count": 2})
    assert image_pixel_size(path) is None


def _image(path, **kwargs):
    tifffile.imwrite(path, np.arange(48, dtype=np.uint8).reshape(6, 8), **kwargs)
    return path


def test_image_pixel_size_from_imagej_calibration(tmp_path):
    path = _image(tmp_path / "ij.tif", imagej=True, resolution=(2.0, 4.0), metadata={"unit": "nm"})
    assert image_pixel_size(path) == ((pytest.approx(0.25), pytest.approx(0.5)), "nm")  # (y, x)


def test_image_pixel_size_from_ome_header(tmp_path):
    path = _image(tmp_path / "o.ome.tif", ome=True, metadata={
        "axes": "YX", "PhysicalSizeX": 0.1, "PhysicalSizeXUnit": "nm", "PhysicalSizeY": 0.2, "PhysicalSizeYUnit": "nm"})
    assert image_pixel_size(path) == ((pytest.approx(0.2), pytest.approx(0.1)), "nm")


def test_image_pixel_size_from_centimetres_not_inches(tmp_path):
    cm = _image(tmp_path / "cm.tif", resolution=(5000.0, 2500.0), resolutionunit="CENTIMETER")
    assert image_pixel_size(cm) == ((pytest.approx(4.0), pytest.approx(2.0)), "um")  # 10^4 um / pixels per cm
    inch = _image(tmp_path / "in.tif", resolution=(72.0, 72.0), resolutionunit="INCH")  # a display resolution
    assert image_pixel_size(inch) is None


def test_image_pixel_size_none_without_calibration(tmp_path):
    assert image_pixel_size(_image(tmp_path / "plain.tif")) is None
    assert image_pixel_size(_image(tmp_path / "ij.tif", imagej=True)) is None
    Image.fromarray(np.zeros((4, 4), np.uint8)).save(tmp_path / "a.png")
    assert image_pixel_size(tmp_path / "a.png") is None
    (tmp_path / "bad.tif").write_bytes(b"not a tiff")
    assert image_pixel_size(tmp_path / "bad.tif") is None
    assert image_pixel_size(tmp_path / "missing.tif") is None


def test_non_ascii_unit_is_written_as_imagej_escape(tmp_path, labels):
    # the ImageJ header is ASCII: the micro sign (an OME file's default unit) would not encode
    out = save_volume(tmp_path / "v.tif", labels, voxel_size=0.5, unit="\u00b5m")
    _, info = load_volume(out)
    assert info["unit"] == "\\u00B5m" and info["voxel_size"] == pytest.approx((0.5, 0.5, 0.5))
    with tifffile.TiffFile(out) as tif:
        assert "unit=\\u00B5m" in tif.pages[0].description


def test_ome_default_unit_is_micrometres(tmp_path):
    path = _image(tmp_path / "o.ome.tif", ome=True, metadata={"axes": "YX", "PhysicalSizeX": 0.5})
    assert image_pixel_size(path) == ((pytest.approx(0.5), pytest.approx(0.5)), "\u00b5m")


@pytest.mark.parametrize("name", ["v.tif", "v.ome.tif", "v.npy"])
def test_a_write_that_fills_the_disk_leaves_what_was_there(tmp_path, full_disk, name):
    """Out of space halfway through the planes: the error is the system's (ENOSPC), the file
    that was at the path is whole and unchanged (or, where none was, there is none), and no
    partial file is left beside it."""
    import errno

    path = tmp_path / name
    old = np.zeros((4, 16, 16), np.float32)
    save_volume(path, old, voxel_size=0.5)
    before = path.read_bytes()
    new = np.random.default_rng(0).random((8, 32, 32)).astype(np.float32)
    full_disk(tmp_path, new.nbytes // 2)
    with pytest.raises(OSError) as caught:
        save_volume(path, new, voxel_size=0.5)
    assert caught.value.errno == errno.ENOSPC
    assert sorted(tmp_path.iterdir()) == [path] and path.read_bytes() == before
    path.unlink()
    full_disk(tmp_path, new.nbytes // 2)  # room again
    with pytest.raises(OSError):
        save_volume(path, new, voxel_size=0.5)
    assert not list(tmp_path.iterdir())  # no file was there: none is


@pytest.mark.parametrize("name", ["v.tif", "v.ome.tif", "v.npy"])
@pytest.mark.parametrize("shape", [(3, 5, 6, 3), (1, 4, 5, 3)])
def test_rgb_volumes_round_trip_with_their_calibration(tmp_path, name, shape):
    vol = np.random.default_rng(0).integers(0, 256, shape).astype(np.uint8)
    path = save_volume(tmp_path / name, vol, voxel_size=(2.0, 0.5, 0.5), metadata={"k": 1})
    back, info = load_volume(path)
    assert back.shape == shape and back.dtype == np.uint8
    np.testing.assert_array_equal(back, vol)
    if name != "v.npy":
        import tifffile

        with tifffile.TiffFile(path) as tif:
            assert tif.pages[0].photometric == tifffile.PHOTOMETRIC.RGB and tif.series[0].axes.endswith("YXS")
        assert info["voxel_size"] == pytest.approx((2.0, 0.5, 0.5)) and info["metadata"] == {"k": 1}


def test_a_16_bit_rgb_volume_goes_to_ome_not_imagej(tmp_path):
    vol = np.random.default_rng(1).integers(0, 65536, (2, 3, 4, 3)).astype(np.uint16)
    np.testing.assert_array_equal(load_volume(save_volume(tmp_path / "v.ome.tif", vol))[0], vol)
    with pytest.raises(InputError, match="8-bit samples only.*ome.tif"):
        save_volume(tmp_path / "v.tif", vol)
    assert not (tmp_path / "v.tif").exists()
