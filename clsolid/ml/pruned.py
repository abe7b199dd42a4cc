"""The pruned likelihood: the Parzen sum over a few candidate sites.

The exact LCPDF of a voxel sums over every exemplar site; at clsolid's bandwidth nearly all
of it comes from the few sites whose neighbourhoods are nearest (``tools/prune_check.py``).
The pruned mode sums over k-coherence candidates instead:

* each voxel keeps, per view, its *source*: the site whose neighbourhood was nearest at its
  last visit (the exact kernel records it as well as the pruned one);
* a voxel's candidates in a view are the sources of itself and its 8 in-slice neighbours,
  each shifted back by that neighbour's offset, and the ``similar`` windows most like each
  (:func:`similar_windows`);
* sites are grouped by their whole window (centre and neighbours): identical windows, the
  flat squares of a binary exemplar above all, count as one candidate weighted by their
  number, so a candidate set never under-counts a repeated window;
* the rest of the sum is estimated from ``prune_sample`` sites drawn systematically (every
  (n / count)-th from a random start, :func:`sample_sites`), each weighted n / count: it
  carries a hot voxel's LCPDF, which spreads over the whole exemplar, and a voxel with no
  source yet (the first sweep of a scale) has only it;
* a voxel whose neighbourhood is hotter than ``prune_min_weight`` (mean ``(1 - t)^2``; 0
  by default: never) gets the exact sum, as does one with no source when there is no
  sample (:func:`needs_exact`).

Everything here is plain NumPy, shared by both back ends; :func:`candidate_keep` is the
float64 reference of the kernel's candidate set.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.philox import bounded, sample_tag, tag_sweep, voxel_words
from ..errors import InputError
from ..exemplar import window_grid
from .model import ScaleModel, view_offsets, wrapped_coords
from .params import VIEW_AXES, MLParams

_BLOCK = 1024  # windows per block of the similarity search, at most
_BLOCK_ENTRIES = 1 << 26  # distances per block (256 MB of float32): bounds its memory for any exemplar
#: Above this many distinct windows (more than a 256^2 exemplar can hold at 11 x 11) the similar
#: windows are searched in lists (:func:`_listed_similar`), not by brute force.
EXACT_SIMILAR_WINDOWS = 1 << 16
SIMILAR_PROBE = 8  # lists read per list
SIMILAR_AXES = 24  # principal axes the lists are made on
#: How far from a voxel the pruned sum reads sources: its 3 x 3 in-slice window in each view.
COHERENCE_REACH = 1


@dataclass
class WindowTable:
    """The exemplar's distinct windows at one scale, and how to reach them from a site.

    ``window_of`` ``(n_sites,)``: the distinct window of each site; ``first_site`` ``(U,)``:
    the lowest site holding each window; ``count`` ``(U,)``: how many sites hold it;
    ``source`` ``(U,)``: the source a voxel records when the window is its nearest
    (:func:`source_of_site` of its first site);
    ``similar`` ``(U, S)``: each window first, then its ``S - 1`` nearest other windows by
    neighbourhood distance (nearest first, lower index first on a tie); ``grid``: the sites'
    rows and columns (site index = row * columns + column).
    """

    window_of: np.ndarray
    first_site: np.ndarray
    count: np.ndarray
    source: np.ndarray
    similar: np.ndarray
    grid: tuple[int, int]

    @property
    def n_windows(self) -> int:
        return self.first_site.size


def similar_windows(neighbours: np.ndarray, count: int) -> np.ndarray:
    """``(U, count)`` int32: each row's index first, then its ``count - 1`` nearest other rows
    of *neighbours* ``(U, R)`` by squared distance (rounded to a whole number), lower index
    first on a tie.

    Up to :data:`EXACT_SIMILAR_WINDOWS` rows (every exemplar up to 256^2) the nearest among all
    rows, by brute force; above it, an O(U^2) search would take from minutes to hours, and the
    nearest are looked for among the rows of a few lists only (:func:`_listed_similar`).

    Grey levels and one-hot codes are whole numbers: while every distance is below 2^22 they
    are exact in float32 in any order of summation, which halves the work; else float64.
    """
    u = neighbours.shape[0]
    count = min(count, u)
    out = np.empty((u, count), np.int32)
    out[:, 0] = np.arange(u)
    if count == 1:
        return out
    x = neighbours.astype(np.float64)
    sq = np.sum(x * x, axis=1)
    if np.array_equal(x, np.rint(x)) and 4.0 * sq.max() < 2.0**24:
        x, sq = x.astype(np.float32), sq.astype(np.float32)
    if u > EXACT_SIMILAR_WINDOWS:
        out[:, 1:] = _listed_similar(x, sq, count - 1)
        return out
    block = max(1, min(_BLOCK, _BLOCK_ENTRIES // u))
    for lo in range(0, u, block):
        hi = min(u, lo + block)
        out[lo:hi, 1:] = _nearest_of(x, sq, np.arange(lo, hi), np.arange(u), count - 1)
    return out


def _nearest_of(x: np.ndarray, sq: np.ndarray, rows: np.ndarray, among: np.ndarray, k: int) -> np.ndarray:
    """``(rows.size, k)``: the *k* nearest of *among* (ascending) to each of *rows* of *x*, by
    rounded squared distance, lower index first on a tie, each row itself left out."""
    d = x[rows] @ x[among].T
    d *= -2.0
    d += sq[among][None, :]
    d += sq[rows][:, None]
    np.rint(d, out=d)
    at = np.minimum(np.searchsorted(among, rows), among.size - 1)
    r = np.flatnonzero(among[at] == rows)
    d[r, at[r]] = np.inf  # itself is first already
    return among[nearest_columns(d, k)]


def principal_axes(x: np.ndarray, dims: int, rows: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The mean ``(R,)`` of the rows of *x* ``(n, R)`` and their first *dims* principal axes
    ``(R, dims)`` (all R if fewer), found from every row or, with *rows*, from about that many
    taken at an even stride (the mean from every row either way)."""
    mean = x.mean(axis=0, dtype=np.float64)
    taken = x if rows is None else x[:: max(1, x.shape[0] // rows)]
    return mean, np.linalg.svd(taken - mean, full_matrices=False)[2][:dims].T


def _listed_similar(x: np.ndarray, sq: np.ndarray, k: int) -> np.ndarray:
    """``(U, k)``: each row's *k* nearest among the rows of the :data:`SIMILAR_PROBE` lists
    whose centres are nearest its own list's (its own first), the rows split into about
    sqrt(U) lists by k-means on their first :data:`SIMILAR_AXES` principal axes
    (:func:`site_lists`); an inverted file, as the projected search uses. Approximate: a near
    row in a list not read is missed. The cost falls from U^2 distances to about
    SIMILAR_PROBE * U^1.5."""
    mean, axes = principal_axes(x, SIMILAR_AXES, rows=20000)
    centres, list_of = site_lists(x @ axes - mean @ axes, n_site_lists(x.shape[0]))
    near = np.argsort(_squared_distances(centres, centres), axis=1, kind="stable")
    members = np.split(np.argsort(list_of, kind="stable"), np.cumsum(np.bincount(list_of))[:-1])
    out = np.empty((x.shape[0], k), np.int32)
    for lst, rows in enumerate(members):
        read, n = 0, 0
        while n <= k or read < SIMILAR_PROBE:  # enough rows to choose from, and the probe's lists read
            n += members[near[lst, read]].size
            read += 1
            if read == near.shape[1]:
                break
        among = np.sort(np.concatenate([members[j] for j in near[lst, :read]]))
        block = max(1, _BLOCK_ENTRIES // among.size)  # a crowded list's distances, a block at a time
        for lo in range(0, rows.size, block):
            out[rows[lo: lo + block]] = _nearest_of(x, sq, rows[lo: lo + block], among, k)
    return out


def nearest_columns(d: np.ndarray, k: int) -> np.ndarray:
    """``(rows, k)``: each row's *k* smallest columns of *d* ``(rows, n)``, nearest first, lower
    column first on a tie (``np.lexsort((columns, row))[:k]``, row by row), for ``k < n``.

    A full selection over every column (``argpartition``, or a sort where ties cross the cut)
    cost most of a large table's build: a binary exemplar's distances are small whole
    numbers, so ties are the rule. Instead each row's *k*-th smallest group minimum (columns
    in groups of up to 64) bounds its *k*-th smallest value from above: at least *k* columns
    lie at or below it, and only those few are sorted.
    """
    rows, n = d.shape
    group = max(1, min(64, n // (2 * k)))
    whole = n - n % group
    mins = d[:, :whole].reshape(rows, -1, group).min(axis=2)
    if whole < n:
        mins = np.column_stack([mins, d[:, whole:].min(axis=1)])
    bound = np.partition(mins, k - 1, axis=1)[:, k - 1]
    r, c = np.nonzero(d <= bound[:, None])
    order = np.lexsort((c, d[r, c], r))
    r, c = r[order], c[order]
    rank = np.arange(r.size) - np.searchsorted(r, r)
    return c[rank < k].reshape(rows, k)


def source_of_site(model: ScaleModel) -> np.ndarray:
    """``(n_sites,)`` int32: for each site, the lowest site with the same neighbourhood (centre
    excluded). A voxel's source is recorded so, the same whichever of equal sites a back end
    finds nearest."""
    first, inverse, _ = unique_rows(model.patches.T)
    return first[inverse].astype(np.int32)


def unique_rows(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The distinct rows of *rows* ``(n, m)``, numbered by their first occurrence: ``first``
    ``(U,)`` ascending (the lowest row holding each), ``inverse`` ``(n,)`` (each row's number)
    and ``count`` ``(U,)``.

    Rows are compared as bytes (-0.0 made 0.0 first), which sorts many times faster than
    ``np.unique(axis=0)``'s field-by-field comparison on a large exemplar's windows.
    """
    a = np.ascontiguousarray(rows)
    if a.dtype.kind == "f":
        a = a + a.dtype.type(0)  # -0.0 + 0.0 is 0.0: equal values, equal bytes
    keys = a.view(np.dtype((np.void, a.dtype.itemsize * a.shape[1]))).ravel()
    _, first, inverse, count = np.unique(keys, return_index=True, return_inverse=True, return_counts=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return first[order], rank[inverse.ravel()], count[order]


def window_table(model: ScaleModel, similar: int, sources: np.ndarray | None = None) -> WindowTable:
    """The distinct windows of *model*'s exemplar and their *similar* nearest (see :class:`WindowTable`);
    *sources*: :func:`source_of_site` of *model*, if the caller has it already."""
    rows = np.column_stack([model.centres, model.patches.T])
    first, window_of, count = unique_rows(rows)
    grid = window_grid(model.exemplar.shape, 2 * model.half + 1)
    first = first.astype(np.int32)
    return WindowTable(window_of=window_of.astype(np.int32), first_site=first, count=count.astype(np.int32),
                       source=(source_of_site(model) if sources is None else sources)[first],
                       similar=similar_windows(_coordinates(model, model.patches.T[first]), similar), grid=grid)


def _coordinates(model: ScaleModel, neighbours: np.ndarray) -> np.ndarray:
    """Rows whose squared distances order *neighbours* ``(U, R)`` as the model's distance does:
    themselves, or with ``model.mismatch`` their one-hot codes (squared distance: 2 x mismatches),
    each label's scaled by the square root of its cost with ``model.costs`` (squared distance:
    2 x the weighted mismatches), or a colour's channels (:meth:`ScaleModel.coded`)."""
    if model.channels > 1:
        return model.coded(neighbours.T).T.astype(np.float64)
    if not model.mismatch:
        return neighbours
    scale = np.ones(model.labels.size) if model.costs is None else np.sqrt(model.costs.astype(np.float64))
    return np.concatenate([(neighbours == v) * c for v, c in zip(model.labels, scale)], axis=1).astype(np.float64)


def coherence_offsets(model: ScaleModel, views: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The voxel and its 8 in-slice neighbours in each view: ``(views, 9, 3)`` (dz, dy, dx)
    offsets and ``(views, 9, 2)`` exemplar (row, column) offsets, paired as in
    :func:`clsolid.ml.model.view_offsets` (whose 3 x 3 window, centre put back, they are)."""
    vox = np.stack([np.insert(view_offsets(view, COHERENCE_REACH), 4, 0, axis=0) for view in views])
    ex = np.stack([vox[i][:, list(VIEW_AXES[view])] for i, view in enumerate(views)])
    return vox.astype(np.int32), ex.astype(np.int32)


def candidate_windows(table: WindowTable, sources: np.ndarray, shifts: np.ndarray) -> list[np.ndarray]:
    """Each voxel's candidate windows (sorted, distinct) in one view, float64-reference style.

    *sources* ``(m, 9)``: the source sites of each voxel's 3 x 3 in-slice neighbours (-1: none);
    *shifts* ``(9, 2)``: their exemplar offsets. A source shifted off the site grid is skipped.
    """
    rows, cols = table.grid
    out = []
    for src in sources:
        found = []
        for s, (dr, dc) in zip(src, shifts):
            if s < 0:
                continue
            r, c = s // cols - dr, s % cols - dc
            if 0 <= r < rows and 0 <= c < cols:
                found.append(table.similar[table.window_of[r * cols + c]])
        out.append(np.unique(np.concatenate(found)) if found else np.empty(0, np.int32))
    return out


def candidate_keep(table: WindowTable, sources: np.ndarray, shifts: np.ndarray) -> np.ndarray:
    """``(m, n_sites)`` bool: the sites whose window is among each voxel's candidates."""
    keep = np.zeros((sources.shape[0], table.window_of.size), bool)
    for i, windows in enumerate(candidate_windows(table, sources, shifts)):
        keep[i] = np.isin(table.window_of, windows)
    return keep


def sample_sites(seed: int, tag: int, voxels: np.ndarray, shape: tuple[int, int, int], view: int,
                 n_sites: int, count: int) -> np.ndarray:
    """``(m, min(count, n_sites))``: each voxel's systematic sample of the sites in one view,
    every ``n_sites / count``-th site from a random start (Philox word *view* of counter
    (x, y, z, :func:`~clsolid.core.philox.sample_tag` (tag)), keyed by *seed*)."""
    count = min(count, n_sites)
    z, y, x = np.unravel_index(voxels, shape)
    start = bounded(voxel_words(seed, z, y, x, sample_tag(tag))[:, view], n_sites)
    return (start[:, None] + (np.arange(count) * n_sites) // count) % n_sites


def term_weights(table: WindowTable, sources: np.ndarray, shifts: np.ndarray,
                 sampled: np.ndarray | None, extra: np.ndarray | None = None) -> np.ndarray:
    """``(m, n_sites)``: the factor of each site's term in the pruned sum (for
    :func:`clsolid.ml.reference.parzen`): 1 for the sites of the candidate windows (those of
    the sources, and *extra* ``(m, K)`` windows, -1 for none), and ``n_sites / count`` for the
    *sampled* ``(m, count)`` sites outside them (an unbiased estimate of the rest of the sum),
    0 for the others."""
    keep = candidate_keep(table, sources, shifts)
    if extra is not None:
        keep |= np.stack([np.isin(table.window_of, row[row >= 0]) for row in extra]).reshape(keep.shape)
    keep = keep.astype(np.float64)
    if sampled is None or sampled.shape[1] == 0:
        return keep
    rest = np.zeros_like(keep)
    np.put_along_axis(rest, sampled, keep.shape[1] / sampled.shape[1], axis=1)
    return np.where(keep > 0, keep, rest)


def nearest_source(table: WindowTable, a: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``(m,)``: the source recorded from the sites in the sum (*weights* > 0): the nearest
    by *a* ``(m, n_sites)``, the lowest window on a tie."""
    a = np.where(weights > 0, a, np.inf)
    tie = a == a.min(axis=1, keepdims=True)
    windows = np.where(tie, table.window_of[None, :], np.iinfo(np.int32).max).min(axis=1)
    return table.source[windows]


def mean_square_weight(temp: np.ndarray, neighbours: np.ndarray) -> np.ndarray:
    """``(m,)``: the mean of ``(1 - t)^2`` over each voxel's neighbours (flat indices ``(m, R)``)."""
    return np.mean((1.0 - temp.ravel()[neighbours].astype(np.float64)) ** 2, axis=1)


def needs_exact(own_sources: np.ndarray, weights: np.ndarray, min_weight: float, sample: int) -> np.ndarray:
    """``(m,)`` bool: voxels that get the exact sum: some view's mean squared weight
    (``(views, m)`` *weights*) below *min_weight*, or, without a *sample*, no source yet in
    some view (no candidates at all). *own_sources* is ``(views, m)``."""
    exact = np.any(weights < min_weight, axis=0)
    return exact | np.any(own_sources < 0, axis=0) if sample == 0 else exact


def projects(params: MLParams, tag: int) -> bool:
    """Whether the sweep of relaxation *tag* searches projected candidates: with
    ``prune_projected``, in the first ``prune_projected_sweeps`` sweeps of each scale (0: every
    sweep). Later sweeps find the nearest windows among the coherence candidates, whose
    sources the projected search left."""
    n = params.prune_projected_sweeps
    return bool(params.prune_projected) and (n == 0 or tag_sweep(tag) <= n)


def may_need_exact(params: MLParams) -> bool:
    """Whether any voxel can need the exact sum under *params* (:func:`needs_exact`): not with a
    sample and no weight threshold, the defaults, so a run need not look."""
    return params.prune_min_weight > 0 or params.n_sample == 0


class Pruning:
    """The pruned sum at one scale: its tables, and the float64 reference of which voxels get
    the exact sum and of each site's factor in the pruned one.

    *sources*: :func:`source_of_site` of *model*, if the caller has it already.
    """

    def __init__(self, model: ScaleModel, params: MLParams, sources: np.ndarray | None = None) -> None:
        self.model, self.params = model, params
        self.table = window_table(model, params.n_similar, sources)
        self.voxel_offsets, self.exemplar_offsets = coherence_offsets(model, params.view_names)
        self.projected = (ProjectedWindows.of(model, params.prune_projected, params.prune_projected_probe)
                          if params.prune_projected else None)

    def exact(self, temp: np.ndarray, src: np.ndarray, voxels: np.ndarray) -> np.ndarray:
        """``(m,)`` bool: which *voxels* get the exact sum, given the temperatures (with the
        parent terms' zeros after them, ``ScaleModel.with_parent``) and the sources ``(views,
        voxels)`` (:func:`needs_exact`)."""
        m, p = self.model, self.params
        if not may_need_exact(p):
            return np.zeros(np.size(voxels), bool)
        weights = np.stack([mean_square_weight(temp, m.neighbour_coords(voxels, v)) for v in range(m.offsets.shape[0])])
        return needs_exact(src[:, voxels], weights, p.prune_min_weight, p.n_sample)

    def weights(self, src: np.ndarray, seed: int, tag: int, voxels: np.ndarray, view: int,
                vol: np.ndarray | None = None) -> np.ndarray:
        """``(m, n_sites)``: each site's factor in the pruned sum of *voxels* in *view*
        (:func:`term_weights`), their candidates taken from the sources ``(views, voxels)`` and,
        with ``prune_projected``, the block *vol*'s projected nearest windows
        (:meth:`projected_windows`), their sample from the sweep's random stream (*seed*,
        relaxation *tag*)."""
        m = self.model
        nb = wrapped_coords(voxels, m.shape, self.voxel_offsets[view])
        sampled = sample_sites(seed, tag, voxels, m.shape, view, m.n_sites, self.params.n_sample)
        extra = self.projected_windows(vol, voxels, view) if projects(self.params, tag) else None
        return term_weights(self.table, src[view][nb], self.exemplar_offsets[view], sampled, extra)

    def projected_windows(self, vol: np.ndarray, voxels: np.ndarray, view: int) -> np.ndarray:
        """``(m, K)``: the windows of each voxel's ``prune_projected_k`` sites nearest by the
        projected distance among the sites it searches, nearest first, the lower site first on a
        tie (-1 past them)."""
        k = self.params.prune_projected_k
        d = self.projected.distances(self.model, vol, voxels, view)
        order = np.argsort(d, axis=1, kind="stable")[:, :k]
        out = np.where(np.isfinite(np.take_along_axis(d, order, axis=1)), self.table.window_of[order], -1)
        return np.pad(out, ((0, 0), (0, k - out.shape[1])), constant_values=-1)


@dataclass
class ProjectedWindows:
    """The exemplar's windows projected on their first principal axes: a cheaper distance
    to find a voxel's nearest sites by (squared differences only): the float64 reference of
    ``prune_projected``'s candidates (the kernel ``projected_nearest``), and what
    ``tools/prune_check.py --pca`` and ``tools/prune_error.py --pca`` measure.

    Each term is scaled as the window distance weighs it at t = 0 (the fall-off's weight);
    the neighbours' temperatures are left out of the search, which finds candidates whose
    exact terms, temperatures included, are then summed."""

    scale: np.ndarray  # (R,) each term's scale, the square root of its fall-off weight
    mean: np.ndarray  # (R,) the mean scaled window
    axes: np.ndarray  # (R, dims) the first principal axes
    sites: np.ndarray  # (n, dims) every site's projection
    centres: np.ndarray  # (C, dims) the centres of the site lists (one list, every site: C = 1)
    list_of: np.ndarray  # (n,) each site's list
    probe: int  # the lists searched, nearest centres first

    @classmethod
    def of(cls, model: ScaleModel, dims: int, probe: int = 0) -> "ProjectedWindows":
        """The first *dims* axes of *model*'s windows (all of them if it has fewer terms), and
        with *probe* > 0 the sites split into about sqrt(n) lists (:func:`site_lists`) of
        which a search reads the *probe* whose centres are nearest (0: one list, every site)."""
        if model.mismatch or model.channels > 1:
            raise InputError("prune_projected needs squared differences of grey levels (distance='squared' on a "
                             "grey exemplar); phases compared as names, and colours, have no projection")
        scale = np.ones(model.patches.shape[0]) if model.term_weight is None else np.sqrt(model.term_weight)
        windows = model.patches.T * scale
        mean, axes = principal_axes(windows, dims)
        sites = (windows - mean) @ axes
        if probe:
            centres, list_of = site_lists(sites, n_site_lists(sites.shape[0]))
        else:
            centres, list_of = sites.mean(axis=0, keepdims=True), np.zeros(sites.shape[0], np.int64)
        return cls(scale, mean, axes, sites, centres, list_of, min(max(probe, 1), centres.shape[0]))

    def project(self, model: ScaleModel, vol: np.ndarray, voxels: np.ndarray, view: int) -> np.ndarray:
        """``(m, dims)``: each voxel's window projected."""
        x = vol.ravel()[model.neighbour_coords(voxels, view)] * self.scale
        return (x - self.mean) @ self.axes

    def searched(self, q: np.ndarray) -> np.ndarray:
        """``(m, n)`` bool: the sites in each projection's *probe* lists with the nearest
        centres (the lower list on a tie)."""
        d = _squared_distances(q, self.centres)
        lists = np.argsort(d, axis=1, kind="stable")[:, : self.probe]
        chosen = np.zeros(d.shape, bool)
        np.put_along_axis(chosen, lists, True, axis=1)
        return chosen[:, self.list_of]

    def distances(self, model: ScaleModel, vol: np.ndarray, voxels: np.ndarray, view: int) -> np.ndarray:
        """``(m, n)``: each voxel's projected distance to every site it searches, inf to the rest."""
        q = self.project(model, vol, voxels, view)
        return np.where(self.searched(q), _squared_distances(q, self.sites), np.inf)

    def nearest(self, model: ScaleModel, vol: np.ndarray, voxels: np.ndarray, view: int, k: int) -> np.ndarray:
        """``(m, n)`` True on each voxel's *k* sites nearest by the projected distance (ties: any)."""
        return smallest(self.distances(model, vol, voxels, view), k)


def _squared_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``(m, n)``: squared distances between the rows of *a* and *b*."""
    return (a**2).sum(axis=1)[:, None] - 2.0 * a @ b.T + (b**2).sum(axis=1)[None, :]


def n_site_lists(n_sites: int) -> int:
    """How many lists :meth:`ProjectedWindows.of` asks :func:`site_lists` for: about sqrt(n)."""
    return max(1, round(math.sqrt(n_sites)))


def site_lists(sites: np.ndarray, count: int, iterations: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """``(centres (C, dims), list_of (n,))``: the projected *sites* split by k-means (Lloyd's
    *iterations* from *count* sites drawn with a fixed seed) into C <= *count* lists, none
    empty, each centre the mean of its list's sites. An inverted file: a search reads the
    few lists whose centres are nearest instead of every site."""
    n = sites.shape[0]
    count = min(count, n)
    centres = sites[np.sort(np.random.default_rng(0).choice(n, count, replace=False))]
    for _ in range(iterations + 1):
        list_of = np.concatenate([np.argmin(_squared_distances(sites[i: i + 4096], centres), axis=1)
                                  for i in range(0, n, 4096)])
        counts = np.bincount(list_of, minlength=centres.shape[0])
        sums = np.zeros_like(centres)
        np.add.at(sums, list_of, sites)
        kept = counts > 0
        centres = sums[kept] / counts[kept, None]
    remap = np.cumsum(kept) - 1
    return centres, remap[list_of]


def smallest(a: np.ndarray, k: int) -> np.ndarray:
    """``a.shape`` mask, True on the *k* smallest of each row (the whole row if k is larger)."""
    keep = np.zeros(a.shape, bool)
    k = min(k, a.shape[1])
    np.put_along_axis(keep, np.argpartition(a, k - 1, axis=1)[:, :k], True, axis=1)
    return keep
