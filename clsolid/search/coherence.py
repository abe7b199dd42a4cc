"""The accelerated search of the fixed-neighbourhood methods: k-coherence candidates
(Ashikhmin 2001; Tong et al. 2002), measured against the exact brute force.

A voxel's neighbours in a view plane were matched to exemplar sites; if the voxel's
neighbourhood continues theirs, its match is their site shifted back by the neighbour's
offset. For each of the 3 x 3 neighbours in the view plane (the voxel included) that
shifted site and its ``SIMILAR - 1`` nearest other sites (precomputed over the exemplar,
:func:`~clsolid.search.chenwang.candidate_sets`) are candidates; the voxel's match is the
candidate of least distance (the lowest site index on a tie), computed exactly on the
device. A voxel none of whose neighbours has a valid candidate is searched exhaustively.

Each voxel's last match in each view is kept. A finer level starts from the coarser
level's matches: the parent's site (r, c) becomes the site (2r + row parity, 2c + column
parity) of the voxel in that plane, where that is a valid site; the coarsest level's first
pass is exhaustive.
"""

from __future__ import annotations

import numpy as np

from ..core.views import VIEW_AXES
from .features import square_voxels
from .match import square_offsets

#: Side of the square of neighbours whose matches propose candidates.
NEIGHBOURS = 3
#: Sites proposed per neighbour: its shifted site and that site's nearest others.
SIMILAR = 4


class Coherence:
    """Each voxel's last match per view, and the candidates they propose.

    Parameters
    ----------
    rows, cols : ndarray
        Exemplar position of each site (:func:`~clsolid.search.features.valid_sites`).
    image_shape : tuple
        The level image's shape.
    similar : ndarray, ``(n_sites, SIMILAR)``
        Each site and its nearest others.
    volume_shape : tuple
        The level's block shape.
    views : tuple of str
        The constrained views.
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, image_shape: tuple[int, int], similar: np.ndarray,
                 volume_shape: tuple[int, int, int], views: tuple[str, ...]) -> None:
        self.rows, self.cols, self.similar = rows, cols, similar
        self.site_at = np.full(image_shape, -1, np.int64)
        self.site_at[rows, cols] = np.arange(rows.size)
        self.shape, self.views = tuple(volume_shape), views
        self.matched = np.full((len(views), int(np.prod(volume_shape))), -1, np.int64)
        # What a neighbour matched at site s proposes through its offset j: shift[s, j] (-1:
        # no valid site); its last row answers for an unknown match (s = -1), as similar's
        # last row answers for no site, so candidates() needs no masks.
        off = square_offsets(NEIGHBOURS)
        every = np.ones((rows.size, off.shape[0]), bool)
        shifted = self._site(rows[:, None] - off[:, 0], cols[:, None] - off[:, 1], every)
        self.shift = np.vstack([shifted, np.full((1, off.shape[0]), -1, np.int64)])
        self.similar_or_none = np.vstack([similar, np.full((1, similar.shape[1]), -1, similar.dtype)])

    def _site(self, r: np.ndarray, c: np.ndarray, known: np.ndarray) -> np.ndarray:
        """The site at (r, c), -1 where unknown or not a valid site."""
        h, w = self.site_at.shape
        ok = known & (r >= 0) & (r < h) & (c >= 0) & (c < w)
        out = np.full(r.shape, -1, np.int64)
        out[ok] = self.site_at[r[ok], c[ok]]
        return out

    def inherit(self, coarse: "Coherence") -> None:
        """Start from the coarser level's matches (its sites, doubled, plus each voxel's parity)."""
        pos = np.stack(np.unravel_index(np.arange(self.matched.shape[1]), self.shape))
        parent = np.ravel_multi_index(tuple((pos[a] // 2) % coarse.shape[a] for a in range(3)), coarse.shape)
        for i, view in enumerate(self.views):
            row_axis, col_axis = VIEW_AXES[view]
            s = coarse.matched[i, parent]
            known = s >= 0
            s = np.maximum(s, 0)
            r = 2 * coarse.rows[s] + pos[row_axis] % 2
            c = 2 * coarse.cols[s] + pos[col_axis] % 2
            self.matched[i] = self._site(r, c, known)

    def candidates(self, i: int, voxels: np.ndarray) -> np.ndarray:
        """``(m, NEIGHBOURS^2 * SIMILAR)`` candidate sites of *voxels* in view *i* (-1: none)."""
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
        least = dist.min(axis=1)
        site = np.where(dist == least[:, None], cand, np.iinfo(np.int64).max).min(axis=1)  # lowest index
        blind = ~np.isfinite(least)
        if blind.any():
            site[blind], least[blind] = matcher.best(queries[blind], weights)
        self.matched[i, voxels] = site
        return site, least
