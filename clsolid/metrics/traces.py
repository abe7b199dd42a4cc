"""Traces of inserted slices: whether the slices at and beside the ``+in`` depths stand out.

A generator that writes exemplar slices into the block (clsolid's ``+in`` slices, the
search methods' anchors) leaves a trace where those slices, or the voxels next to them,
differ from the rest of the block: a plane with other phase fractions, less speckle, or a
jump to its neighbour, which another view shows as a straight line. Each statistic is
taken per slice along the view's depth axis, and the slices within ``reach`` of an inserted
depth are compared with the spread of all the others.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import InputError
from ._common import as_volume, check_views, is_integer_valued, view_slices
from .patches import patch_distance_by_slice
from .speckle import isolated_fraction_by_slice

#: Slices this far from an inserted depth count as traced: the slice itself and its neighbours.
DEFAULT_REACH = 1
#: The largest difference, in the other slices' standard deviations, between a traced group's
#: mean and theirs that is no trace.
DEFAULT_LIMIT = 1.0


def slice_profile(volume: Any, view: str, *, exemplar: Any = None, categorical: bool | None = None
                  ) -> dict[str, np.ndarray]:
    """Per-slice statistics of one view, each an ``(n_slices,)`` array in slice order.

    Parameters
    ----------
    volume : array_like, (Z, Y, X)
        Labels (phases) or grey levels.
    view : {"front", "right", "top"}
        Whose slices, as :func:`clsolid.metrics.view_slices` orients them.
    exemplar : array_like or None
        The exemplar: its labels are the phases counted, and for grey volumes its
        neighbour steps set the isolated threshold. None: the volume's own labels.
    categorical : bool or None
        Whether the values are phases. None: integer values, at most 16 of them.

    Returns
    -------
    dict
        ``"fraction <label>"`` for every phase (categorical), or ``"mean"`` and ``"std"``
        (grey); ``"isolated"``, the slice's isolated share
        (:func:`clsolid.metrics.isolated_fraction_by_slice`); ``"step"``, how much the
        slice differs from the next one (wrapping around): the share of pixels that differ
        (categorical) or their mean absolute difference over the volume's standard
        deviation (grey); with an exemplar, ``"patch"``, the slice's patch distance to it
        (:func:`clsolid.metrics.patch_distance` at full resolution and half, one slice at a
        time).
    """
    vol = as_volume(volume)
    (view,) = check_views((view,), "view")
    stack = view_slices(vol, view).astype(np.float64)
    ref = vol if exemplar is None else np.asarray(exemplar)
    values = np.unique(ref)
    if categorical is None:
        categorical = values.size <= 16 and is_integer_valued(values)
    out: dict[str, np.ndarray] = {}
    nxt = np.roll(stack, -1, axis=0)
    if categorical:
        if exemplar is not None and not np.isin(np.unique(vol), values).any():
            raise InputError("the volume holds none of the exemplar's values: give both as labels or both as values")
        for label in values:
            out[f"fraction {label}"] = np.mean(stack == label, axis=(1, 2))
        out["isolated"] = isolated_fraction_by_slice(vol, view)
        out["step"] = np.mean(stack != nxt, axis=(1, 2))
    else:
        out["mean"] = stack.mean(axis=(1, 2))
        out["std"] = stack.std(axis=(1, 2))
        out["isolated"] = isolated_fraction_by_slice(vol, view, exemplar=ref)  # the volume: its own steps
        scale = float(vol.std()) or 1.0
        out["step"] = np.mean(np.abs(stack - nxt), axis=(1, 2)) / scale
    if exemplar is not None:
        out["patch"] = patch_distance_by_slice(exemplar, stack, scales=(1, 2))
    return out


def depth_distance(n: int, depths: Any) -> np.ndarray:
    """``(n,)`` int: each slice's distance to the nearest of *depths* (on the torus of *n* slices)."""
    d = np.asarray(depths, int).ravel() % n
    gap = np.abs(np.arange(n)[:, None] - d[None, :])
    return np.minimum(gap, n - gap).min(axis=1)


def slice_traces(volume: Any, depths: Mapping[str, Any], *, exemplar: Any = None, categorical: bool | None = None,
                 reach: int = DEFAULT_REACH, limit: float = DEFAULT_LIMIT) -> dict[str, Any]:
    """Whether the slices at and beside inserted depths lie within the other slices' spread.

    The slices of a view are grouped by their distance k to the nearest inserted depth. For
    every statistic of :func:`slice_profile`, the mean of group k = 0 .. *reach* is compared
    with the slices farther away: its *effect* is the difference of the means over those
    slices' standard deviation. A trace is a group whose typical slice lies outside that
    spread (an absolute effect above *limit*); single slices scatter too much at small sizes to be judged
    one by one.

    Parameters
    ----------
    volume : array_like, (Z, Y, X)
        A label or grey volume.
    depths : mapping
        View name -> the depths of its inserted slices (:func:`clsolid.api.inserted_slices`);
        views with none are skipped.
    exemplar : array_like or None
        As for :func:`slice_profile`.
    categorical : bool or None
        As for :func:`slice_profile`.
    reach : int, default 1
        The groups compared: the inserted slices (k = 0) and their neighbours up to k = reach.
    limit : float, default 1.0
        The largest absolute effect that is no trace.

    Returns
    -------
    dict
        ``"views"``: per view, per statistic, ``groups`` (each group's mean, k = 0 ..
        reach), ``others`` (the farther slices' mean), ``spread`` (their standard
        deviation), ``effect`` (per group) and ``within`` (every absolute effect at most *limit*);
        ``"outside"``: ``"view statistic"`` for each statistic with a trace; ``"within"``:
        True when there is none.

    Raises
    ------
    InputError
        A view whose every slice is within *reach* of an inserted depth (nothing to compare).
    """
    vol = as_volume(volume)
    if not isinstance(depths, Mapping):
        raise InputError(f"depths must map view names to depths, not {type(depths).__name__}")
    if not isinstance(reach, (int, np.integer)) or isinstance(reach, bool) or reach < 0:
        raise InputError(f"reach must be an integer >= 0, not {reach!r}")
    views = check_views(tuple(depths), "depths", allow_empty=True)
    report: dict[str, Any] = {"views": {}, "outside": []}
    for view in views:
        d = np.asarray(depths[view], int).ravel()
        if d.size == 0:
            continue
        profile = slice_profile(vol, view, exemplar=exemplar, categorical=categorical)
        distance = depth_distance(next(iter(profile.values())).size, d)
        far = distance > reach
        if np.count_nonzero(far) < 2:
            raise InputError(f"fewer than 2 {view} slices lie farther than reach={reach} from an inserted depth: "
                             "nothing to compare")
        rows = {}
        for name, series in profile.items():
            others, spread = float(series[far].mean()), float(series[far].std())
            groups = [float(series[distance == k].mean()) for k in range(reach + 1) if np.any(distance == k)]
            effect = [(g - others) / spread if spread > 0 else (0.0 if g == others else float("inf")) for g in groups]
            within = bool(all(abs(e) <= limit for e in effect))
            rows[name] = {"groups": groups, "others": others, "spread": spread, "effect": effect, "within": within}
            if not within:
                report["outside"].append(f"{view} {name}")
        report["views"][view] = rows
    report["within"] = not report["outside"]
    return report
