"""The accelerated search of the fixed-neighbourhood methods: k-coherence candidates
(Ashikhmin 2001; Tong et al. 2002), measured against the exact brute force.

A voxel's neighbours in a view plane were matched to exemplar sites; if the voxel's
neighbourhood continues theirs, its match is their site shifted back by the neighbour's
offset. For each of the 3 x 3 neighbours in the view plane (the voxel included) that
shifted site and its ``SIMILAR - 1`` nearest other sites (precomputed over the exemplar,
:func:`~clsolid.search.match.candidate_sets`) are candidates; the voxel's match is the
candidate of least distance (the lowest site index on a tie), computed exactly on the
device. A voxel none of whose neighbours has a valid candidate is searched exhaustively.

For kopf, on a level whose exemplar holds only phases (at most
:data:`~clsolid.search.params.MAX_PHASES` values), each site's set also holds the nearest
site centred on each phase (:func:`phase_nearest`). Without them a minority phase that the
neighbours' matches stop proposing never comes back: kopf's phase balance only chooses
among the phases the views' matches propose, so a minority phase dwindles. chen-wang, which
has no balance, does without them: with them its phase fractions drift further from the
exemplar's (docs/design.md#coherence-search).

Each voxel's last match in each view is kept. A finer level starts from the coarser
level's matches: the parent's site (r, c) becomes the site (2r + row parity, 2c + column
parity) of the voxel in that plane, where that is a valid site; the coarsest level's first
pass is exhaustive.

On an OpenCL matcher (:class:`~clsolid.search.match.CLMatcher`) :meth:`Coherence.search`
runs the whole of it for a set in one kernel (``coherence_best``, :class:`DeviceSearch`):
the voxels' neighbourhoods, their neighbours' proposals and the distances are gathered
on the device. :meth:`Coherence.best` is the same search with the gathering in NumPy (the
reference the kernel is tested against, and the path of the float64 matcher).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.launch import launch
from ..core.views import VIEW_AXES
from ..errors import DeviceMemoryError
from .block import DeviceBlock
from .features import square_voxels, voxel_features
from .match import LOCAL, CLMatcher, square_offsets
from .usage import excess_factor, recount, spread_rank

#: Side of the square of neighbours whose matches propose candidates.
NEIGHBOURS = 3
#: Sites proposed per neighbour: its shifted site and that site's nearest others.
SIMILAR = 4


def phase_nearest(make_matcher: Any, table: np.ndarray, centres: np.ndarray, weights: np.ndarray,
                  mismatch: int = 0) -> np.ndarray:
    """``(n_sites, n_phases)``: for each site (row of *table*), the nearest site whose centre
    is each phase of *centres* in turn (lowest index on a tie), by *weights*' distance.

    *make_matcher(rows, mismatch=n)* builds a matcher (``best(queries, weights)``) over a
    subset of the rows: one exhaustive search per phase, n_sites² distances in all.
    """
    out = []
    for phase in np.unique(centres):
        sites = np.flatnonzero(centres == phase)
        nearest, _ = make_matcher(table[sites], mismatch=mismatch).best(table, weights)
        out.append(sites[nearest])
    return np.stack(out, axis=1)


class Coherence:
    """Each voxel's last match per view, and the candidates they propose.

    Parameters
    ----------
    rows, cols : ndarray
        Exemplar position of each site (:func:`~clsolid.search.features.valid_sites`).
    image_shape : tuple
        The level image's shape.
    similar : ndarray, ``(n_sites, n)``
        Each site and its nearest others (:data:`SIMILAR` of them, then, for kopf on a
        level of phases, the nearest of each phase: :func:`phase_nearest`).
    volume_shape : tuple
        The level's block shape.
    views : tuple of str
        The constrained views.
    spread_eps : float or None
        None: each voxel's match is the candidate of least distance. A number: the
        candidate of least ``(sqrt(distance) + spread_eps) * excess_factor(usage)``
        (:func:`~clsolid.search.usage.excess_factor`; Chen & Wang's index histogram, as
        ``chen-wang`` chooses among its candidate sets), ``usage`` counting the voxels
        (of every view) whose last match is each site and its uniform level views x
        voxels / sites, so that no part of the exemplar is matched far more than its share
        (``index_histogram``, :class:`~clsolid.search.params.SearchParams`).
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, image_shape: tuple[int, int], similar: np.ndarray,
                 volume_shape: tuple[int, int, int], views: tuple[str, ...], spread_eps: float | None = None) -> None:
        self.rows, self.cols, self.similar, self.spread_eps = rows, cols, similar, spread_eps
        self.usage = None if spread_eps is None else np.zeros(rows.size, np.int64)
        self.site_at = np.full(image_shape, -1, np.int64)
        self.site_at[rows, cols] = np.arange(rows.size)
        self.shape, self.views = tuple(volume_shape), views
        self.matched = np.full((len(views), int(np.prod(volume_shape))), -1, np.int32)  # as the device's
        # What a neighbour matched at site s proposes through its offset j: shift[s, j] (-1:
        # no valid site); its last row answers for an unknown match (s = -1), as similar's
        # last row answers for no site, so candidates() needs no masks.
        off = square_offsets(NEIGHBOURS)
        every = np.ones((rows.size, off.shape[0]), bool)
        shifted = self._site(rows[:, None] - off[:, 0], cols[:, None] - off[:, 1], every)
        self.shift = np.vstack([shifted, np.full((1, off.shape[0]), -1, np.int64)])
        self.similar_or_none = np.vstack([similar, np.full((1, similar.shape[1]), -1, similar.dtype)])
        self._device: DeviceSearch | None = None

    def _site(self, r: np.ndarray, c: np.ndarray, known: np.ndarray) -> np.ndarray:
        """The site at (r, c), -1 where unknown or not a valid site."""
        h, w = self.site_at.shape
        ok = known & (r >= 0) & (r < h) & (c >= 0) & (c < w)
        out = np.full(r.shape, -1, np.int64)
        out[ok] = self.site_at[r[ok], c[ok]]
        return out

    def inherit(self, coarse: "Coherence") -> None:
        """Start from the coarser level's matches (its sites, doubled, plus each voxel's parity).

        A plane of the block at a time, so that no whole-block index array is made."""
        depth, n_rows, n_cols = self.shape
        y, x = np.ogrid[:n_rows, :n_cols]
        parent_yx = ((y // 2) % coarse.shape[1]) * coarse.shape[2] + (x // 2) % coarse.shape[2]
        plane = n_rows * n_cols
        for z in range(depth):
            parity = (z % 2, y % 2, x % 2)  # each voxel's place within its parent, per axis
            parent = (((z // 2) % coarse.shape[0]) * coarse.shape[1] * coarse.shape[2] + parent_yx).ravel()
            for i, view in enumerate(self.views):
                row_axis, col_axis = VIEW_AXES[view]
                s = coarse.matched[i, parent]
                known = s >= 0
                s = np.maximum(s, 0)
                r = 2 * coarse.rows[s] + np.broadcast_to(parity[row_axis], (n_rows, n_cols)).ravel()
                c = 2 * coarse.cols[s] + np.broadcast_to(parity[col_axis], (n_rows, n_cols)).ravel()
                self.matched[i, z * plane:(z + 1) * plane] = self._site(r, c, known)
        self.count_usage()

    def count_usage(self) -> None:
        """Count :attr:`usage` anew from every view's matches (after :attr:`matched` was set wholesale)."""
        if self.usage is not None:
            known = self.matched[self.matched >= 0]
            self.usage = np.bincount(known, minlength=self.rows.size).astype(np.int64)

    def assign(self, i: int, voxels: np.ndarray, sites: np.ndarray) -> None:
        """Take *sites* as the matches of *voxels* in view *i*, and count them in :attr:`usage`."""
        if self.usage is not None:
            recount(self.usage, self.matched[i, voxels], np.asarray(sites))
        self.matched[i, voxels] = sites

    def record(self, i: int, voxels: np.ndarray, sites: np.ndarray) -> None:
        """Take *sites* as the matches of *voxels* in view *i* (found by another search)."""
        self.assign(i, voxels, sites)
        if self._device is not None:
            self._device._sent[i] = False  # the device's copy is stale

    def excess(self) -> np.ndarray | None:
        """Each site's index-histogram factor (float64, ``(n_sites,)``), None without ``spread_eps``."""
        if self.usage is None:
            return None
        return excess_factor(self.usage, self.matched.size / self.usage.size)

    def scores(self, cand: np.ndarray, dist: np.ndarray) -> np.ndarray:
        """What the candidates *cand* at distances *dist* are ranked by (least first; inf where none)."""
        if self.usage is None:
            return dist
        return spread_rank(dist, self.spread_eps, self.excess()[np.maximum(cand, 0)])

    def candidates(self, i: int, voxels: np.ndarray) -> np.ndarray:
        """``(m, NEIGHBOURS^2 * n)`` candidate sites of *voxels* in view *i* (-1: none), n the
        width of each site's set (:attr:`similar`)."""
        row_axis, col_axis = VIEW_AXES[self.views[i]]
        pos = np.stack(np.unravel_index(voxels, self.shape))
        s = self.matched[i, square_voxels(self.shape, pos, row_axis, col_axis, NEIGHBOURS)]  # (m, n): their matches
        shifted = self.shift[s, np.arange(s.shape[1])]  # s = -1 reads the last row: -1
        return self.similar_or_none[shifted].reshape(voxels.size, s.shape[1] * self.similar.shape[1])

    def best(self, matcher, i: int, voxels: np.ndarray, queries: np.ndarray,
             weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The best candidate of each voxel in view *i* (an exhaustive search where there is
        none), recorded as the voxel's match. Returns ``(site (m,), distance (m,))``."""
        cand = self.candidates(i, voxels)
        dist = matcher.distances(queries, cand, weights)
        score = self.scores(cand, dist)
        top = score.min(axis=1)
        site = np.where(score == top[:, None], cand, np.iinfo(np.int64).max).min(axis=1)  # lowest index
        blind = ~np.isfinite(top)
        least = np.where(blind, np.inf, dist[np.arange(cand.shape[0]), np.argmax(cand == site[:, None], axis=1)])
        if blind.any():
            site[blind], least[blind] = matcher.best(queries[blind], weights)
        self.assign(i, voxels, site)
        return site, least.astype(dist.dtype)

    def search(self, matcher: Any, i: int, voxels: np.ndarray, vol: np.ndarray, coarse: np.ndarray | None,
               k: int, weights: np.ndarray, queries: np.ndarray | None = None,
               block: DeviceBlock | None = None) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`best` for *voxels* of the block *vol* (*coarse*: the parent level, k: the
        square's side): in one kernel on an OpenCL *matcher* (the block on its device:
        *block*, made here if not given), else with *queries* (gathered here if not given)."""
        if isinstance(matcher, CLMatcher):
            if self._device is None:
                self._device = DeviceSearch(self, matcher, block)
            return self._device.best(i, voxels, vol, coarse, k, weights)
        if queries is None:
            queries = voxel_features(vol, coarse, voxels, self.views[i], k)
        return self.best(matcher, i, voxels, queries, weights)


class DeviceSearch:
    """:meth:`Coherence.best` in one kernel on *matcher*'s device (``coherence_best``).

    The host's :attr:`Coherence.matched` stays the truth; the device keeps a copy per view,
    which the kernel updates as the host does, and which is sent again after the host
    changed it otherwise (an exhaustive search of voxels without candidates). The kernel
    reads one copy and writes the next (a spare, swapped in after), so that every voxel
    reads its neighbours' matches as the call began even where the voxels are neighbours
    (Kopf's overlap rule: with the matches updated in place, the result would depend on the
    order the device runs the voxels in, and one seed would not give one block).
    The block reaches the device through *block* (:class:`~clsolid.search.block.DeviceBlock`,
    shared with the level's exhaustive searches; one of its own if not given).
    """

    def __init__(self, coh: Coherence, matcher: CLMatcher, block: DeviceBlock | None = None) -> None:
        import pyopencl as cl

        assert NEIGHBOURS == 3  # the kernel reads the 3 x 3 neighbours
        self.coh, self.matcher = coh, matcher
        self.block = block if block is not None else DeviceBlock(matcher)
        ctx, mf = matcher.device.context, cl.mem_flags
        n_voxels = coh.matched.shape[1]
        if 4 * n_voxels > matcher.device.max_alloc:  # each view's matches, int32
            raise DeviceMemoryError("coherence matches", 4 * n_voxels, matcher.device.max_alloc)

        def table(a: np.ndarray):
            return cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(a, np.int32))

        self._shift, self._similar = table(coh.shift), table(coh.similar_or_none)
        self._matched = [cl.Buffer(ctx, mf.READ_WRITE, 4 * n_voxels) for _ in coh.views]
        self._spare = cl.Buffer(ctx, mf.READ_WRITE, 4 * n_voxels)
        self._sent = [False] * len(coh.views)
        self._excess = cl.Buffer(ctx, mf.READ_ONLY, 4 * coh.rows.size)  # read only with the index histogram
        self._room, self._sites, self._dists = 0, None, None

    def _buffers(self, m: int) -> None:
        """Room for the results of a set of *m* voxels."""
        import pyopencl as cl

        if m > self._room:
            ctx, mf = self.matcher.device.context, cl.mem_flags
            self._room = m
            self._sites = cl.Buffer(ctx, mf.WRITE_ONLY, 4 * m)
            self._dists = cl.Buffer(ctx, mf.WRITE_ONLY, 4 * m)

    def best(self, i: int, voxels: np.ndarray, vol: np.ndarray, coarse: np.ndarray | None, k: int,
             weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`Coherence.best` for *voxels* (a conflict-free set) of the block *vol*,
        *coarse* its parent level, *k* the square's side. Returns ``(site (m,), distance (m,))``."""
        import pyopencl as cl

        coh, matcher, queue = self.coh, self.matcher, self.matcher.device.queue
        m = voxels.size
        if m == 0:
            return np.empty(0, np.int64), np.empty(0, np.float32)
        lay = matcher.layout(weights)
        spread = coh.usage is not None
        kernel = matcher.kernel("coherence_best", KSIDE=k, PARENT=int(coarse is not None),
                                SIMILAR=coh.similar.shape[1], SPREAD=int(spread))
        self._buffers(m)
        if spread:  # the factors as the set begins (a set's voxels do not see each other's matches)
            cl.enqueue_copy(queue, self._excess, np.ascontiguousarray(coh.excess(), np.float32))
        if not self._sent[i]:
            cl.enqueue_copy(queue, self._matched[i], np.ascontiguousarray(coh.matched[i], np.int32))
            self._sent[i] = True
        leading, voxels_buf = self.block.send(vol, coarse, voxels)
        row_axis, col_axis = VIEW_AXES[coh.views[i]]
        cl.enqueue_copy(queue, self._spare, self._matched[i])
        launch(matcher.device, kernel, m, LOCAL, *leading, np.int32(row_axis), np.int32(col_axis),
               voxels_buf, np.int32(m),
               self._matched[i], self._spare, self._shift, self._similar, np.int32(coh.similar.shape[0]), lay.places,
               lay.rows, lay.weights, self._excess, np.float32(coh.spread_eps or 0.0), self._sites, self._dists)
        self._matched[i], self._spare = self._spare, self._matched[i]
        site, least = np.empty(m, np.int32), np.empty(m, np.float32)
        cl.enqueue_copy(queue, site, self._sites)
        cl.enqueue_copy(queue, least, self._dists)
        site = site.astype(np.int64)
        blind = site < 0
        if blind.any():  # no neighbour proposes a site: an exhaustive search, on the host's copy too
            site[blind], least[blind] = self.block.best(coh.views[i], voxels[blind], vol, coarse, k, weights)
            self._sent[i] = False
        coh.assign(i, voxels, site)
        return site, least
