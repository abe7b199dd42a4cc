"""The multi-scale driver of the search methods (Urs thesis, §3.2.2-3.2.3): pyramids, starts,
passes over conflict-free sets, progress; the per-voxel rule is the method's (``wl.py``,
``kopf.py``, ``chenwang.py``).

The coarsest level starts as noise drawn from its exemplar's pixels; each finer level
starts from the coarser result up-sampled (or, with ``init="noise"``, from fresh noise,
Wei & Levoy's reading; Urs thesis, §3.2.3 does not say how a finer level starts), and the
coarser result also enters every neighbourhood as its parent square. One pass visits every
voxel once, conflict-free set by conflict-free set in a seeded order, so a pass equals a
sequential one in that order.
"""

from __future__ import annotations

import math
import time
from functools import partial
from typing import Any, Callable, NamedTuple

import numpy as np

from ..core.orders import visiting_order
from ..core.schedule import colour_set, set_count, set_order
from ..core.slices import insert_slices
from ..core.synthesis import SweepInfo
from ..errors import InputError
from ..exemplar import pooled
from ..phases import is_categorical
from . import chenwang, coherence, kopf, wl
from .features import centre_weights, exemplar_features, site_use, valid_sites
from .level import Level, LevelHistogram
from .codes import phase_codes
from .match import candidate_sets
from .params import SearchParams
from .palette import Palette, colour_pyramid
from .pyramid import gaussian_pyramid, upsampled
from .specify import specify_histogram

#: Each method's rule for one conflict-free set: ``update(level, vol, coarse, voxels) -> searches``.
UPDATES = {"wl": wl.update, "kopf": kopf.update, "chen-wang": chenwang.update}


class SearchOutput(NamedTuple):
    """What :func:`run_search` returns.

    Attributes
    ----------
    volume : ndarray
        The float64 block.
    timings : dict
        Per level: shape, sites, searches, seconds; and ``total_s``.
    site_use : ndarray or None
        With ``count_sites``: the position histogram (:func:`~clsolid.search.features.site_use`).
    source : ndarray or None
        ``chen-wang`` only: ``(Z, Y, X, 2)`` int64, the exemplar ``(row, column)`` each voxel's
        value was copied from.
    """

    volume: np.ndarray
    timings: dict
    site_use: np.ndarray | None
    source: np.ndarray | None


def level_shapes(shape: tuple[int, int, int], levels: int) -> list[tuple[int, int, int]]:
    """Volume shape at each level, finest first (halved, rounded down, per level)."""
    out = [tuple(int(n) for n in shape)]
    for _ in range(levels - 1):
        out.append(tuple(max(1, n // 2) for n in out[-1]))
    return out


def run_search(exemplar: np.ndarray | dict[str, np.ndarray], shape: tuple[int, int, int], params: SearchParams,
               seed: int,
               make_matcher: Callable[[np.ndarray], Any],
               progress: Callable[[SweepInfo], None] | None = None,
               count_sites: bool = False, categorical: bool | None = None,
               palette: np.ndarray | None = None) -> SearchOutput:
    """Grow a ``shape`` block from a 2D *exemplar* (float grey levels) with ``params.method``;
    or from one exemplar per view (a dict by view, ``params.view_names``' views): each view
    then searches its own (the exact search; ``wl`` and ``kopf``).

    *make_matcher(table, mismatch=n)* returns an object with ``best(queries, weights)`` (a
    :class:`~clsolid.search.match.CLMatcher` or :class:`~clsolid.search.match.ReferenceMatcher`;
    n the leading terms of a row that are phase codes). ``params.distance="auto"`` is
    resolved for the exemplar (:meth:`~clsolid.search.params.SearchParams.for_exemplar`).
    *progress* gets a :class:`~clsolid.core.synthesis.SweepInfo` after every pass (no
    temperatures: those fields are NaN). Returns a :class:`SearchOutput`; with *count_sites*
    its position histogram counts, for ``chen-wang``, each voxel's source, and for the others
    every voxel matched once more in every view. *categorical*: whether the exemplar's values
    are phases (:func:`clsolid.phases.is_categorical`; None: by their number alone). With a
    colour *palette* ``(P, 3)`` (CIELAB), the exemplar holds its labels, and so does the block
    (:mod:`clsolid.search.palette`).
    """
    per_view = isinstance(exemplar, dict)
    pool = pooled(exemplar)
    n_values = np.unique(pool).size
    categorical = is_categorical(n_values) if categorical is None else categorical
    params = params.for_exemplar(n_values, categorical, colour=palette is not None)
    k = params.neighborhood
    colour = None if palette is None else Palette(palette, k * k, math.sqrt(params.parent_weight))
    pyramid = gaussian_pyramid if colour is None else partial(colour_pyramid, lab=colour.lab)
    shapes = level_shapes(shape, params.scales)
    if min(shapes[-1]) < 2:
        raise InputError(f"shape={tuple(shape)} is too small for {params.scales} levels")
    if per_view:
        check_per_view(params, count_sites)
        view_pyr = {v: pyramid(exemplar[v], levels=params.scales) for v in params.view_names}
        # a level's pixels pooled over the views: its noise, histogram, values
        pyr = [pooled({v: p[level] for v, p in view_pyr.items()}) for level in range(params.scales)]
    else:
        view_pyr = {None: pyramid(exemplar, levels=params.scales)}
        pyr = view_pyr[None]
    timings: dict = {"levels": []}
    t0 = time.perf_counter()
    coarse, use, source, coh = None, None, None, None
    for level in range(params.scales - 1, -1, -1):
        t_level = time.perf_counter()
        with_parent = params.parent and level + 1 < params.scales
        # each view's sites in turn (one exemplar: its own), with their parents' terms
        tables = [exemplar_features(p[level], p[level + 1] if with_parent else None, k) for p in view_pyr.values()]
        table, centres = (np.concatenate(parts) for parts in zip(*tables))
        use_parent = with_parent
        parent_shape = view_pyr[next(iter(view_pyr))][level + 1].shape if with_parent else None
        vol = _start(pyr[level], shapes[level], coarse, params.init, seed, level)
        level_images = {v: p[level] for v, p in view_pyr.items()} if per_view else pyr[level]
        anchors = _anchor(params, vol, level_images, level, seed, shape)
        codes = phase_codes(pyr[0]) if params.distance == "weighted" and level == 0 else None
        searched = (_searched_table(table, codes, k, params.parent_weight) if colour is None
                    else colour.encode_terms(table))
        mismatch = 0 if codes is None else k * k
        starts = np.cumsum([0] + [t.shape[0] for t, _ in tables])
        view_matchers = [make_matcher(searched[a:b], mismatch=mismatch)
                         for a, b in zip(starts[:-1], starts[1:])] if per_view else None
        matcher = view_matchers[0] if per_view else make_matcher(searched, mismatch=mismatch)
        ctx = _level(params, pyr, level, parent_shape, table, searched, centres, vol, matcher, make_matcher, coh,
                     categorical, colour)
        ctx.codes = codes
        if per_view:
            ctx.view_matchers, ctx.view_starts = view_matchers, [int(a) for a in starts[:-1]]
        coh = ctx.coherence
        update = UPDATES[params.method]
        n_sets = set_count(shapes[level], k // 2)
        searches = 0
        t_iter = time.perf_counter()
        # the parent terms scaled as the table's (labels: once encoded, Palette.encode_terms)
        parent = (coarse if colour is not None else coarse * math.sqrt(params.parent_weight)) if use_parent else None
        for it in range(1, params.iterations + 1):
            ctx.seeding = it <= params.exact_passes and _search_at(params, level) == "coherence"
            ctx.exhaustive = ctx.seeding or _search_at(params, level) == "exact"
            if params.method == "kopf" and params.rule == "overlap":
                searches += kopf.overlap_pass(ctx, vol, parent)
            elif params.order != "sets":
                for v in visiting_order(shapes[level], params.order, np.random.default_rng([seed, level, it])):
                    searches += update(ctx, vol, parent, np.array([v]))
            else:
                for c in set_order(n_sets, seed, level, it):
                    searches += update(ctx, vol, parent, colour_set(shapes[level], n_sets, c))
            if params.specify and not ctx.phases:
                _specify(ctx, vol, pyr[level])
            if anchors is not None:
                _rewrite(ctx, vol, *anchors)
            if progress is not None:
                now = time.perf_counter()
                progress(_report(params, level, it, shapes[level], now - t_iter, now - t0, level_images, vol))
            t_iter = time.perf_counter()
        timings["levels"].append({"level": level, "shape": list(shapes[level]), "n_sites": int(table.shape[0]),
                                  "searches": searches, "seconds": time.perf_counter() - t_level})
        if count_sites and level == 0:
            sites = (ctx.sources.source if ctx.sources is not None
                     else wl.matches(ctx, vol, parent, np.arange(vol.size), ctx.w_first)[0])
            use = site_use(pyr[0].shape, parent_shape, k, sites)
        if ctx.sources is not None and level == 0:
            rows, cols = valid_sites(pyr[0].shape, parent_shape, k)
            source = np.stack([rows[ctx.sources.source], cols[ctx.sources.source]], axis=-1).reshape(vol.shape + (2,))
        coarse = vol
    timings["total_s"] = time.perf_counter() - t0
    return SearchOutput(coarse, timings, use, source)


def _level(params: SearchParams, pyr: list[np.ndarray], level: int, parent_shape: tuple[int, int] | None,
           table: np.ndarray, searched: np.ndarray, centres: np.ndarray, vol: np.ndarray, matcher: Any,
           make_matcher: Callable[..., Any], coarser: coherence.Coherence | None, categorical: bool,
           colour: Palette | None = None) -> Level:
    """One level's :class:`Level`: weights, and what the method and search keep: kopf's
    grey-level histogram, chen-wang's candidate sets and histograms, the coherence state
    (started from the *coarser* level's). *table* holds the sites' grey values, *searched*
    the rows the matcher compares (with phase codes, :mod:`clsolid.search.codes`; with a *colour*
    palette, the labels' colours, and the weights repeated for each channel)."""
    k, use_parent = params.neighborhood, parent_shape is not None
    w_first = centre_weights(k, use_parent, centre=False, causal=params.causal)
    w_again = centre_weights(k, use_parent, centre=True, causal=params.causal)
    if colour is not None:
        w_first, w_again = colour.weights(w_first), colour.weights(w_again)
    ctx = Level(params=params, matcher=matcher, centres=centres,
                patches=table[:, : k * k].astype(np.float64), values=np.unique(pyr[level]),
                w_first=w_first, w_again=w_again,
                span=(float(np.ptp(pyr[0])) or 1.0) if colour is None else colour.span, categorical=categorical,
                colour=colour)
    if params.method == "kopf":
        ctx.histogram = LevelHistogram(pyr[0], pyr[level], vol, params.view_names if params.histogram == "slice" else ())
    n_cw = params.candidates if params.method == "chen-wang" else 0
    n_coh = coherence.SIMILAR if params.search == "coherence" else 0
    if n_cw or n_coh:  # one search serves both: a smaller set is a larger one's first columns
        sets = candidate_sets(matcher, searched, max(n_cw, n_coh), ctx.w_again)
    if n_cw:
        ctx.sources = chenwang.Sources.start(sets[:, :n_cw], vol.size, len(params.view_names))
    if n_coh:
        rows, cols = valid_sites(pyr[level].shape, parent_shape, k)
        similar = sets[:, :n_coh]
        # A level that searches every site only records its matches (for the finer level's
        # start): it needs neither the phase candidates nor the sites' use.
        ranks = _search_at(params, level) == "coherence"
        if ranks and params.method == "kopf" and ctx.phases:  # for its phase balance
            similar = np.hstack([similar, coherence.phase_nearest(make_matcher, searched, centres, ctx.w_again,
                                                                  matcher.mismatch)])
        eps = kopf.EPS_REL * ctx.span if ranks and params.index_histogram else None  # Kopf's eps, as chen-wang's
        ctx.coherence = coherence.Coherence(rows, cols, pyr[level].shape, similar, vol.shape, params.view_names, eps)
        if coarser is not None:
            ctx.coherence.inherit(coarser)
    return ctx


def _searched_table(table: np.ndarray, codes: Any, k: int, parent_weight: float) -> np.ndarray:
    """The rows the matcher compares: the sites' features with the square's phases as
    *codes* (:mod:`clsolid.search.codes`; None: grey values) and the parent's terms scaled
    by sqrt(*parent_weight*), as the voxels' parent squares are, so that each weighs
    *parent_weight* in the distance while the kernels keep unit weights (a weight other
    than 1 would cost a multiply a term, a large share of the exhaustive search's time)."""
    out = table if codes is None else codes.encode_terms(table, k * k)
    if parent_weight != 1.0 and table.shape[1] > k * k:
        out = np.array(out, np.float64)
        out[:, k * k :] *= math.sqrt(parent_weight)
    return out


def _anchor(params: SearchParams, vol: np.ndarray, exemplar: np.ndarray | dict[str, np.ndarray], level: int,
            seed: int,
            shape: tuple[int, int, int]) -> tuple[np.ndarray, np.ndarray] | None:
    """Write a level's anchor slices (``insert_spacing``; :func:`clsolid.core.slices.insert_slices`)
    into its starting block *vol*. Returns ``(voxels, values)`` to write again after every
    pass; None at the finest level, whose slice voxels start from noise drawn from its
    exemplar's pixels (kept, they would come out as copies of the exemplar), or without
    anchors."""
    if not params.insert_spacing:
        return None
    mask = insert_slices(vol, exemplar, params, level, seed, shape)
    if level > 0:
        voxels = np.flatnonzero(mask)
        return voxels, vol.ravel()[voxels]
    # the coarser slice came up-sampled onto depth d + 1 as well: both start from noise
    mask |= np.roll(mask, 1, axis=0) | np.roll(mask, 1, axis=1) | np.roll(mask, 1, axis=2)
    voxels = np.flatnonzero(mask)
    np.put(vol, voxels, np.random.default_rng([seed, level, 0xA9C4]).choice(pooled(exemplar).ravel(),
                                                                           size=voxels.size))
    return None


def check_per_view(params: SearchParams, count_sites: bool = False) -> None:
    """Refuse what an exemplar per view cannot do: chen-wang's histograms over one exemplar's
    sites, the coherence search's candidates within one exemplar, a map of one exemplar's sites."""
    if params.method == "chen-wang":
        raise InputError("an exemplar per view: chen-wang keeps its histograms over one exemplar's sites; use "
                         "method 'kopf' or 'wl' (or 'ml')")
    if params.search != "exact":
        raise InputError(f"search={params.search!r} follows coherent candidates within one exemplar; with an "
                         "exemplar per view give search='exact'")
    if count_sites:
        raise InputError("site_map=True maps one exemplar's sites; with an exemplar per view there is none")


def _rewrite(ctx: Level, vol: np.ndarray, voxels: np.ndarray, values: np.ndarray) -> None:
    """Give *voxels* (flat indices) of the block *vol* their *values* (in place), and tell
    kopf's histogram: the anchor slices after every pass, or the whole specified block."""
    old = vol.ravel()[voxels]
    np.put(vol, voxels, values)
    if ctx.histogram is not None:
        ctx.histogram.replace(old, values, voxels)


def _specify(ctx: Level, vol: np.ndarray, exemplar: np.ndarray) -> None:
    """Give the block (in place) the level exemplar's histogram, and tell kopf's histogram."""
    _rewrite(ctx, vol, np.arange(vol.size), specify_histogram(vol, exemplar).ravel())


def _start(exemplar: np.ndarray, shape: tuple[int, int, int], coarse: np.ndarray | None, init: str,
           seed: int, level: int) -> np.ndarray:
    """A level's starting block: the coarser result up-sampled 2x2x2 (wrapping where a side is
    odd), or noise drawn from the level's exemplar pixels (always at the coarsest level)."""
    if coarse is None or init == "noise":
        return np.random.default_rng([seed, level]).choice(exemplar.ravel(), size=shape)
    return upsampled(coarse, shape)


#: Rough cost of a finer level against the one before it, by the two levels' searches: 8x the
#: voxels, and with the exhaustive search about 4x the sites (the coherence candidates do not
#: grow); a first level among the candidates after an exhaustive one, about 3x (measured).
_FINER_COST = {("exact", "exact"): 32.0, ("coherence", "coherence"): 8.0, ("exact", "coherence"): 3.0}


def _search_at(params: SearchParams, level: int) -> str:
    """How *level* searches: ``"coherence"`` at the ``coherence_levels`` finest under the
    coherence search, else ``"exact"``."""
    return "coherence" if params.search == "coherence" and level < params.coherence_levels else "exact"


def _report(params: SearchParams, level: int, it: int, shape: tuple[int, int, int], last_s: float,
            elapsed: float, exemplar: np.ndarray, vol: np.ndarray) -> SweepInfo:
    """The progress report after pass *it* of *level*, with a rough ETA from the last pass."""
    left, cost = (params.iterations - it) * last_s, last_s
    for finer in range(level - 1, -1, -1):
        cost *= _FINER_COST[_search_at(params, finer + 1), _search_at(params, finer)]
        left += params.iterations * cost
    return SweepInfo(scale=params.scales - level, n_scales=params.scales, shape=tuple(shape), sweep=it,
                     max_sweeps=params.iterations, temperature=math.nan, initial_temperature=math.nan,
                     target=math.nan, visited=int(np.prod(shape)), elapsed=elapsed, eta=left,
                     exemplar=exemplar, volume=lambda: vol.copy())
