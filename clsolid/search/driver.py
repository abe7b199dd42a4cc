"""The multi-scale driver of the search methods (thesis_spec §1.1, §1.3): pyramids, starts,
passes over conflict-free sets, progress; the per-voxel rule is the method's (``wl.py``,
``kopf.py``).

The coarsest level starts as noise drawn from its exemplar's pixels; each finer level
starts from the coarser result up-sampled (or, with ``init="noise"``, from fresh noise,
Wei & Levoy's reading, thesis_spec §1.3 (a)), and the coarser result also enters every
neighbourhood as its parent square. One pass visits every voxel once, conflict-free set by
conflict-free set in a seeded order, so a pass equals a sequential one in that order.
"""

from __future__ import annotations

import math
import time
from typing import Any, Callable

import numpy as np

from ..core.orders import visiting_order
from ..core.schedule import colour_sets, set_order, split_by_colour
from ..core.synthesis import SweepInfo
from ..errors import InputError
from . import kopf, wl
from .features import centre_weights, exemplar_features, site_use
from .level import Level, LevelHistogram
from .params import SearchParams
from .pyramid import gaussian_pyramid

#: Each method's rule for one conflict-free set: ``update(level, vol, coarse, voxels) -> searches``.
UPDATES = {"wl": wl.update, "kopf": kopf.update}


def level_shapes(shape: tuple[int, int, int], levels: int) -> list[tuple[int, int, int]]:
    """Volume shape at each level, finest first (halved, rounded down, per level)."""
    out = [tuple(int(n) for n in shape)]
    for _ in range(levels - 1):
        out.append(tuple(max(1, n // 2) for n in out[-1]))
    return out


def run_search(exemplar: np.ndarray, shape: tuple[int, int, int], params: SearchParams, seed: int,
               make_matcher: Callable[[np.ndarray], Any],
               progress: Callable[[SweepInfo], None] | None = None,
               count_sites: bool = False) -> tuple[np.ndarray, dict, np.ndarray | None]:
    """Grow a ``shape`` block from a 2D *exemplar* (float grey levels) with ``params.method``.

    *make_matcher(table)* returns an object with ``best(queries, weights)`` (a
    :class:`~clsolid.search.match.CLMatcher` or :class:`~clsolid.search.match.ReferenceMatcher`).
    *progress* gets a :class:`~clsolid.core.synthesis.SweepInfo` after every pass (no
    temperatures: those fields are NaN). Returns the float64 volume, the timings and, with
    *count_sites*, the position histogram of the finished block
    (:func:`~clsolid.search.features.site_use`: every voxel matched once more in every view;
    else None).
    """
    k = params.neighborhood
    shapes = level_shapes(shape, params.scales)
    if min(shapes[-1]) < 2:
        raise InputError(f"shape={tuple(shape)} is too small for {params.scales} levels")
    pyr = gaussian_pyramid(exemplar, params.scales)
    timings: dict = {"levels": []}
    t0 = time.perf_counter()
    coarse, use = None, None
    for level in range(params.scales - 1, -1, -1):
        t_level = time.perf_counter()
        parent_img = pyr[level + 1] if params.parent and level + 1 < params.scales else None
        table, centres = exemplar_features(pyr[level], parent_img, k)
        use_parent = parent_img is not None
        vol = _start(pyr[level], shapes[level], coarse, params.init, seed, level)
        ctx = Level(params=params, matcher=make_matcher(table), centres=centres,
                    patches=table[:, : k * k].astype(np.float64), values=np.unique(pyr[level]),
                    w_first=centre_weights(k, use_parent, centre=False, causal=params.causal),
                    w_again=centre_weights(k, use_parent, centre=True, causal=params.causal),
                    histogram=LevelHistogram(pyr[0], pyr[level], vol,
                                             params.view_names if params.histogram == "slice" else ())
                    if params.method == "kopf" else None)
        update = UPDATES[params.method]
        colour, n_sets = colour_sets(shapes[level], k // 2)
        sets = split_by_colour(np.ones(shapes[level], bool), colour, n_sets)
        searches = 0
        t_iter = time.perf_counter()
        parent = coarse if use_parent else None
        for it in range(1, params.iterations + 1):
            if params.method == "kopf" and params.rule == "overlap":
                searches += kopf.overlap_pass(ctx, vol, parent)
            elif params.order != "sets":
                for v in visiting_order(shapes[level], params.order, np.random.default_rng([seed, level, it])):
                    searches += update(ctx, vol, parent, np.array([v]))
            else:
                for c in set_order(n_sets, seed, level, it):
                    searches += update(ctx, vol, parent, sets[c])
            if progress is not None:
                now = time.perf_counter()
                progress(_report(params, level, it, shapes[level], now - t_iter, now - t0, pyr[level], vol))
            t_iter = time.perf_counter()
        timings["levels"].append({"level": level, "shape": list(shapes[level]), "n_sites": int(table.shape[0]),
                                  "searches": searches, "seconds": time.perf_counter() - t_level})
        if count_sites and level == 0:
            sites = wl.matches(ctx, vol, parent, np.arange(vol.size), ctx.w_first)[0]
            use = site_use(pyr[0].shape, None if parent_img is None else parent_img.shape, k, sites)
        coarse = vol
    timings["total_s"] = time.perf_counter() - t0
    return coarse, timings, use


def _start(exemplar: np.ndarray, shape: tuple[int, int, int], coarse: np.ndarray | None, init: str,
           seed: int, level: int) -> np.ndarray:
    """A level's starting block: the coarser result up-sampled 2x2x2 (wrapping where a side is
    odd), or noise drawn from the level's exemplar pixels (always at the coarsest level)."""
    if coarse is None or init == "noise":
        return np.random.default_rng([seed, level]).choice(exemplar.ravel(), size=shape)
    idx = np.ix_(*[(np.arange(n) // 2) % m for n, m in zip(shape, coarse.shape)])
    return coarse[idx].astype(np.float64)


#: Rough cost of a finer level against the one before it: 8x the voxels, about 4x the sites.
_FINER_COST = 32.0


def _report(params: SearchParams, level: int, it: int, shape: tuple[int, int, int], last_s: float,
            elapsed: float, exemplar: np.ndarray, vol: np.ndarray) -> SweepInfo:
    """The progress report after pass *it* of *level*, with a rough ETA from the last pass."""
    left = (params.iterations - it) * last_s
    left += sum(params.iterations * last_s * _FINER_COST**j for j in range(1, level + 1))
    return SweepInfo(scale=params.scales - level, n_scales=params.scales, shape=tuple(shape), sweep=it,
                     max_sweeps=params.iterations, temperature=math.nan, initial_temperature=math.nan,
                     target=math.nan, visited=int(np.prod(shape)), elapsed=elapsed, eta=left,
                     exemplar=exemplar, volume=lambda: vol.copy())
