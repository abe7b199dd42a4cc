"""Fuzzed inputs (slow lane): readers, config files and options, with Hypothesis.

The contract checked: every case ends in a result or in one of the documented errors (a
:class:`~clsolid.errors.ClsolidError`, and from the command line its exit status), never in
another exception, never in a hang, and a failed command leaves no output file behind.
Examples are derandomised and no database is kept, so a run is the same on every machine.
"""

from __future__ import annotations

import contextlib
import functools
import io
import json
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

import clsolid
from clsolid.cli import main
from clsolid.cli.config import read_config, sidecar_settings
from clsolid.cli.synth import SOURCES
from clsolid.core.options import Choice, Flag, Int, Real, Reals, Views, declared, names
from clsolid.errors import EXIT_CODES, ClsolidError, ExemplarWarning
from clsolid.exemplar import load_exemplar, load_exemplars
from clsolid.ml.params import MLParams
from clsolid.report import load_volume as load_report_volume
from clsolid.search.params import SearchParams
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
    if isinstance(image, np.ndarray):  # grey, or RGB: a file whose last axis holds 3 samples
        assert (image.ndim == 2 or image.shape[-1:] == (3,) and image.ndim == 3) and image.size > 0
        assert image.dtype.kind in "iuf"
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
        assert volume.ndim == 3 or (volume.ndim == 4 and volume.shape[-1] == 3)
    size = image_pixel_size(path)  # None where unreadable, never an exception
    assert size is None or (len(size) == 2 and len(size[0]) == 2)


@settings(max_examples=300, **FUZZ)
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


@settings(max_examples=1000, **FUZZ)
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


@settings(max_examples=300, **FUZZ)
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


@settings(max_examples=300, **FUZZ)
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


# --------------------------------------------------------------------------- options

#: Options whose values set how long a run takes: drawn small, so that no valid value means hours.
_COSTLY = {"sweeps", "max_sweeps", "iterations", "inner", "polish_sweeps", "exact_passes", "candidates",
           "prune_sample", "prune_projected", "prune_projected_k", "prune_projected_probe", "prune_projected_sweeps",
           "seed_components", "insert_slices", "insert_piece", "levels", "region", "coherence_levels", "prune_similar",
           "scales", "neighborhood"}
_SPECS = {f.name: spec for cls in (MLParams, SearchParams) for f, spec in declared(cls) if f.name != "method"}
_ODD_VALUES = st.one_of(
    st.none(), st.booleans(), st.integers(-3, 12), st.sampled_from([2**40, -(2**63), 2**64]),
    st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([5e-324, 1e308, -0.0]),
    _TEXT, st.sampled_from(["3", "0.5", "auto", "nan", "1/8", "front+top", "all"]),
    st.lists(st.floats(-2, 1e9, allow_nan=False), max_size=4), st.tuples(st.integers(0, 3)),
    st.dictionaries(_TEXT, st.integers(), max_size=2),
    st.sampled_from([np.int64(3), np.float32(0.5), np.bool_(True), np.uint8(1), np.array(1), np.array([1.0, 2.0]),
                     np.float64("nan"), 1 + 2j, b"3", Ellipsis, range(3)]))


@st.composite
def _valid(draw, name: str):
    """A value *name*'s declaration takes (small where it sets the run's length)."""
    check = _SPECS[name].check
    if name == "neighborhood":
        return draw(st.sampled_from([3, 5]))
    if name == "scales":
        return draw(st.sampled_from([1, 2]))
    if name == "levels":
        return draw(st.sampled_from([2, 3, 8, 256, 65536, None]))
    if isinstance(check, Choice):
        return draw(st.sampled_from(check.values))
    if isinstance(check, Int):
        lo = check.lo if check.lo is not None else -3
        hi = lo + 6 if check.hi is None or name in _COSTLY else check.hi
        value = draw(st.integers(lo, min(hi, check.hi) if check.hi is not None else hi))
        return value | 1 if check.odd else value
    if isinstance(check, Real):
        lo = check.lo if check.lo is not None else -10.0
        hi = check.hi if check.hi is not None else lo + 1e6
        return draw(st.floats(lo, hi, allow_nan=False))
    if isinstance(check, Reals):
        return draw(st.one_of(st.floats(1e-3, 1e3), st.lists(st.floats(1e-3, 1e3), min_size=1, max_size=3)))
    if isinstance(check, Flag):
        return draw(st.booleans())
    if isinstance(check, Views):
        return draw(st.sampled_from([2, 3, "front+top", "right+top", "front+right+top"]))
    return draw(st.sampled_from(["h2-product", "h1-mean", "TIP2014", "h2-min"]))  # the heuristic's own check


def _option_value(name: str):
    """Mostly a valid value of *name*, else a value of any type (ints small where they cost time)."""
    odd = _ODD_VALUES if name not in _COSTLY else _ODD_VALUES.filter(lambda v: not isinstance(v, int) or v < 12)
    return st.one_of(_valid(name), _valid(name), _valid(name), odd) if name in _SPECS else odd


_OPTIONS = st.lists(st.sampled_from(sorted(_SPECS) + ["relaxaton", "seed", "tile"]), max_size=4, unique=True).flatmap(
    lambda names: st.fixed_dictionaries({n: _option_value(n) for n in names}))
_EXEMPLARS = st.sampled_from([
    np.random.default_rng(0).integers(0, 3, (12, 12)).astype(np.uint8),  # three phases
    (np.random.default_rng(1).random((10, 14)) * 100).astype(np.float32),  # grey
    np.random.default_rng(2).integers(0, 2, (9, 9)).astype(np.uint16) * 1000,  # two phases, 16-bit
    np.zeros((8, 8), np.uint8),  # constant
])
_SHAPES3 = st.one_of(*[st.tuples(*[st.integers(4, 8)] * 3)] * 4,
                     st.sampled_from([(0, 4, 4), (4, 4), (-4, 4, 4), (4.0, 5, 6), "444", (True, 4, 4),
                                      (2**40, 2**40, 2**40), (2**21, 2**21, 2**21), (1, 1, 1)]))
_DEVICES = ["reference", "0:0"]


def _seen(info) -> None:
    """A progress hook that reads what it is given."""
    assert info.sweep >= 0 and info.volume().ndim == 3


@settings(max_examples=600, **FUZZ)
@given(exemplar=_EXEMPLARS, per_view=st.booleans(), shape=_SHAPES3, device=st.sampled_from(_DEVICES),
       method=st.sampled_from(["ml"] * 6 + ["wl", "kopf", "chen-wang"] * 2 + ["ML", None]),
       rng=st.one_of(*[st.integers(0, 2**32)] * 4, st.sampled_from([-1, 2**70, 1.5, "1", None, True])),
       extra=st.fixed_dictionaries({}, optional={
           "output": st.sampled_from(["values", "labels", "indices", None]), "full_output": st.booleans(),
           "site_map": st.one_of(st.booleans(), st.just(1)), "progress": st.sampled_from([None, print, 1]),
           "backend": st.sampled_from([None, {}, {"tile": 4}, {"tile": 0}, {"tiles": 4}, {"local_size": 3},
                                       {"voxels_per_item": 3}, {"max_batch": 1}, [], "x"])}),
       options=_OPTIONS)
def test_synthesize_takes_any_options_or_refuses_them(exemplar, per_view, shape, device, method, rng, extra,
                                                      options):
    source = {"front": exemplar, "top": exemplar.T.copy()} if per_view else exemplar
    if extra.get("progress") is print:
        extra["progress"] = _seen
    options = {"scales": 1, "neighborhood": 3, **options}
    result = _outcome(clsolid.synthesize, source, shape, method=method, device=device, rng=rng, **extra, **options)
    event(f"synthesize: {type(result).__name__}")
    if not isinstance(result, Exception):
        volume = result.volume if extra.get("full_output") else result
        assert volume.shape == tuple(shape) and volume.size > 0
        assert np.isfinite(volume).all()


@st.composite
def _method_and_options(draw):
    """A method and valid values of some of its own options (which may still conflict)."""
    method = draw(st.sampled_from(["ml", "ml", "wl", "kopf", "chen-wang"]))
    own = sorted(n for n in names(MLParams if method == "ml" else SearchParams) if n != "method")
    chosen = draw(st.lists(st.sampled_from(own), min_size=1, max_size=5, unique=True))
    return method, {n: draw(_valid(n)) for n in chosen}


@settings(max_examples=450, **FUZZ)
@given(exemplar=_EXEMPLARS, per_view=st.booleans(), shape=st.tuples(*[st.integers(4, 8)] * 3),
       device=st.sampled_from(_DEVICES), rng=st.integers(0, 2**32), full_output=st.booleans(),
       method_options=_method_and_options())
def test_synthesize_takes_valid_option_mixes(exemplar, per_view, shape, device, rng, full_output, method_options):
    method, options = method_options
    source = {"front": exemplar, "right": exemplar.T.copy()} if per_view else exemplar
    options = {"scales": 1, "neighborhood": 3, **options}
    result = _outcome(clsolid.synthesize, source, shape, method=method, device=device, rng=rng,
                      full_output=full_output, progress=_seen, **options)
    event(f"synthesize: {type(result).__name__}")
    if not isinstance(result, Exception):
        volume = result.volume if full_output else result
        assert volume.shape == shape and np.isfinite(volume).all()


# --------------------------------------------------------------------------- command line and config files

#: The documented exit statuses of a refusal (1, a bug, is not one of them).
_REFUSALS = set(EXIT_CODES) - {0, 1}
#: Flags left out: they start or reach processes (Dask), or print the help and exit.
_NOT_FUZZED = {"scheduler", "workers", "client", "help", "help_all"}
_SMALL_RUN = ["--scales", "1", "--neighborhood", "3", "-q"]


def _run_cli(argv: list[str], *outputs: str) -> int:
    """``clsolid`` with *argv*: a documented status, and no output file after a failure."""
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        try:
            code = _outcome(main, argv)
        except SystemExit as exc:  # argparse's usage errors
            code = exc.code
    if isinstance(code, ClsolidError):  # --debug raises it
        code = code.exit_code
    assert code == 0 or code in _REFUSALS, f"exit status {code}: {err.getvalue()}"
    assert "Traceback" not in err.getvalue()
    for path in outputs:
        assert Path(path).exists() == (code == 0), f"{path} after exit status {code}: {err.getvalue()}"
    event(f"exit status {code}")
    return code


def _exemplar_file() -> str:
    np.save("ex.npy", np.random.default_rng(0).integers(0, 3, (12, 12)).astype(np.uint8))
    return "ex.npy"


_WORDS = st.one_of(st.sampled_from(["1", "0", "3", "-1", "0.5", "nan", "inf", "1e308", "auto", "exact", "icm",
                                    "front+top", "all", "x.png", "x.json", "x.npy", "dir", "um", "", "--"]), _TEXT)
_FLAG_NAMES = sorted({f.name for _, cls in SOURCES for f, spec in declared(cls) if spec.flag is not None
                      and not spec.positional} - _NOT_FUZZED - {"output", "shape", "device", "quiet"})


@settings(max_examples=300, **FUZZ)
@given(flags=st.lists(st.tuples(st.sampled_from(_FLAG_NAMES), st.lists(_WORDS, max_size=3)), max_size=3),
       method=st.sampled_from(["ml", "ml", "kopf", "wl", "chen-wang"]), device=st.sampled_from(_DEVICES),
       output=st.sampled_from(["out.npy", "out.tif", "out.ome.tif", "sub/out.TIFF"]))
def test_synth_command_takes_any_flags_or_refuses_them(flags, method, device, output):
    with _in_tmpdir():
        argv = ["synth", _exemplar_file(), "-o", output, "--shape", "5", "6", "4", "--method", method,
                "--device", device, *_SMALL_RUN]
        for name, words in flags:
            argv += ["--" + name.replace("_", "-"), *words]
        _run_cli(argv, output)


def _toml(value) -> str:
    """*value* as TOML (a table's values inline)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not np.isfinite(value):
        return "nan" if np.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, (int, float, str)):
        return json.dumps(value)
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {_toml(v)}" for k, v in value.items()) + "}"
    return "[" + ", ".join(_toml(v) for v in value) + "]"


_JSON_VALUES = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-3, 12), st.floats(allow_nan=False, allow_infinity=False),
              st.sampled_from([2**40, 1e308, 5e-324]), _TEXT, st.sampled_from(["ml", "kopf", "ex.npy", "brick"])),
    lambda inner: st.one_of(st.lists(inner, max_size=3), st.dictionaries(_TEXT, inner, max_size=2)), max_leaves=4)
_TOML_VALUES = _JSON_VALUES.filter(lambda v: v is not None and "None" not in repr(v))
_CONFIG_KEYS = sorted(set(_FLAG_NAMES) | {"exemplar", "shape", "method", "about", "preset", "relaxaton"})


@st.composite
def _config_value(draw, name: str):
    """A valid value of *name* where it has a declaration, a small shape, or anything TOML holds."""
    if name == "shape":
        return draw(st.one_of(st.lists(st.integers(4, 7), min_size=3, max_size=3), _TOML_VALUES))
    if name in _SPECS and draw(st.booleans()):
        value = draw(_valid(name))
        return list(value) if isinstance(value, tuple) else value
    value = draw(_TOML_VALUES)
    return value if name not in _COSTLY or not isinstance(value, int) or value < 12 else 3


_CONFIGS = st.lists(st.sampled_from(_CONFIG_KEYS), max_size=5, unique=True).flatmap(
    lambda keys: st.fixed_dictionaries({k: _config_value(k) for k in keys}))


@settings(max_examples=200, **FUZZ)
@given(config=_CONFIGS, garbage=st.one_of(st.none(), st.binary(max_size=40)), positional=st.booleans(),
       device=st.sampled_from(_DEVICES))
def test_synth_config_takes_any_toml_or_refuses_it(config, garbage, positional, device):
    with _in_tmpdir():
        text = "\n".join(f"{json.dumps(k)} = {_toml(v)}" for k, v in config.items() if v is not None)
        Path("run.toml").write_bytes(garbage if garbage is not None else text.encode())
        # A small shape unless the file holds one: the default 64³ would take hours on the reference.
        sized = garbage is None and "shape" in config
        argv = ["synth", *([_exemplar_file()] if positional else []), "--config", "run.toml", "-o", "out.npy",
                "--device", device, *_SMALL_RUN, *([] if sized else ["--shape", "5", "5", "5"])]
        if "exemplar" not in config:
            _exemplar_file()
        _run_cli(argv, "out.npy")
        settings_or_error = _outcome(read_config, Path("run.toml"))
        assert isinstance(settings_or_error, (dict, ClsolidError))


@functools.lru_cache(maxsize=None)
def _sidecar() -> dict:
    """The sidecar of a small finished run (its exemplar is ``ex.npy`` beside it)."""
    with _in_tmpdir():
        assert main(["synth", _exemplar_file(), "-o", "run.npy", "--shape", "5", "5", "5", "--device", "reference",
                     "--seed", "3", *_SMALL_RUN]) == 0
        return json.loads(Path("run.json").read_text())


@st.composite
def _damaged_sidecar(draw) -> dict:
    """The sidecar with keys dropped, added or given values of other types, at its top and in its params."""
    meta = json.loads(json.dumps(_sidecar()))
    params = meta["params"]
    for table in (meta, params):
        for key in draw(st.lists(st.sampled_from(sorted(table)), max_size=3, unique=True)):
            if draw(st.booleans()):
                del table[key]
            else:
                table[key] = draw(_JSON_VALUES)
        table.update(draw(st.dictionaries(st.sampled_from(["extra", "tile", "voxel_size_from", "written"]),
                                          _JSON_VALUES, max_size=2)))
    if draw(st.booleans()):
        meta = draw(st.one_of(_JSON_VALUES, st.just({"params": params})))
    return meta


@settings(max_examples=200, **FUZZ)
@given(meta=_damaged_sidecar(), device=st.sampled_from(_DEVICES))
def test_synth_config_takes_any_sidecar_or_refuses_it(meta, device):
    with _in_tmpdir():
        _exemplar_file()
        Path("run.json").write_text(json.dumps(meta))
        found = _outcome(sidecar_settings, Path("run.json"))
        assert isinstance(found, (dict, ClsolidError))
        _run_cli(["synth", "--config", "run.json", "-o", "again.npy", "--device", device, "-q"], "again.npy")


@settings(max_examples=100, **FUZZ)
@given(config=_CONFIGS)
def test_validate_config_takes_any_toml_or_refuses_it(config):
    with _in_tmpdir():
        np.save("real.npy", (np.random.default_rng(0).random((8, 8, 8)) > 0.5).astype(np.uint8))
        text = "\n".join(f"{json.dumps(k)} = {_toml(v)}" for k, v in config.items() if v is not None)
        Path("opts.toml").write_text(text)
        _run_cli(["validate", "real.npy", "-n", "1", "--no-tortuosity", "--device", "reference", "--config",
                  "opts.toml", "-q", "-o", "report.json"], "report.json")
