"""Fuzzed inputs (slow lane): readers, config files and options, with Hypothesis.

The contract checked: every case ends in a result or in one of the documented errors (a
:class:`~clsolid.errors.ClsolidError`, and from the command line its exit status), never in
another exception, never in a hang, and a failed command leaves no output file behind.
Examples are derandomised and no database is kept, so a run is the same on every machine.
"""

from __future__ import annotations

import contextlib
import os
import struct
import tempfile
import warnings
import zlib
from pathlib import Path

import numpy as np
import pytest
import tifffile
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as nps
from PIL import Image

from clsolid.errors import ClsolidError, ExemplarWarning
from clsolid.exemplar import load_exemplar, load_exemplars
from clsolid.report import load_volume as load_report_volume
from clsolid.volumeio import image_pixel_size, load_volume

pytestmark = pytest.mark.slow

#: Derandomised, no example database: the same examples on every run and every machine.
FUZZ = dict(derandomize=True, database=None, deadline=None, print_blob=True,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much])


@contextlib.contextmanager
def _in_tmpdir():
    """A fresh current folder for one example (Hypothesis runs many in one test call)."""
    old = os.getcwd()
    with tempfile.TemporaryDirectory(prefix="clsolid-fuzz-") as tmp:
        os.chdir(tmp)
        try:
            yield Path(tmp)
        finally:
            os.chdir(old)


def _outcome(call, *args, **kwargs):
    """The result of ``call``, or the documented error it raised (any other exception propagates)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExemplarWarning)  # a constant exemplar: documented, not a failure
        warnings.simplefilter("ignore", Image.DecompressionBombWarning)  # Pillow's note on a large PNG
        try:
            return call(*args, **kwargs)
        except ClsolidError as exc:
            assert str(exc), f"{type(exc).__name__} without a message"
            return exc


# --------------------------------------------------------------------------- readers

_NUMERIC = (nps.boolean_dtypes() | nps.integer_dtypes(endianness="?") | nps.unsigned_integer_dtypes(endianness="?")
            | nps.floating_dtypes(endianness="?") | nps.complex_number_dtypes(endianness="?"))
_ODD = (nps.datetime64_dtypes() | nps.timedelta64_dtypes() | nps.byte_string_dtypes(max_len=3)
        | nps.unicode_string_dtypes(max_len=3))
_SHAPES = st.one_of(nps.array_shapes(min_dims=2, max_dims=3, min_side=1, max_side=6),
                    nps.array_shapes(min_dims=2, max_dims=3, min_side=1, max_side=6),
                    nps.array_shapes(min_dims=0, max_dims=4, min_side=0, max_side=4))
#: Numbers (NaN and infinities among the floats) in any byte order, mostly; dates and strings too.
_ARRAYS = nps.arrays(st.one_of(_NUMERIC, _NUMERIC, _NUMERIC, _ODD), _SHAPES)


def _write(path: Path, kind: str, array: np.ndarray) -> bool:
    """Write *array* as a *kind* file; False where that writer refuses it (not a reader's case)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if kind == "npy":
                np.save(path, array)
            elif kind == "tif":
                tifffile.imwrite(path, array)
            elif kind == "imagej":
                tifffile.imwrite(path, array, imagej=True)
            elif kind == "ome":
                tifffile.imwrite(path, array, ome=True)
            else:
                Image.fromarray(array).save(path)
    except Exception:  # noqa: BLE001 - the writers' own refusals are not under test
        if path.exists():
            path.unlink()
        return False
    return True


_SUFFIX = {"npy": ".npy", "tif": ".tif", "imagej": ".TIFF", "ome": ".ome.tif", "png": ".png"}


def _check_readers(path: Path) -> None:
    """Every reader of *path* gives a result that keeps its promises, or an InputError."""
    image = _outcome(load_exemplar, str(path))
    event(f"exemplar: {type(image).__name__}")
    if isinstance(image, np.ndarray):
        assert image.ndim == 2 and image.size > 0 and image.dtype.kind in "iuf"
        assert image.dtype.isnative and image.flags.c_contiguous
        assert np.isfinite(image).all()
    per_view = _outcome(load_exemplars, {"front": path, "top": str(path)})
    assert isinstance(per_view, dict) == isinstance(image, np.ndarray)
    got = _outcome(load_volume, path)
    if not isinstance(got, Exception):
        data, info = got
        assert isinstance(data, np.ndarray) and set(info) >= {"voxel_size", "unit", "metadata"}
    volume = _outcome(load_report_volume, path)
    if isinstance(volume, np.ndarray):
        assert volume.ndim == 3
    size = image_pixel_size(path)  # None where unreadable, never an exception
    assert size is None or (len(size) == 2 and len(size[0]) == 2)


@settings(max_examples=150, **FUZZ)
@given(array=_ARRAYS, kind=st.sampled_from(sorted(_SUFFIX)))
def test_readers_take_any_array_or_refuse_it(array, kind):
    with _in_tmpdir() as tmp:
        path = tmp / f"image{_SUFFIX[kind]}"
        if not _write(path, kind, array):  # what that writer refuses, .npy holds
            path = tmp / "image.npy"
            np.save(path, array)
        _check_readers(path)


_GOOD = st.sampled_from([np.uint8, np.uint16, np.float32, np.int16]).flatmap(
    lambda dt: nps.arrays(dt, st.sampled_from([(4, 5), (1, 6, 7), (3, 4, 4), (5, 6, 1)]),
                          elements=st.integers(0, 200).map(float)))


@st.composite
def _damage(draw, data: bytes) -> bytes:
    """*data* truncated, or with bytes flipped in its header or anywhere, or cut and spliced."""
    n = len(data)
    how = draw(st.sampled_from(["truncate", "header", "anywhere", "splice"]))
    if how == "truncate":
        return data[:draw(st.integers(0, max(n - 1, 0)))]
    buf = bytearray(data)
    if how == "splice":
        a = draw(st.integers(0, n))
        b = draw(st.integers(a, n))
        return bytes(buf[:a] + draw(st.binary(max_size=16)) + buf[b:])
    hi = min(n, 160) if how == "header" else n
    for _ in range(draw(st.integers(1, 6))):
        at = draw(st.integers(0, hi - 1))
        buf[at] = draw(st.sampled_from([0x00, 0xFF, 0x7F, 0x80, buf[at] ^ 0xFF, buf[at] ^ 0x01]))
    return bytes(buf)


@settings(max_examples=600, **FUZZ)
@given(array=_GOOD, kind=st.sampled_from(sorted(_SUFFIX)), data=st.data())
def test_readers_refuse_damaged_files(array, kind, data):
    with _in_tmpdir() as tmp:
        path = tmp / f"image{_SUFFIX[kind]}"
        if kind == "png":
            array = array.astype(np.uint8)
        if not _write(path, kind, array):
            return
        path.write_bytes(data.draw(_damage(path.read_bytes()), label="damaged"))
        _check_readers(path)


_TEXT = st.text(st.characters(codec="ascii", exclude_characters="\x00"), max_size=12)
_NUMBER = st.one_of(st.integers(-3, 2**40), st.floats(allow_nan=True, allow_infinity=True))
_VALUE_TEXT = st.one_of(_TEXT, _NUMBER.map(str), st.sampled_from(["nan", "-inf", "0", "-1", "1e400", "um", "µm", ""]))


@st.composite
def _description(draw) -> str:
    """An ImageDescription: ImageJ's ``key=value`` lines or OME-XML, with odd or missing values."""
    if draw(st.booleans()):
        keys = st.sampled_from(["ImageJ", "images", "slices", "frames", "channels", "spacing", "unit", "axes",
                                "hyperstack", "loop", "min", "max", "finterval", "Properties"])
        pairs = draw(st.lists(st.tuples(keys, _VALUE_TEXT), max_size=6))
        return "\n".join(["ImageJ=1.11a"] + [f"{k}={v}" for k, v in pairs]) + "\n"
    attrs = draw(st.dictionaries(
        st.sampled_from(["PhysicalSizeX", "PhysicalSizeY", "PhysicalSizeZ", "PhysicalSizeXUnit", "PhysicalSizeYUnit",
                         "PhysicalSizeZUnit", "SizeX", "SizeY", "SizeZ", "SizeC", "SizeT", "DimensionOrder", "Type"]),
        _VALUE_TEXT.map(lambda v: v.replace('"', "").replace("<", "").replace("&", "")), max_size=8))
    body = " ".join(f'{k}="{v}"' for k, v in attrs.items())
    name = draw(st.sampled_from(["clsolid ZYX volume", "x"]))
    described = draw(st.sampled_from(["", "<Description>{\"seed\": 1}</Description>", "<Description>[</Description>"]))
    return ('<?xml version="1.0" encoding="UTF-8"?><OME xmlns="http://www.openmicroscopy.org/Schemas/OME/2016-06">'
            f'<Image ID="Image:0" Name="{name}">{described}<Pixels ID="Pixels:0" {body}>'
            '<Channel ID="Channel:0:0" SamplesPerPixel="1"/><TiffData/></Pixels></Image></OME>')


_EXTRA_TAGS = st.lists(st.tuples(
    st.sampled_from([282, 283, 296, 305, 339, 340, 341, 50838, 50839, 65000]),  # resolution, unit, ImageJ's
    st.sampled_from(["B", "H", "I", "d", "2I", "s"]), st.integers(0, 4)), max_size=3)


@settings(max_examples=200, **FUZZ)
@given(array=_GOOD, description=_description(), tags=_EXTRA_TAGS,
       resolution=st.none() | st.tuples(_NUMBER, _NUMBER), unit=st.none() | st.integers(0, 7),
       ijmeta=st.none() | st.dictionaries(st.sampled_from(["spacing", "unit", "Properties", "axes"]),
                                          st.one_of(_VALUE_TEXT, _NUMBER, st.dictionaries(
                                              st.sampled_from(["clsolid.axes", "clsolid.metadata", "x"]),
                                              _VALUE_TEXT, max_size=2)), max_size=3))
def test_readers_take_odd_tags(array, description, tags, resolution, unit, ijmeta):
    with _in_tmpdir() as tmp:
        path = tmp / "odd.tif"
        extratags = [(code, dtype, count or 1, "x" * (count or 1) if dtype == "s" else
                      ((1,) * (2 * (count or 1)) if dtype == "2I" else (0,) * (count or 1)), True)
                     for code, dtype, count in tags]
        kwargs = {"extratags": extratags, "resolution": resolution, "resolutionunit": unit}
        if ijmeta is None:
            kwargs.update(description=description, metadata=None)
        else:
            kwargs.update(imagej=True, metadata=ijmeta)
            array = array.astype(np.float32)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                tifffile.imwrite(path, array, **kwargs)
        except Exception:  # noqa: BLE001 - what tifffile will not write is not a reader's case
            event("tifffile refused to write it")
            return
        _check_readers(path)


def _with_ihdr(png: bytes, fields: bytes) -> bytes:
    """*png* with the 13 bytes of its IHDR chunk replaced, and that chunk's CRC made right again
    (a damaged header that still passes the reader's checksum)."""
    return png[:16] + fields + struct.pack(">I", zlib.crc32(b"IHDR" + fields)) + png[33:]


@settings(max_examples=150, **FUZZ)
@given(array=_GOOD, width=st.integers(0, 2**31 - 1), height=st.integers(0, 2**31 - 1),
       depth=st.sampled_from([0, 1, 2, 4, 8, 16, 32]), colour=st.sampled_from([0, 1, 2, 3, 4, 6, 7]),
       interlace=st.integers(0, 2), small=st.booleans())
def test_png_reader_takes_odd_headers(array, width, height, depth, colour, interlace, small):
    with _in_tmpdir() as tmp:
        path = tmp / "odd.png"
        Image.fromarray(array.astype(np.uint8).reshape(array.shape[0], -1)).save(path)
        if small:  # near the real size: the data may still decode
            width, height = width % 9, height % 9
        fields = struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, interlace)
        path.write_bytes(_with_ihdr(path.read_bytes(), fields))
        _check_readers(path)
