"""Input checks, view slicing and small numeric helpers shared by the metric modules."""

from __future__ import annotations

import math
import numbers
from typing import Any

import numpy as np

from ..errors import InputError

#: The three views of a (Z, Y, X) volume, in the order they are reported.
VIEWS = ("front", "right", "top")
#: The views a synthesis constrains by default.
DEFAULT_CONSTRAINED = ("front", "right")

#: Pseudo-count added to every histogram bin before normalising (Jeffreys prior), so that
#: an empty bin gives a finite log ratio whose size does not depend on a float epsilon.
PSEUDO_COUNT = 0.5


def check_int(value: Any, name: str, minimum: int, *, allow_none: bool = False) -> int | None:
    """Return ``value`` as an int >= ``minimum``; bools and floats are refused."""
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise InputError(f"{name}={value!r} must be an integer >= {minimum}")
    return int(value)


def as_image(image: Any, name: str, *, min_side: int = 2) -> np.ndarray:
    """A finite, real 2D float64 array with both sides >= ``min_side``."""
    arr = _as_real_array(image, name)
    if arr.ndim != 2:
        raise InputError(f"{name} must be a 2D image, got an array of shape {arr.shape}")
    if min(arr.shape) < min_side:
        raise InputError(f"{name} has shape {arr.shape}; both sides must be >= {min_side} pixels")
    return arr


def as_stack(slices: Any, name: str, *, min_side: int = 2) -> np.ndarray:
    """A finite ``(n, rows, cols)`` float64 stack; a 2D image becomes a stack of one."""
    arr = _as_real_array(slices, name)
    if arr.ndim == 2:
        arr = arr[None]
    if arr.ndim != 3 or arr.shape[0] == 0:
        raise InputError(f"{name} must be an (n, rows, cols) stack of slices, got shape {arr.shape}")
    if min(arr.shape[1:]) < min_side:
        raise InputError(f"{name} has slices of shape {arr.shape[1:]}; both sides must be >= {min_side}")
    return arr


def as_volume(volume: Any, name: str = "volume", *, min_side: int = 2) -> np.ndarray:
    """A finite, real 3D array ``(Z, Y, X)``; the dtype is kept (no copy of large volumes)."""
    arr = np.asarray(volume)
    if arr.ndim != 3:
        raise InputError(f"{name} must be a 3D (Z, Y, X) array, got an array of shape {arr.shape}")
    _check_dtype(arr, name)
    if min(arr.shape) < min_side:
        raise InputError(f"{name} has shape {arr.shape}; every side must be >= {min_side} voxels")
    if arr.dtype.kind == "f" and not np.isfinite(arr).all():
        raise InputError(f"{name} contains NaN or infinite values")
    return arr


def as_image_or_volume(data: Any, name: str) -> np.ndarray:
    """A finite, real, non-empty 2D image or 3D ``(Z, Y, X)`` volume; the dtype is kept."""
    arr = np.asarray(data)
    if arr.ndim not in (2, 3) or arr.size == 0:
        raise InputError(f"{name} must be a non-empty 2D image or 3D (Z, Y, X) volume, got shape {arr.shape}")
    _check_dtype(arr, name)
    if arr.dtype.kind == "f" and not np.isfinite(arr).all():
        raise InputError(f"{name} contains NaN or infinite values")
    return arr


def neighbour_pairs(ndim: int, axis: int) -> tuple[tuple, tuple]:
    """Indices of the first and the second element of every pair of neighbours along ``axis``
    of an ``ndim``-D array (``a[lo]`` and ``a[hi]`` line up pair by pair)."""
    lo, hi = [slice(None)] * ndim, [slice(None)] * ndim
    lo[axis], hi[axis] = slice(None, -1), slice(1, None)
    return tuple(lo), tuple(hi)


def _check_dtype(arr: np.ndarray, name: str) -> None:
    if arr.dtype.kind not in "biuf":
        raise InputError(f"{name} must hold real numbers, got dtype {arr.dtype}")


def _as_real_array(data: Any, name: str) -> np.ndarray:
    arr = np.asarray(data)
    _check_dtype(arr, name)
    arr = arr.astype(np.float64, copy=False)
    if not np.isfinite(arr).all():
        raise InputError(f"{name} contains NaN or infinite values")
    return arr


def check_views(views: Any, name: str, *, allow_empty: bool = False) -> tuple[str, ...]:
    """Validate a sequence of view names; return them deduplicated, in the given order."""
    if isinstance(views, str):
        views = (views,)
    try:
        items = tuple(views)
    except TypeError:
        raise InputError(f"{name}={views!r} must be a sequence of view names {VIEWS}") from None
    bad = [v for v in items if v not in VIEWS]
    if bad:
        raise InputError(f"{name}={views!r} contains {bad!r}; views are {', '.join(VIEWS)}")
    if not items and not allow_empty:
        raise InputError(f"{name} is empty; give at least one of {', '.join(VIEWS)}")
    return tuple(dict.fromkeys(items))


def view_slices(volume: Any, view: str, max_slices: int | None = None, exclude: Any = ()) -> np.ndarray:
    """The slices of a ``(Z, Y, X)`` volume seen from one view, as an ``(n, rows, cols)`` stack.

    Parameters
    ----------
    volume : array_like, shape (Z, Y, X)
        The volume; its dtype is kept.
    view : {"front", "right", "top"}
        ``front``: the (y, x) planes ``volume[z]`` (rows = y, columns = x);
        ``right``: the planes ``volume[:, :, x].T`` (rows = y, columns = z);
        ``top``: the planes ``volume[:, y, :]`` (rows = z, columns = x).
    max_slices : int or None
        At most this many slices, evenly spaced: slice ``i`` of ``k`` is the one at
        ``floor((i + 0.5) * n / k)`` (the centres of ``k`` equal blocks). None: all.
    exclude : sequence of int
        Slice indices to leave out (for example a synthesis's ``+in`` slices, which are
        exemplar copies); the slices are then chosen, as above, among the others.

    Returns
    -------
    numpy.ndarray
        ``(n, rows, cols)``; a view of ``volume`` for ``front`` with all slices, a copy otherwise.
    """
    vol = as_volume(volume, "volume", min_side=1)
    if view not in VIEWS:
        raise InputError(f"view={view!r} must be one of {', '.join(VIEWS)}")
    max_slices = check_int(max_slices, "max_slices", 1, allow_none=True)
    axis = {"front": 0, "right": 2, "top": 1}[view]
    idx = slice_indices(vol.shape[axis], max_slices, exclude)
    if view == "front":
        return vol if np.array_equal(idx, np.arange(vol.shape[0])) else vol[idx]
    if view == "right":
        return np.ascontiguousarray(np.transpose(vol[:, :, idx], (2, 1, 0)))
    return np.ascontiguousarray(np.transpose(vol[:, idx, :], (1, 0, 2)))


def slice_indices(n: int, max_slices: int | None, exclude: Any = ()) -> np.ndarray:
    """Indices of ``min(m, max_slices)`` evenly spaced slices among the ``m`` of ``0..n-1``
    not in *exclude* (all of those when None).

    Raises
    ------
    InputError
        An index of *exclude* outside ``0..n-1``, or every slice excluded.
    """
    skip = np.unique(np.asarray(exclude, dtype=np.intp).ravel())
    if skip.size and (skip[0] < 0 or skip[-1] >= n):
        raise InputError(f"slices to exclude must lie in 0..{n - 1}; got {skip.tolist()}")
    kept = np.setdiff1d(np.arange(n), skip)
    if kept.size == 0:
        raise InputError(f"every one of the {n} slices is excluded; nothing is left to measure")
    if max_slices is None or max_slices >= kept.size:
        return kept
    return kept[((np.arange(max_slices) + 0.5) * kept.size / max_slices).astype(np.intp)]


def smoothed_probabilities(counts: np.ndarray, pseudo: float = PSEUDO_COUNT) -> np.ndarray:
    """Normalise non-negative bin counts (last axis) after adding ``pseudo`` to every bin."""
    c = np.asarray(counts, dtype=np.float64) + pseudo
    return c / c.sum(axis=-1, keepdims=True)


def symmetric_kl(p: np.ndarray, q: np.ndarray) -> float:
    """``sum_i (p_i - q_i) ln(p_i / q_i)`` = KL(p||q) + KL(q||p) for strictly positive p, q."""
    p = np.asarray(p, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    return float(np.sum((p - q) * np.log(p / q)))


def wasserstein_1d(a: np.ndarray, b: np.ndarray, wa: np.ndarray | None = None,
                   wb: np.ndarray | None = None) -> float:
    """Wasserstein-1 distance between two weighted 1D samples (integral of |F_a - F_b|)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    wa = np.ones_like(a) if wa is None else np.asarray(wa, dtype=np.float64)
    wb = np.ones_like(b) if wb is None else np.asarray(wb, dtype=np.float64)
    values = np.concatenate([a, b])
    order = np.argsort(values, kind="stable")
    # Signed mass: +w for sample a, -w for sample b; the running sum is F_a - F_b.
    mass = np.concatenate([wa / wa.sum(), -wb / wb.sum()])[order]
    diff = np.cumsum(mass)[:-1]
    return float(np.sum(np.abs(diff) * np.diff(values[order])))


def is_integer_valued(values: np.ndarray) -> bool:
    """True when every value is a whole number (so one histogram bin per grey level fits)."""
    return bool(np.all(values == np.round(values)))


def jsonable(obj: Any) -> Any:
    """Recursively convert numpy scalars/arrays to Python types; NaN and inf become None."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, numbers.Integral):
        return int(obj)
    if isinstance(obj, numbers.Real):
        value = float(obj)
        return value if math.isfinite(value) else None
    return obj
