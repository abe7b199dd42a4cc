"""Reading and writing volumes.

Volumes are ``(Z, Y, X)`` arrays. TIFF output is an ImageJ hyperstack so that Fiji
opens it as a z-stack with the right voxel size, or, named ``.ome.tif``, an OME-TIFF (a
BigTIFF above 4 GiB, which every reader reads whole); ``.npy`` keeps the bare array. All
are written a plane at a time, to a temporary file renamed into place when complete.
Label volumes (integer grey-level indices) are narrowed to ``uint8``/``uint16``
because those, with ``float32``, are the only sample types ImageJ understands.
"""

from __future__ import annotations

import json
import math
import os
import logging
import pathlib
import struct
import tokenize
import warnings
import zlib
from numbers import Real
from typing import Any, Iterator, Union

import numpy as np
import tifffile
from PIL import Image

from .core.files import replaced_atomically
from .errors import InputError, LargeTiffWarning

PathLike = Union[str, "os.PathLike[str]"]

#: Extensions :func:`save_volume` can write.
VOLUME_WRITE_SUFFIXES = (".tif", ".tiff", ".npy")
#: Extensions :func:`load_volume` can read.
VOLUME_READ_SUFFIXES = (".tif", ".tiff", ".npy", ".png")

#: Names :func:`save_volume` writes as OME-TIFF (BigTIFF above 4 GiB), not ImageJ's TIFF.
OME_SUFFIXES = (".ome.tif", ".ome.tiff")
#: OME-XML's length units (its UnitsLength), and the spellings taken for them.
_OME_UNITS = ("Ym", "Zm", "Em", "Pm", "Tm", "Gm", "Mm", "km", "hm", "dam", "m", "dm", "cm", "mm", "\u00b5m", "nm",
              "pm", "fm", "am", "zm", "ym", "\u00c5", "thou", "li", "in", "ft", "yd", "mi", "ua", "ly", "pc", "pt",
              "pixel", "reference frame")
_OME_ALIASES = {"um": "\u00b5m", "micron": "\u00b5m", "microns": "\u00b5m", "\u03bcm": "\u00b5m",
                "\\u00B5m": "\u00b5m", "A": "\u00c5", "angstrom": "\u00c5", "\\u00C5": "\u00c5", "inch": "in"}
#: Bytes of samples above which a TIFF needs 64-bit offsets (tifffile's margin for the rest).
_CLASSIC_TIFF_BYTES = 2**32 - 2**25

#: The Name of the image of an OME-TIFF that :func:`save_volume` wrote: a ZYX volume.
_OME_NAME = "clsolid ZYX volume"

# ImageJ "Properties" keys under which we store what the ImageJ header cannot say.
_PROP_AXES = "clsolid.axes"
_PROP_METADATA = "clsolid.metadata"


# --------------------------------------------------------------------------- helpers


def _as_path(path: Any, param: str) -> pathlib.Path:
    """Turn ``path`` into a :class:`pathlib.Path`, rejecting non path-like values."""
    if isinstance(path, (str, os.PathLike)):
        return pathlib.Path(path)
    raise InputError(
        f"{param} must be a file path (str or pathlib.Path), got {type(path).__name__} {path!r}; "
        "pass the file name as a string"
    )


def _suffix(path: pathlib.Path, param: str, allowed: tuple[str, ...]) -> str:
    """Lower-case extension of ``path``, which must be one of ``allowed``."""
    suffix = path.suffix.lower()
    if suffix not in allowed:
        raise InputError(
            f"{param} {str(path)!r} has unsupported extension {path.suffix or '(none)'!r}; "
            f"use one of {', '.join(allowed)} (any case)"
        )
    return suffix


def _read_png(path: pathlib.Path, param: str) -> np.ndarray:
    """Read a PNG keeping its bit depth; colour images keep their channel axis last."""
    try:
        with Image.open(path) as img:
            img.load()
            if img.mode == "1":
                # A bilevel image would come back as bool, which is not a grey scale.
                img = img.convert("L")
            elif img.mode == "P":
                # Palette indices are not grey values: expand, then collapse a grey palette.
                img = img.convert("RGBA" if "transparency" in img.info else "RGB")
            data = np.asarray(img)
    except Image.DecompressionBombError as exc:  # a damaged header can declare billions of pixels
        raise InputError(f"{param} {str(path)!r} declares more pixels than Pillow opens ({exc}); check that the "
                         "file is not damaged, or save a large image as .tif or .npy") from exc
    except (OSError, ValueError) as exc:
        raise InputError(
            f"{param} {str(path)!r} could not be read as a PNG image ({exc}); "
            "check that the file is a valid PNG"
        ) from exc
    if data.ndim == 3 and data.shape[-1] == 3 and _channels_equal(data):
        data = data[..., 0]
    return np.array(data)


def _channels_equal(rgb: np.ndarray) -> bool:
    """Whether the three colour channels are identical (a grey palette image)."""
    return bool(np.array_equal(rgb[..., 0], rgb[..., 1]) and np.array_equal(rgb[..., 0], rgb[..., 2]))


def _rational(value: Any) -> float | None:
    """A TIFF RATIONAL tag value as float, or ``None`` if it is missing or zero."""
    try:
        num, den = value
        ratio = float(num) / float(den)
    except (TypeError, ValueError, ZeroDivisionError):
        return None
    return ratio if ratio > 0 and math.isfinite(ratio) else None


def _tiff_info(tif: tifffile.TiffFile) -> tuple[dict, dict]:
    """Voxel size, unit and our metadata from an ImageJ TIFF; also the raw ImageJ properties."""
    info: dict[str, Any] = {"voxel_size": None, "unit": None, "metadata": None}
    ij = tif.imagej_metadata or {}
    props = ij.get("Properties") or {}
    if not isinstance(props, dict):
        props = {}
    # ImageJ writes 'unit' (and 'spacing' for stacks) only for a calibrated image.
    if "spacing" in ij or "unit" in ij:
        tags = tif.pages.first.tags
        xres = tags.get("XResolution")
        yres = tags.get("YResolution")
        xppu = _rational(xres.value) if xres is not None else None
        yppu = _rational(yres.value) if yres is not None else None
        x = 1.0 / xppu if xppu else 1.0
        y = 1.0 / yppu if yppu else x
        # ImageJ's default voxel depth is 1 when no spacing is recorded.
        z = float(ij.get("spacing", 1.0))
        info["voxel_size"] = (z, y, x)
        info["unit"] = str(ij.get("unit", "pixel"))
    if _PROP_METADATA in props:
        try:
            info["metadata"] = json.loads(props[_PROP_METADATA])
        except (TypeError, ValueError):
            info["metadata"] = None
    return info, props


#: TIFF ResolutionUnit 3: the resolution is in pixels per centimetre. Unit 2 (inch) is not read
#: as a pixel size: most writers put a display resolution of 72 or 96 dpi there.
_RESOLUTION_CM = 3


def _ome_elements(xml: str | None, tag: str) -> Iterator[Any]:
    """The elements named *tag* (any namespace) of an OME-XML header, in document order;
    none where it does not parse."""
    import xml.etree.ElementTree as ElementTree

    try:
        root = ElementTree.fromstring(xml or "")
    except ElementTree.ParseError:
        return iter(())
    return (el for el in root.iter() if el.tag.rsplit("}", 1)[-1] == tag)


def _pixels_size(el: Any) -> tuple[tuple[float, float], str] | None:
    """``((y, x), unit)`` from an OME ``Pixels`` element, or None."""
    unit = el.get("PhysicalSizeXUnit", "\u00b5m")  # OME's default unit
    if el.get("PhysicalSizeX") is None or el.get("PhysicalSizeYUnit", unit) != unit:
        return None
    try:
        x = float(el.get("PhysicalSizeX"))
        y = float(el.get("PhysicalSizeY", x))
    except ValueError:
        return None
    return ((y, x), unit) if min(x, y) > 0 and math.isfinite(x + y) else None


def _ome_pixel_size(xml: str | None) -> tuple[tuple[float, float], str] | None:
    """``((y, x), unit)`` from an OME-XML header's first ``Pixels`` element, or None."""
    pixels = next(_ome_elements(xml, "Pixels"), None)
    return None if pixels is None else _pixels_size(pixels)


def _ome_info(xml: str | None) -> dict[str, Any]:
    """Voxel size, unit and our metadata from the OME-XML of a stack :func:`save_volume`
    wrote (or any OME-TIFF: a missing PhysicalSizeZ is 1, as ImageJ's default depth), and
    ``ome_stack``: whether :func:`save_volume` wrote it (a one-plane stack stays 3D)."""
    info: dict[str, Any] = {}
    image = next(_ome_elements(xml, "Image"), None)
    if image is None:
        return info
    for el in image:
        name = el.tag.rsplit("}", 1)[-1]
        if name == "Description" and el.text:
            try:
                info["metadata"] = json.loads(el.text)
            except ValueError:
                pass
        elif name == "Pixels":
            info["ome_stack"] = image.get("Name") == _OME_NAME
            found = _pixels_size(el)
            if found is not None:
                (y, x), unit = found
                z = float(el.get("PhysicalSizeZ", 1.0)) if el.get("PhysicalSizeZUnit", unit) == unit else 1.0
                info.update(voxel_size=(z, y, x), unit=unit)
    return info


def _tiff_pixel_size(tif: tifffile.TiffFile) -> tuple[tuple[float, float], str] | None:
    """``((y, x), unit)`` from an open TIFF's calibration, or None (see :func:`image_pixel_size`)."""
    info, _ = _tiff_info(tif)
    if info["voxel_size"] is not None and info["unit"] != "pixel":
        return (info["voxel_size"][1], info["voxel_size"][2]), info["unit"]
    if tif.is_ome:
        return _ome_pixel_size(tif.ome_metadata)
    tags = tif.pages.first.tags
    unit, xres, yres = (tags.get(name) for name in ("ResolutionUnit", "XResolution", "YResolution"))
    if unit is None or int(unit.value) != _RESOLUTION_CM or xres is None:
        return None
    xppcm = _rational(xres.value)
    yppcm = _rational(yres.value) if yres is not None else xppcm
    return ((1e4 / yppcm, 1e4 / xppcm), "um") if xppcm and yppcm else None


def image_pixel_size(path: PathLike) -> tuple[tuple[float, float], str] | None:
    """The size of a 2D image file's pixels, where the file records it.

    Parameters
    ----------
    path : str or os.PathLike
        An image file (any of the exemplar formats).

    Returns
    -------
    tuple or None
        ``((y, x), unit)`` from a TIFF's ImageJ calibration, its OME-XML header
        (``PhysicalSizeY``, ``PhysicalSizeX``) or a resolution in pixels per centimetre
        (then in ``"um"``). None for PNG and ``.npy`` files, a file that cannot be read,
        an uncalibrated TIFF, and a resolution in inches (most writers put a display
        resolution of 72 or 96 dpi there, not the size of a pixel).
    """
    p = pathlib.Path(path)
    if p.suffix.lower() not in (".tif", ".tiff") or not p.is_file():
        return None
    with _TiffComplaints():
        try:
            with tifffile.TiffFile(p) as tif:
                return _tiff_pixel_size(tif)
        except _TIFF_DAMAGE:
            return None


#: What tifffile raises on a damaged file: besides its own errors, whatever its parser trips over
#: (struct.error, KeyError, IndexError, TypeError, RuntimeError, zlib's or another codec's error).
_TIFF_DAMAGE = (OSError, ValueError, tifffile.TiffFileError, struct.error, zlib.error, LookupError, TypeError,
                RuntimeError, AssertionError, ArithmeticError)


class _TiffComplaints(logging.Handler):
    """Holds what tifffile logs while a file is read, instead of letting it reach the terminal:
    a damaged file makes it log a line per bad tag, and the reader's own error says enough."""

    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())

    def __enter__(self) -> "_TiffComplaints":
        self._logger = logging.getLogger("tifffile")
        self._propagate = self._logger.propagate
        self._logger.addHandler(self)
        self._logger.propagate = False
        return self

    def __exit__(self, *exc: Any) -> None:
        self._logger.removeHandler(self)
        self._logger.propagate = self._propagate


def _read_tiff(path: pathlib.Path, param: str) -> tuple[np.ndarray, dict]:
    """Read a TIFF as stored (a stack as ``(Z, Y, X)``) with its calibration."""
    with _TiffComplaints() as complaints:
        try:
            with tifffile.TiffFile(path) as tif:
                data = tif.asarray()
                info, props = _tiff_info(tif)
                if tif.is_ome and not tif.is_imagej:
                    info.update(_ome_info(tif.ome_metadata))
                ome_stack = info.pop("ome_stack", False)
                rgb = bool(tif.pages) and tif.pages[0].photometric == tifffile.PHOTOMETRIC.RGB
        except MemoryError as exc:  # a damaged header can declare terabytes
            raise InputError(f"{param} {str(path)!r} declares an image larger than the memory free ({exc}); "
                             "check that the file is not damaged, or use a smaller image") from exc
        except _TIFF_DAMAGE as exc:
            raise InputError(
                f"{param} {str(path)!r} could not be read as a TIFF file ({exc}); "
                "check that the file is a valid TIFF"
            ) from exc
    if complaints.messages and data.size == 0:
        raise InputError(f"{param} {str(path)!r} is a damaged TIFF: {len(complaints.messages)} of its tags could "
                         f"not be read (the first: {complaints.messages[0]}) and it holds no image; check the file")
    # tifffile squeezes a one-slice stack to 2D; our marker (an OME stack's axes) says it was a volume.
    stack = props.get(_PROP_AXES) in ("ZYX", "ZYXS") or ome_stack
    if stack and data.ndim == (3 if rgb else 2):  # one plane, RGB or grey
        data = data[np.newaxis]
    return data, info


def _npy_data_bytes(path: pathlib.Path) -> tuple[int, int, tuple, np.dtype] | None:
    """``(declared, held, shape, dtype)``: the data bytes a ``.npy`` file's header declares
    and those the file holds; None for what is not a ``.npy`` header (:func:`numpy.load` says why)."""
    with open(path, "rb") as fh:
        try:
            version = np.lib.format.read_magic(fh)
        except ValueError:
            return None
        if version not in ((1, 0), (2, 0), (3, 0)):
            return None
        # Version 3 differs from 2 only in its header's encoding (UTF-8 field names).
        read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, _, dtype = read(fh)
        held = os.fstat(fh.fileno()).st_size - fh.tell()
    return math.prod(shape) * dtype.itemsize, held, shape, dtype


def _read_npy(path: pathlib.Path, param: str) -> np.ndarray:
    """Read a ``.npy`` file without unpickling (object arrays are refused), checking first that
    it holds the data its header declares: a damaged header must not make it allocate more."""
    try:
        sizes = _npy_data_bytes(path)
        truncated = sizes is not None and sizes[0] > sizes[1]
        data = None if truncated else np.load(path, allow_pickle=False)
    # numpy's header parser lets a damaged header's SyntaxError and TokenError through
    except (OSError, ValueError, EOFError, SyntaxError, tokenize.TokenError) as exc:
        raise InputError(
            f"{param} {str(path)!r} could not be read as a .npy array ({exc}); "
            "save it with numpy.save from a numeric array"
        ) from exc
    if truncated:
        declared, held, shape, dtype = sizes
        raise InputError(f"{param} {str(path)!r} is damaged or truncated: its header declares a {shape} {dtype} "
                         f"array ({declared} bytes) but it holds {held} bytes of data; save it again with numpy.save")
    if not isinstance(data, np.ndarray):  # np.load returns an NpzFile for .npz content
        raise InputError(f"{param} {str(path)!r} is not a single .npy array; save it with numpy.save")
    return data


def _read_any(path: Any, param: str) -> tuple[np.ndarray, dict]:
    """Read a supported file as stored, colour channels included, with its info dict."""
    p = _as_path(path, param)
    suffix = _suffix(p, param, VOLUME_READ_SUFFIXES)
    if not p.exists():
        raise InputError(f"{param} {str(p)!r} does not exist; check the file name and directory")
    if not p.is_file():
        raise InputError(f"{param} {str(p)!r} is not a regular file; pass the path of a file")
    info: dict[str, Any] = {"voxel_size": None, "unit": None, "metadata": None}
    if suffix in (".tif", ".tiff"):
        return _read_tiff(p, param)
    if suffix == ".npy":
        return _read_npy(p, param), info
    return _read_png(p, param), info


def _check_voxel_size(voxel_size: Any) -> tuple[float, float, float] | None:
    """Validate ``voxel_size`` (scalar = isotropic) and return it as ``(z, y, x)``."""
    if voxel_size is None:
        return None
    values = (voxel_size,) * 3 if isinstance(voxel_size, Real) and not isinstance(voxel_size, bool) else voxel_size
    try:
        values = tuple(values)
    except TypeError:
        values = ()
    ok = len(values) == 3 and all(isinstance(v, Real) and not isinstance(v, bool) for v in values)
    if not ok or not all(math.isfinite(float(v)) and float(v) > 0 for v in values):
        raise InputError(
            f"voxel_size must be a positive finite number or a (z, y, x) tuple of three, got {voxel_size!r}; "
            "pass e.g. voxel_size=0.5 or voxel_size=(2.0, 0.5, 0.5)"
        )
    return tuple(float(v) for v in values)  # type: ignore[return-value]


def _check_unit(unit: Any) -> str:
    """The unit string must be short text that fits on one ImageJ header line. Returned as
    ImageJ writes it: the header is ASCII, so a character beyond it (the micro sign of an
    OME file's default unit, an angstrom) becomes ImageJ's escape ``\\uXXXX``, which ImageJ
    shows as the character and tifffile returns as written."""
    if not isinstance(unit, str) or not unit.strip() or any(c in unit for c in "\r\n="):
        raise InputError(
            f"unit must be a non-empty string without line breaks or '=', got {unit!r}; "
            "pass e.g. unit='um' or unit='mm'"
        )
    return "".join(c if ord(c) < 128 else f"\\u{ord(c):04X}" for c in unit)


def _written_unit(unit: Any, path: pathlib.Path | None, spacing: Any) -> str:
    """*unit* as the file at *path* records it: OME's symbol in an ``.ome.tif`` with a voxel
    size (:func:`_ome_unit`), else as the ImageJ header writes it (:func:`_check_unit`)."""
    written = _check_unit(unit)
    return _ome_unit(unit) if spacing is not None and path is not None and _is_ome(path) else written


def check_calibration(voxel_size: Any, unit: Any, path: PathLike | None = None) -> None:
    """Raise :class:`~clsolid.errors.InputError` for a *voxel_size* or *unit* that
    :func:`save_volume` would refuse (writing *path*, if given), so that a run can fail
    before it starts, not after."""
    _written_unit(unit, None if path is None else pathlib.Path(path), _check_voxel_size(voxel_size))


def _check_metadata(metadata: Any) -> str | None:
    """Serialise ``metadata`` to JSON, which is how it is stored in the TIFF."""
    if metadata is None:
        return None
    if not isinstance(metadata, dict):
        raise InputError(f"metadata must be a dict or None, got {type(metadata).__name__}; pass a dict")
    try:
        return json.dumps(metadata, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise InputError(
            f"metadata must be JSON-serialisable (str keys; str, number, bool, None, list, dict values), "
            f"got {metadata!r} ({exc}); convert arrays with .tolist() and drop other objects"
        ) from exc


def _check_volume(volume: Any) -> np.ndarray:
    """A non-empty, real-valued 3D ndarray, or an RGB one ``(Z, Y, X, 3)``."""
    if not isinstance(volume, np.ndarray):
        raise InputError(
            f"volume must be a numpy array of shape (Z, Y, X), got {type(volume).__name__}; "
            "pass np.asarray(volume)"
        )
    if volume.ndim != 3 and not (volume.ndim == 4 and volume.shape[-1] == 3):
        raise InputError(
            f"volume must be 3D (Z, Y, X), or RGB (Z, Y, X, 3), got shape {volume.shape}; "
            "for a single 2D slice pass volume[np.newaxis]"
        )
    if volume.size == 0:
        raise InputError(f"volume is empty (shape {volume.shape}); every dimension must be at least 1")
    if volume.dtype.kind not in "biuf":
        raise InputError(
            f"volume has unsupported dtype {volume.dtype}; use an integer, float or bool array"
        )
    return volume


def _narrow_dtype(volume: np.ndarray) -> np.dtype | None:
    """The dtype an integer/bool volume is written as: ``uint8``/``uint16`` if its values
    fit, else ``None`` (a reduction: no copy of a large volume is made)."""
    if volume.dtype == np.uint8 or volume.dtype == np.uint16:
        return volume.dtype
    if volume.dtype.kind == "b":
        return np.dtype(np.uint8)
    lo, hi = int(volume.min()), int(volume.max())
    if lo >= 0 and hi < 256:
        return np.dtype(np.uint8)
    if lo >= 0 and hi < 65536:
        return np.dtype(np.uint16)
    return None


def _tiff_dtype(volume: np.ndarray) -> np.dtype:
    """The ImageJ sample type (uint8, uint16 or float32) ``volume`` is written as."""
    if volume.dtype.kind == "f":
        return np.dtype(np.float32)
    narrowed = _narrow_dtype(volume)
    if narrowed is None:
        raise InputError(
            f"volume values span {int(volume.min())}..{int(volume.max())} (dtype {volume.dtype}), which does not "
            "fit ImageJ's uint8/uint16 samples; rescale to 0..65535, convert to float32, or save as .npy"
        )
    return narrowed


def _planes(volume: np.ndarray, dtype: np.dtype) -> Iterator[np.ndarray]:
    """The Z planes of *volume* as contiguous *dtype* arrays, one at a time: a volume larger
    than memory (a memory-mapped result) is written without a whole copy of it."""
    for plane in volume:
        yield np.ascontiguousarray(plane, dtype=dtype)


def _write_npy(path: pathlib.Path, volume: np.ndarray, dtype: np.dtype) -> None:
    """Write *volume* as *dtype* to a ``.npy`` file, a plane at a time."""
    header = {"descr": np.lib.format.dtype_to_descr(dtype), "fortran_order": False, "shape": volume.shape}
    # Through a file object: np.save on a name appends ".npy" unless it ends in lower-case ".npy".
    with open(path, "wb") as fh:
        np.lib.format.write_array_header_1_0(fh, header)
        for plane in _planes(volume, dtype):
            fh.write(plane.tobytes())


# --------------------------------------------------------------------------- public API


def save_volume(
    path: PathLike,
    volume: np.ndarray,
    *,
    voxel_size: float | tuple[float, float, float] | None = None,
    unit: str = "um",
    metadata: dict | None = None,
) -> pathlib.Path:
    """Write a ``(Z, Y, X)`` volume, or an RGB one ``(Z, Y, X, 3)``, to ``.tif``/``.tiff``,
    ``.ome.tif``/``.ome.tiff`` or ``.npy``, a plane at a time (a memory-mapped volume larger
    than memory is written without a whole copy).

    Parameters
    ----------
    path : str or os.PathLike
        Output file. The extension (any case) picks the format. Parent
        directories are created; an existing file is replaced. The file is written under
        a temporary name in its folder and renamed when complete: a write that fails
        (a full disk) leaves what was at *path* before, never part of the volume.
    volume : numpy.ndarray
        3D array ``(Z, Y, X)`` of integers, floats or bools, or ``(Z, Y, X, 3)`` RGB.
    voxel_size : float or tuple of 3 floats, optional
        Physical voxel size ``(z, y, x)``; a scalar means isotropic. TIFF only.
    unit : str, default "um"
        Length unit of ``voxel_size``. TIFF only (written only with ``voxel_size``).
    metadata : dict, optional
        JSON-serialisable extra information, stored in the TIFF as the ImageJ
        property ``clsolid.metadata`` (OME-TIFF: the image's Description) and returned
        by :func:`load_volume`. TIFF only.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    InputError
        Unsupported extension, bad ``volume``, ``voxel_size``, ``unit`` or
        ``metadata``, or integer values that fit neither uint8 nor uint16 (TIFF).
    OSError
        The file could not be written (its temporary file is removed).

    Notes
    -----
    TIFF: an ImageJ hyperstack with axes ``ZYX``. ImageJ stores only uint8,
    uint16 and float32 samples, so integer and bool volumes become ``uint8``
    when their values are in 0..255, else ``uint16`` when in 0..65535 (else
    an error); floats become ``float32``. ImageJ's TIFF is never BigTIFF: above
    4 GiB of samples it is written in ImageJ's large-file form (one directory,
    the planes stored contiguously), which ImageJ/Fiji, tifffile and
    :func:`load_volume` read whole and other TIFF readers see as its first
    plane; a :class:`~clsolid.LargeTiffWarning` says so.

    RGB volumes are written with RGB photometric interpretation, axes ``ZYXS``: ImageJ's
    TIFF holds them as 8-bit samples only (others are refused: write an ``.ome.tif``).

    OME-TIFF (a name ending in ``.ome.tif`` or ``.ome.tiff``, any case): the same sample
    types, one page a plane, and a BigTIFF when the samples pass 4 GiB, which every OME
    reader (Fiji's Bio-Formats, napari, tifffile, :func:`load_volume`) reads whole. The
    voxel size is OME's ``PhysicalSizeZ/Y/X`` in ``unit`` spelt as OME-XML spells it
    (``um`` becomes ``\u00b5m``; a unit OME does not know is refused), the metadata the
    image's ``Description``.

    NPY: integer and bool volumes are narrowed the same way when they fit
    (else kept as they are); floats keep their dtype. A ``.npy`` file holds
    only the array, so ``voxel_size``, ``unit`` and ``metadata`` are validated
    but not stored there; use TIFF to keep them.
    """
    p = _as_path(path, "path")
    suffix = _suffix(p, "path", VOLUME_WRITE_SUFFIXES)
    vol = _check_volume(volume)
    spacing = _check_voxel_size(voxel_size)
    unit = _written_unit(unit, p, spacing)
    meta_json = _check_metadata(metadata)
    p.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".npy":
        narrowed = vol.dtype if vol.dtype.kind == "f" else _narrow_dtype(vol)
        with replaced_atomically(p) as tmp:
            _write_npy(tmp, vol, vol.dtype if narrowed is None else narrowed)
        return p
    dtype = _tiff_dtype(vol)
    _check_rgb_samples(p, vol, dtype)
    with replaced_atomically(p) as tmp:
        if _is_ome(p):
            _write_ome(tmp, vol, dtype, spacing, unit, meta_json)
        else:
            _write_imagej(tmp, vol, dtype, spacing, unit, meta_json, shown=p)
    return p


def _check_rgb_samples(path: pathlib.Path, volume: np.ndarray, dtype: np.dtype) -> None:
    """Refuse RGB samples ImageJ's TIFF cannot hold (8-bit only)."""
    if volume.ndim == 4 and dtype != np.uint8 and not _is_ome(path):
        raise InputError(f"{path.name}: ImageJ stores RGB as 8-bit samples only, and this volume's are {dtype}; "
                         "write an .ome.tif or a .npy file")


def check_rgb_output(path: PathLike, exemplar: np.ndarray) -> None:
    """Raise :class:`~clsolid.errors.InputError` where :func:`save_volume` would refuse to
    write, at *path*, a colour volume grown from the RGB *exemplar* (whose colours it holds),
    so that a run can fail before it starts, not after. A grey exemplar passes."""
    p = pathlib.Path(path)
    if exemplar.ndim == 3 and p.suffix.lower() in (".tif", ".tiff"):
        _check_rgb_samples(p, exemplar[None], _tiff_dtype(exemplar))


def _is_ome(path: pathlib.Path) -> bool:
    return path.name.lower().endswith(OME_SUFFIXES)


def _ome_unit(unit: str) -> str:
    """*unit* as OME-XML's unit symbol (``um`` is ``\u00b5m``); refuse one OME does not know."""
    symbol = _OME_ALIASES.get(unit.strip(), unit.strip())
    if symbol not in _OME_UNITS:
        raise InputError(f"unit {unit!r} is not one of OME-XML's length units, which an .ome.tif must use; pass "
                         "e.g. unit='um', 'nm', 'mm' or 'angstrom', or write an ImageJ .tif")
    return symbol


def _write_ome(path: pathlib.Path, volume: np.ndarray, dtype: np.dtype, spacing: tuple[float, float, float] | None,
               unit: str, meta_json: str | None) -> None:
    """Write an OME-TIFF ZYX stack, a page a plane, written a plane at a time: a BigTIFF when
    its samples pass 4 GiB, which every OME reader (Fiji's Bio-Formats, napari, tifffile)
    reads whole. The calibration is OME's PhysicalSize; the metadata its image's Description."""
    rgb = volume.ndim == 4
    meta: dict[str, Any] = {"axes": "ZYXS" if rgb else "ZYX", "Name": _OME_NAME}
    if spacing is not None:  # unit: OME's symbol (_written_unit)
        for axis, size in zip("ZYX", spacing):
            meta.update({f"PhysicalSize{axis}": size, f"PhysicalSize{axis}Unit": unit})
    if meta_json is not None:
        meta["Description"] = meta_json
    big = volume.size * dtype.itemsize > _CLASSIC_TIFF_BYTES
    # minisblack for grey: else tifffile takes a last axis of 3 or 4 voxels for RGB(A) samples
    tifffile.imwrite(path, _planes(volume, dtype), shape=volume.shape, dtype=dtype, ome=True, bigtiff=big,
                     photometric="rgb" if rgb else "minisblack", metadata=meta)


def _write_imagej(path: pathlib.Path, volume: np.ndarray, dtype: np.dtype, spacing: tuple[float, float, float] | None,
                  unit: str, meta_json: str | None, shown: pathlib.Path | None = None) -> None:
    """Write an ImageJ ZYX hyperstack of *dtype* samples, with optional calibration and
    metadata, a plane at a time; a warning names the file *shown* (default *path*)."""
    axes = "ZYXS" if volume.ndim == 4 else "ZYX"  # RGB: 8-bit samples (save_volume checks)
    props = {_PROP_AXES: axes}
    if meta_json is not None:
        props[_PROP_METADATA] = meta_json
    ij_meta: dict[str, Any] = {"axes": axes, "Properties": props}
    kwargs: dict[str, Any] = {}
    if spacing is not None:
        z, y, x = spacing
        ij_meta.update(spacing=z, unit=unit)
        # TIFF resolution is pixels per unit, the inverse of the pixel size.
        kwargs["resolution"] = (1.0 / x, 1.0 / y)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tifffile.imwrite(path, _planes(volume, dtype), shape=volume.shape, dtype=dtype, imagej=True,
                         metadata=ij_meta, photometric="rgb" if volume.ndim == 4 else None, **kwargs)
    for w in caught:  # tifffile's own note on the large-file form says nothing a user can act on
        if "truncating ImageJ file" in str(w.message):
            warnings.warn(LargeTiffWarning(
                f"{shown or path}: {volume.size * dtype.itemsize / 2**30:.1f} GiB of samples, above the 4 GiB of a classic "
                "TIFF, written in ImageJ's large-file form (one directory, the planes stored contiguously): "
                "ImageJ/Fiji, tifffile and clsolid read it whole, other TIFF readers only its first plane; save "
                "as .npy for those, or .ome.tif (an OME BigTIFF, which they read whole)"), stacklevel=3)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


def load_volume(path: PathLike) -> tuple[np.ndarray, dict]:
    """Read a volume (or a single slice) from ``.tif``/``.tiff``/``.npy``/``.png``.

    Parameters
    ----------
    path : str or os.PathLike
        File to read; the extension (any case) picks the reader.

    Returns
    -------
    array : numpy.ndarray
        The data with its stored dtype: ``(Z, Y, X)`` for a stack (``(Z, Y, X, 3)`` for
        an RGB one), 2D for a single image (a PNG is always one 2D slice). A one-slice
        volume written by :func:`save_volume` reads back as ``(1, Y, X)``.
    info : dict
        ``'voxel_size'``: ``(z, y, x)`` floats when the TIFF carries ImageJ
        calibration (z is 1.0, ImageJ's default, when no spacing is recorded),
        else ``None``; ``'unit'``: the ImageJ unit string or ``None``;
        ``'metadata'``: the dict given to :func:`save_volume` or ``None``.

    Raises
    ------
    InputError
        Missing file, unsupported extension, unreadable content or a colour PNG.
    """
    data, info = _read_any(path, "path")
    if _as_path(path, "path").suffix.lower() == ".png" and data.ndim != 2:
        raise InputError(
            f"path {str(path)!r} is a colour PNG (shape {data.shape}); only grey PNG slices are supported, "
            "convert it to grey first (e.g. skimage.color.rgb2gray)"
        )
    return data, info
