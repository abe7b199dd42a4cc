"""Exemplars: the 2D grey images a solid texture is synthesised from.

Three built-in exemplars come from scikit-image's bundled CC0 textures. Any
other exemplar is a numpy array or an image file; it is validated here so that
the synthesis code can assume a finite, real, non-empty 2D array.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np
import skimage.data

from .colour import as_colour, float_top, lab, palette
from .core.views import VIEW_ORDER
from .core.geometry import window_grid  # noqa: F401 (where the exemplar's windows lie)
from .errors import InputError
from .volumeio import VOLUME_WRITE_SUFFIXES, _read_any

#: Names accepted by :func:`builtin_exemplar` (scikit-image's 512x512 CC0 textures).
BUILTINS = ("brick", "grass", "gravel")
#: File extensions accepted by :func:`load_exemplar` (matched in any case).
EXEMPLAR_SUFFIXES = (".png",) + VOLUME_WRITE_SUFFIXES
_BUILTIN_SIDE = 512
_DEFAULT_REGION = 256


def _check_int(value: Any, param: str, lo: int, hi: int, hint: str) -> int:
    """``value`` must be an integer (not a bool) in ``[lo, hi]``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= value <= hi:
        raise InputError(f"{param} must be an integer in [{lo}, {hi}], got {value!r}; {hint}")
    return int(value)


def _area_weights(n_in: int, n_out: int) -> np.ndarray:
    """``(n_out, n_in)`` matrix averaging input pixels over each output pixel's footprint.

    Output pixel ``i`` covers ``[i * r, (i + 1) * r)`` in input pixel units, with
    ``r = n_in / n_out``; each input pixel is weighted by the length it shares
    with that interval, so every row sums to one.
    """
    r = n_in / n_out
    starts = np.arange(n_out)[:, None] * r
    left = np.maximum(starts, np.arange(n_in)[None, :])
    right = np.minimum(starts + r, np.arange(n_in)[None, :] + 1)
    return np.clip(right - left, 0.0, None) / r


def _area_downscale(image: np.ndarray, size: int) -> np.ndarray:
    """Area-average a square image down to ``size`` x ``size``."""
    n = image.shape[0]
    if n % size == 0:
        # Exact block mean: the common case (256 -> 64) needs no interpolation at all.
        k = n // size
        return image.reshape(size, k, size, k).mean(axis=(1, 3))
    w = _area_weights(n, size)
    return w @ image @ w.T


def builtin_exemplar(name: str, *, size: int = 64, region: int = _DEFAULT_REGION) -> np.ndarray:
    """One of scikit-image's bundled textures, cropped and area-averaged.

    Parameters
    ----------
    name : {"brick", "grass", "gravel"}
        Which texture (``skimage.data.brick()`` etc., 512x512, CC0).
    size : int, default 64
        Side of the returned square exemplar, ``1 <= size <= region``.
    region : int, default 256
        Side of the top-left square crop taken first, ``region <= 512``.

    Returns
    -------
    numpy.ndarray
        ``(size, size)`` float64 on the original 0..255 grey scale.

    Raises
    ------
    InputError
        Unknown ``name``, or ``size``/``region`` out of range.

    Notes
    -----
    A plain 64x64 crop holds barely one brick, so a larger region is averaged
    down instead. When ``region`` is a multiple of ``size`` this is an exact
    block mean (the default is 4x4 blocks); otherwise every output pixel is
    the area-weighted mean of the input pixels its footprint overlaps.
    """
    if not isinstance(name, str) or name not in BUILTINS:
        raise InputError(
            f"name {name!r} is not a built-in exemplar; use one of {', '.join(BUILTINS)}"
        )
    region = _check_int(region, "region", 1, _BUILTIN_SIDE, f"the built-in textures are {_BUILTIN_SIDE} px wide")
    size = _check_int(size, "size", 1, region, f"size must not exceed region ({region}); lower size or raise region")
    crop = getattr(skimage.data, name)()[:region, :region].astype(np.float64)
    return _area_downscale(crop, size)


def _reject_colour_or_volume(shape: tuple[int, ...]) -> None:
    """Explain why a 3D array is not a usable exemplar."""
    last = shape[-1]
    if last in (3, 4):
        raise InputError(
            f"exemplar has shape {shape}: a colour (RGB) image or a volume; for colour pass channel_axis=-1, "
            "for a volume one slice (e.g. volume[0])"
        )
    if last == 2:
        raise InputError(
            f"exemplar has shape {shape}, a grey image with an alpha channel; drop the alpha channel "
            "(image[..., 0])"
        )
    raise InputError(
        f"exemplar has shape {shape}, which looks like a 3D volume; the exemplar must be one 2D image, "
        "pass a single slice (e.g. volume[0])"
    )


def _check_exemplar_array(data: np.ndarray, channel_axis: int | None = None) -> np.ndarray:
    """Validate an exemplar array; return it 2D (grey) or ``(H, W, 3)`` (colour: the
    channels along *channel_axis*), native byte order, as its own copy."""
    if channel_axis is not None:
        data = as_colour(data, channel_axis)
    if data.ndim == 3 and channel_axis is None and data.shape[-1] == 1:
        data = data[..., 0]
    if data.ndim == 3 and channel_axis is None and data.shape[0] == 1:
        data = data[0]  # a one-slice stack is a 2D image
    if data.ndim == 3 and channel_axis is None:
        _reject_colour_or_volume(data.shape)
    if data.ndim not in (2, 3):
        raise InputError(
            f"exemplar must be a 2D image (grey, or colour with channel_axis), got a {data.ndim}D array of shape "
            f"{data.shape}; pass a (height, width) array"
        )
    if data.size == 0:
        raise InputError(f"exemplar is empty (shape {data.shape}); both dimensions must be at least 1")
    if data.dtype.kind not in "iuf":
        raise InputError(
            f"exemplar has unsupported dtype {data.dtype}; use an integer or float grey image "
            "(e.g. image.astype(np.uint8) for a bool mask)"
        )
    if data.dtype.kind == "f" and not np.isfinite(data).all():
        raise InputError(
            f"exemplar contains {int(np.count_nonzero(~np.isfinite(data)))} NaN or infinite values; "
            "replace them (e.g. numpy.nan_to_num) before using the image"
        )
    # Native byte order: the array is later copied byte for byte to the device.
    return np.array(data, dtype=data.dtype.newbyteorder("="), order="C")


def _load_string(source: str, builtin_size: int) -> np.ndarray:
    """A string is a built-in name or a file path."""
    if source in BUILTINS:
        return builtin_exemplar(source, size=builtin_size)
    if not os.path.exists(source) and os.path.splitext(source)[1].lower() not in EXEMPLAR_SUFFIXES:
        raise InputError(
            f"exemplar {source!r} is neither an existing file nor a built-in exemplar name; pass a path to a "
            f"{'/'.join(EXEMPLAR_SUFFIXES)} file or one of {', '.join(BUILTINS)}"
        )
    return _load_file(source)


def _load_file(path: str | os.PathLike) -> np.ndarray:
    """Read an exemplar file as stored, then validate it: a last axis of 3 or 4 samples is a
    colour image's (PNG, RGB TIFF)."""
    data, _ = _read_any(path, "exemplar")
    colour = data.ndim == 3 and data.shape[-1] in (3, 4) and data.shape[0] > 1
    return _check_exemplar_array(data, -1 if colour else None)


def load_exemplar(source: Any, *, builtin_size: int = 64, channel_axis: int | None = None) -> np.ndarray:
    """Load and validate an exemplar.

    Parameters
    ----------
    source : numpy.ndarray, str or os.PathLike
        A 2D array; a path to a ``.png``, ``.tif``, ``.tiff`` or ``.npy`` file
        (extension in any case); or a built-in name (see :data:`BUILTINS`).
        A trailing singleton channel axis ``(H, W, 1)`` and a leading
        singleton axis ``(1, H, W)`` are squeezed away. A file whose last axis holds 3
        samples (a colour PNG or TIFF) is an RGB image.
    builtin_size : int, default 64
        Side of a built-in exemplar (``builtin_exemplar(name, size=...)``),
        in ``[1, 256]``.
    channel_axis : int or None, default None
        The axis of an array's colour channels (as in scikit-image): the array is then an
        RGB image. None: the array is grey.

    Returns
    -------
    numpy.ndarray
        A 2D (grey) or ``(H, W, 3)`` (RGB) C-contiguous copy in native byte order that keeps
        the source dtype and units: uint8 stays 0..255, uint16 stays 0..65535, floats are
        unchanged. Keeping the dtype lets ``quantise(image, levels=None)`` see
        that an image is 8-bit. Built-ins are float64 on the 0..255 scale. An RGB image
        whose three channels are equal comes back grey.

    Raises
    ------
    InputError
        Missing, unreadable or unsupported file; unknown name; RGBA or another channel
        count; 3D volume or other non-2D shape; empty array; bool, complex, object,
        string or other non-numeric dtype; NaN or infinite values.
    """
    builtin_size = _check_int(
        builtin_size, "builtin_size", 1, _DEFAULT_REGION,
        f"built-ins are averaged from a {_DEFAULT_REGION} px region; for larger ones call builtin_exemplar",
    )
    if isinstance(source, np.ndarray):
        return _check_exemplar_array(source, channel_axis)
    if isinstance(source, str):
        return _load_string(source, builtin_size)
    if isinstance(source, os.PathLike):
        return _load_file(source)
    raise InputError(
        f"exemplar must be a numpy array, a file path or a built-in name, got {type(source).__name__}; "
        "pass np.asarray(...) for array-like data"
    )


def _check_levels(levels: Any) -> int:
    """``levels`` must be an integer in [2, 65536]."""
    return _check_int(levels, "levels", 2, 65536, "pass the number of grey levels, e.g. levels=32")


def _scaled_floor(image: np.ndarray, lo: Any, hi: Any, levels: int) -> np.ndarray:
    """``floor((image - lo) / (hi - lo) * levels)`` for ``hi > lo``, exact for integers."""
    if image.dtype.kind in "iu":
        lo_i, hi_i = int(lo), int(hi)
        if (hi_i - lo_i) * levels < 2**62:
            # Integer arithmetic avoids float rounding just below a level boundary.
            shifted = image.astype(np.int64) - lo_i
            return shifted * levels // (hi_i - lo_i)
    x = image.astype(np.float64)
    lo_f, hi_f = float(lo), float(hi)
    if np.isfinite(hi_f - lo_f):
        t = (x - lo_f) / (hi_f - lo_f)
    else:  # halving both ends keeps an extreme span finite (and is exact there: no subnormals)
        t = (x / 2 - lo_f / 2) / (hi_f / 2 - lo_f / 2)
    return np.floor(t * levels)


#: The views an exemplar per axis may be given for (:mod:`clsolid.core.views`).
VIEW_KEYS = VIEW_ORDER


def load_exemplars(source: Any, *, builtin_size: int = 64,
                   channel_axis: int | None = None) -> np.ndarray | dict[str, np.ndarray]:
    """Load one exemplar, or one per view.

    Parameters
    ----------
    source : numpy.ndarray, str, os.PathLike or dict
        One exemplar (:func:`load_exemplar`), or a dict ``{view: exemplar}`` of two or three
        of ``"front"``, ``"right"``, ``"top"``, each anything :func:`load_exemplar` takes.
    builtin_size, channel_axis
        As for :func:`load_exemplar` (one *channel_axis* for every view's array).

    Returns
    -------
    numpy.ndarray or dict
        The image, or ``{view: image}`` in :data:`VIEW_KEYS` order. The images may differ in
        size, not in dtype, and are all grey or all colour.

    Raises
    ------
    InputError
        What :func:`load_exemplar` refuses (the message names the view), a key that is no
        view, fewer than two views, or images of different dtypes.
    """
    if not isinstance(source, dict):
        return load_exemplar(source, builtin_size=builtin_size, channel_axis=channel_axis)
    unknown = [k for k in source if k not in VIEW_KEYS]
    if unknown:
        raise InputError(f"exemplar keys {unknown!r} are not views; use two or three of {', '.join(VIEW_KEYS)}")
    if len(source) < 2:
        raise InputError(f"an exemplar per view needs two or three of {', '.join(VIEW_KEYS)}, got {list(source)}; "
                         "pass a single exemplar for one material seen alike in every view")
    images = {}
    for view in (v for v in VIEW_KEYS if v in source):
        try:
            images[view] = load_exemplar(source[view], builtin_size=builtin_size, channel_axis=channel_axis)
        except InputError as err:
            raise InputError(f"the {view} exemplar: {err}") from None
    dtypes = {v: str(im.dtype) for v, im in images.items()}
    if len(set(dtypes.values())) > 1:
        raise InputError(f"the views' exemplars must share one dtype, got {dtypes}; convert them to one "
                         "(e.g. image.astype(np.uint8)) so that their values mean the same")
    kinds = {v: "colour" if im.ndim == 3 else "grey" for v, im in images.items()}
    if len(set(kinds.values())) > 1:
        raise InputError(f"the views' exemplars must be all grey or all colour, got {kinds}")
    return images


def each(images: Any) -> list:
    """The exemplars as a list: one image alone, or every view's of a dict by view (none for None)."""
    if images is None:
        return []
    return list(images.values()) if isinstance(images, dict) else [images]


def pooled(images: np.ndarray | dict[str, np.ndarray]) -> np.ndarray:
    """One image, or every view's pixels in one row (their statistics pooled)."""
    if not isinstance(images, dict):
        return images
    return np.concatenate([im.reshape(-1, *im.shape[2:]) for im in images.values()])[None]


def quantise(image: np.ndarray, levels: int | None = 32) -> np.ndarray:
    """Uniformly quantise a grey image to integer labels.

    Parameters
    ----------
    image : numpy.ndarray
        Real-valued, finite, non-empty array (any number of dimensions).
    levels : int or None, default 32
        Number of grey levels, in ``[2, 65536]``. ``None`` keeps every level
        of an 8-bit image and is only accepted for ``uint8`` input.

    Returns
    -------
    numpy.ndarray
        int32 labels of the same shape, in ``[0, levels - 1]``.

    Raises
    ------
    InputError
        Bad ``levels`` (bools rejected), ``levels=None`` with non-uint8 input,
        or an invalid ``image``.

    Notes
    -----
    The image's own ``[min, max]`` is mapped linearly onto ``[0, levels)``:
    ``label = floor((v - min) / (max - min) * levels)``, with ``v = max``
    clipped to ``levels - 1``. An image that spans its range thus uses the
    first and last levels, the mapping is monotone, and a constant image gives
    all zeros. With ``levels=None`` the uint8 values themselves are the
    labels (0..255), independent of the image's range.
    """
    if not isinstance(image, np.ndarray):
        raise InputError(f"image must be a numpy array, got {type(image).__name__}; pass np.asarray(image)")
    if image.size == 0:
        raise InputError(f"image is empty (shape {image.shape}); pass a non-empty array")
    if image.dtype.kind not in "iuf":
        raise InputError(f"image has unsupported dtype {image.dtype}; use an integer or float grey image")
    if image.dtype.kind == "f" and not np.isfinite(image).all():
        raise InputError("image contains NaN or infinite values; replace them before quantising")
    if levels is None:
        if image.dtype != np.uint8:
            raise InputError(
                f"levels=None keeps the 256 levels of an 8-bit image, but image has dtype {image.dtype}; "
                "pass an integer levels (e.g. levels=32) or convert the image to uint8"
            )
        return image.astype(np.int32)
    levels = _check_levels(levels)
    lo, hi = image.min(), image.max()
    if not hi > lo:
        return np.zeros(image.shape, dtype=np.int32)
    labels = _scaled_floor(image, lo, hi, levels)
    return np.clip(labels, 0, levels - 1).astype(np.int32)


@dataclass(frozen=True)
class LevelMap:
    """How an exemplar's values become the label indices the engine works on, and back.

    Attributes
    ----------
    labels : numpy.ndarray or dict
        int32 image of label indices, ``0 <= labels < values.size`` (one per view, in a
        dict, for an exemplar per view).
    values : numpy.ndarray
        ``values[i]`` is label ``i`` in the exemplar's own units and dtype.
    exact : bool
        True when ``values`` are exactly the values found in the exemplar (a binary or
        segmented image, or one already holding at most ``levels`` values); False when
        each is the mean of the exemplar pixels quantised to that level.
    features : numpy.ndarray or None
        A colour exemplar's palette in CIELAB, ``(L, 3)`` float64: where the Parzen
        distances between labels are taken (:mod:`clsolid.colour`). None for grey.
    """

    labels: np.ndarray | dict[str, np.ndarray]
    values: np.ndarray
    exact: bool
    features: np.ndarray | None = None

    @property
    def colour(self) -> bool:
        """Whether the labels stand for colours (``values`` is ``(L, 3)``)."""
        return self.features is not None

    @property
    def n_labels(self) -> int:
        """How many labels there are (``values``' rows)."""
        return len(self.values)

    @property
    def label_dtype(self) -> type:
        """The dtype a volume of these labels is given: uint8, or uint16 above 256 labels."""
        return np.uint8 if self.n_labels <= 256 else np.uint16

    def to_values(self, labels: np.ndarray | dict[str, np.ndarray]) -> np.ndarray | dict[str, np.ndarray]:
        """Map label indices back to the exemplar's values (and dtype); a dict view by view."""
        if isinstance(labels, dict):
            return {v: self.values[im] for v, im in labels.items()}
        return self.values[labels]


def nearest_level_index(values: Any, levels: np.ndarray) -> np.ndarray:
    """Index in the sorted *levels* of the level nearest to each of *values* (flattened; the
    lower level on a tie). Values between levels, as averaging methods and ``h1-mean`` write,
    count for the nearest; the midpoints are taken in float64, so integer levels do not wrap."""
    lv = np.asarray(levels, np.float64)
    return np.searchsorted((lv[1:] + lv[:-1]) / 2.0, np.ravel(values))


def _bin_means(image: np.ndarray, labels: np.ndarray, levels: int) -> np.ndarray:
    """Mean of the pixels of each level, in the image's dtype; an empty level gets its bin centre."""
    counts = np.bincount(labels.ravel(), minlength=levels)
    sums = np.bincount(labels.ravel(), weights=image.ravel().astype(np.float64), minlength=levels)
    lo, hi = float(np.min(image)), float(np.max(image))
    centres = lo + (np.arange(levels) + 0.5) * (hi - lo) / levels
    means = np.where(counts > 0, sums / np.maximum(counts, 1), centres)
    if image.dtype.kind in "iu":
        info = np.iinfo(image.dtype)
        return np.clip(np.rint(means), info.min, info.max).astype(image.dtype)
    return means.astype(image.dtype)


def level_map(image: np.ndarray | dict[str, np.ndarray], levels: int | None) -> LevelMap:
    """Labels of *image* for the engine, and the value each label stands for.

    Parameters
    ----------
    image : numpy.ndarray or dict
        The exemplar (2D, real, finite), or one per view (:func:`load_exemplars`): their
        pixels are pooled, so that every view has the same levels, and ``labels`` is a dict.
    levels : int or None
        Most grey levels. ``None`` keeps the 256 levels of a uint8 image.

    Returns
    -------
    LevelMap

    Notes
    -----
    - ``levels=None`` (uint8 only): the labels are the pixel values, and so are the values.
    - At most ``levels`` distinct values (a binary or segmented micrograph): the labels are
      their ranks (0, 1, 2, … in increasing value; equally spaced for the Parzen
      distances) and the values are exactly those values, so a volume holds only values
      that occur in the exemplar.
    - Otherwise :func:`quantise` makes ``levels`` equal-width levels over the image's range,
      and each level's value is the mean of the exemplar pixels in it (an empty level
      gets its bin centre; integer images round the mean).
    """
    if isinstance(image, dict):  # one level set for every view: their pixels pooled
        pool = level_map(pooled(image), levels)
        cuts = np.cumsum([im.shape[0] * im.shape[1] for im in image.values()])[:-1]
        parts = np.split(pool.labels.ravel(), cuts)
        return LevelMap({v: p.reshape(im.shape[:2]) for (v, im), p in zip(image.items(), parts)}, pool.values,
                        pool.exact, pool.features)
    if image.ndim == 3:  # colour: a palette, its distances in CIELAB
        if levels is None:
            raise InputError("levels=None keeps the 256 levels of an 8-bit grey image; a colour exemplar needs a "
                             "number of colours (e.g. levels=32)")
        labels, values, exact = palette(image, _check_levels(levels))
        return LevelMap(labels, values, exact, lab(values, image.dtype, float_top(image)))
    if levels is None:
        labels = quantise(image, None)
        return LevelMap(labels, np.arange(256, dtype=np.uint8), True)
    distinct = np.unique(image)
    if distinct.size <= _check_levels(levels):
        return LevelMap(np.searchsorted(distinct, image).astype(np.int32), distinct, True)
    labels = quantise(image, levels)
    return LevelMap(labels, _bin_means(image, labels, levels), False)
