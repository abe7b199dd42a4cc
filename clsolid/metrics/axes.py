"""How far features reach along each axis, and how a volume stretches them.

Two constrained views share the y axis: every pair of voxels one above the other lies in
both views' windows, while neighbours along x lie in the front view's only and neighbours
along z in the right view's. A volume can then keep features coherent along y and let them
fray along x and z, so that they come out taller than wide, in slices whose other
statistics score well. :func:`stretch` measures it: a view's height-to-width ratio of
correlation lengths in the volume, over the same ratio in the exemplar (1: the
exemplar's proportions).

A correlation length is the lag at which the normalised autocorrelation along an axis first
falls to one half (:func:`correlation_length`). On grey levels the autocorrelation is
Pearson's; on phases it is the chance that two voxels at that lag share a phase, above
the chance for two voxels drawn at random, so that it does not depend on the values the
phases are coded with (on two phases the two are equal).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.views import VIEW_AXES
from ..errors import InputError
from ._common import VIEWS, _as_real_array, check_views
from .phases import phase_values, to_labels

#: The level the autocorrelation falls to at a correlation length.
HALF = 0.5


def lag_correlations(data: Any, axis: int, max_lag: int, phases: Any = None) -> np.ndarray:
    """Normalised autocorrelation of an image or volume along one axis, lags 0..max_lag.

    Parameters
    ----------
    data : array_like
        A 2D image or 3D volume, read as it is (not periodic: lag l compares the
        ``n - l`` pairs that fit).
    axis : int
        The axis along which the lag runs.
    max_lag : int
        The largest lag, ``1 <= max_lag < data.shape[axis]``.
    phases : array_like or None
        The phase values of a categorical image: then ``rho(l) = (P_same(l) - sum f^2) /
        (1 - sum f^2)``, f the phase fractions; None for grey levels, Pearson's
        ``rho(l) = mean((a - m)(a' - m)) / var``.

    Returns
    -------
    numpy.ndarray
        ``(max_lag + 1,)`` float64, ``rho[0] = 1``; NaN everywhere on constant data.
    """
    a = _as_real_array(data, "data")
    if a.ndim not in (2, 3) or not -a.ndim <= axis < a.ndim:
        raise InputError(f"axis={axis!r} must be an axis of the {a.ndim}-D data (2-D or 3-D)")
    if not 1 <= int(max_lag) < a.shape[axis]:
        raise InputError(f"max_lag={max_lag!r} must be 1 to {a.shape[axis] - 1} along axis {axis}")
    n = a.shape[axis]

    lags = range(1, int(max_lag) + 1)

    def pairs(b: np.ndarray, lag: int) -> tuple[np.ndarray, np.ndarray]:
        return np.take(b, range(n - lag), axis), np.take(b, range(lag, n), axis)

    if phases is not None:
        f = np.array([np.mean(a == p) for p in np.asarray(phases)])
        base = float(np.sum(f * f))
        if base >= 1.0:
            return np.full(int(max_lag) + 1, np.nan)
        same = [np.mean(np.equal(*pairs(a, lag))) for lag in lags]
        return np.concatenate([[1.0], (np.array(same) - base) / (1.0 - base)])
    centred = a - a.mean()  # float64 already
    var = float(np.mean(centred * centred))
    if var == 0.0:
        return np.full(int(max_lag) + 1, np.nan)
    return np.array([1.0] + [float(np.mean(np.multiply(*pairs(centred, lag)))) / var for lag in lags])


def correlation_length(rho: Any, level: float = HALF) -> float:
    """The first lag at which *rho* (``rho[0] = 1``) falls to *level*, linearly interpolated
    between whole lags; ``inf`` when it stays above within the lags given, NaN for NaN."""
    r = np.asarray(rho, np.float64)
    if r.size < 2 or not np.all(np.isfinite(r)):
        return float("nan")
    below = np.flatnonzero(r <= level)
    if below.size == 0:
        return float("inf")
    k = int(below[0])
    return k - 1 + (r[k - 1] - level) / (r[k - 1] - r[k])


def correlation_lengths(data: Any, phases: Any = None) -> tuple[float, ...]:
    """:func:`correlation_length` along every axis of an image or volume, lags up to half
    of each side (``phases`` as for :func:`lag_correlations`)."""
    a = _as_real_array(data, "data")
    return tuple(correlation_length(lag_correlations(a, axis, max(1, n // 2), phases))
                 for axis, n in enumerate(a.shape))


def stretch(exemplar: Any, volume: Any, views: Any = ("front", "right")) -> dict[str, float]:
    """How much taller than wide a volume's features are in each view, against the exemplar.

    Parameters
    ----------
    exemplar : array_like, 2D
        The exemplar; categorical when it holds few values (``clsolid.metrics.phases``'s
        rule), then the phases' correlation is used for it and the volume alike.
    volume : array_like, (Z, Y, X)
        The volume; its views' rows and columns are as in :mod:`clsolid.metrics` (front:
        rows y, columns x; right: rows y, columns z; top: rows z, columns x).
    views : sequence of str, default ("front", "right")
        The views to measure, usually the constrained ones.

    Returns
    -------
    dict
        ``{view: (L_rows / L_cols in the volume) / (L_rows / L_cols in the exemplar)}``,
        L the correlation lengths (:func:`correlation_lengths`). 1: the exemplar's
        proportions; 2: features twice as tall, for their width, as the exemplar's; inf
        (0) where the volume's features are longer than half its side along the rows (the
        columns) and not across; NaN where nothing can be said (a constant image, an
        exemplar's length beyond half its side, or a volume's along both axes).
    """
    ex = _as_real_array(exemplar, "exemplar")
    vol = _as_real_array(volume, "volume")
    if ex.ndim != 2 or vol.ndim != 3:
        raise InputError(f"the exemplar must be 2-D and the volume 3-D, not {ex.ndim}-D and {vol.ndim}-D")
    views = check_views(views, "views")
    phases = phase_values(ex)
    if phases is not None:  # a volume between phases (a blend) counts for the nearest
        ex, vol, phases = to_labels(ex, phases), to_labels(vol, phases), np.arange(phases.size)
    rows, cols = correlation_lengths(ex, phases)
    lengths = correlation_lengths(vol, phases)
    out = {}
    for view in (v for v in VIEWS if v in views):
        r, c = VIEW_AXES[view]
        tall, wide = lengths[r], lengths[c]
        unknown = np.isnan(tall) or np.isnan(wide) or tall == wide == np.inf
        if unknown or not (np.isfinite(rows) and np.isfinite(cols)):
            out[view] = float("nan")
        elif tall == np.inf or wide == np.inf:  # features longer along the rows (columns) than half a side
            out[view] = float("inf") if tall == np.inf else 0.0
        else:
            out[view] = float((tall / wide) / (rows / cols))
    return out
