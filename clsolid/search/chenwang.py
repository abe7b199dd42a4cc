"""NP_CW's rule (Urs thesis, §3.4.2-3.4.3, after Chen & Wang 2010): candidate sets, index and
position histograms, and the discrete solver that copies an exemplar pixel.

Analysis: every exemplar site gets a candidate set, itself and its ``candidates - 1``
nearest other sites (full neighbourhood, centre included;
:func:`~clsolid.search.match.candidate_sets`).

At a voxel, per view: the best match p of the neighbourhood (centre left out; exhaustive,
or k-coherence with ``search="coherence"``), then
among p's candidate set the candidate c of least ``(||N(v) - N(c)|| + eps) * w_index(c)``
(the L2 distance, the thesis's eq. 3.8), with

    w_index(c) = 1 + max(0, H_index(c) / phi - 1),    phi = views * voxels / sites,

H_index(c) the number of (voxel, view) choices that are c now, and eps Kopf's (a thousandth
of the exemplar's range): without it a perfect match (distance 0, as every flat square of a
binary exemplar is for the flat sites) could never give way to an equally perfect, less used
candidate, and the index histogram would do nothing there. Then each view's choice
c_i gets Kopf's robust weight (r = 0.8, as ``kopf``) divided by the position factor

    1 + max(0, H_position(c_i) / theta - 1),           theta = voxels / sites,

H_position(c) the number of voxels whose value is copied from c now; the prospective value
is ``v* = sum w_i value(c_i) / sum w_i`` and the voxel copies the value of the c_i nearest
to v* (the first view's on a tie): the discrete solver, so the block holds only exemplar
values. The voxel's source becomes that site.

The two histogram weights are a reconstruction of the thesis's (Urs thesis, §3.4.2-3.4.3:
its equations 3.9-3.10 are lost), ``1 + lambda * max(0, H - level)`` with lambda = 1, read with
the excess measured in units of the uniform level (``H / level - 1``), as ``kopf``'s
grey-level factor is (``s * (H_solid - H_exemplar)`` on fractions): on raw counts a site
used twice as often as uniform would weigh 1 + theta (about 80 at 64^3), on fractions 1 +
1/sites (no effect). This reading is not checked against Chen & Wang's own paper.

Both histograms are live counts over the current block (Urs thesis, §3.4.2-3.4.3 does not
say whether they are decremented or rebuilt): a voxel's old choice and source are taken out
when it gets new ones, set by set. Each level starts with no sources (its voxels are the
coarser level's values); the counts fill as its first pass visits the voxels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .kopf import EPS_REL, robust_weights
from .level import Level
from .usage import excess_factor, recount, spread_rank


@dataclass
class Sources:
    """``chen-wang``'s state at one level: candidate sets, each voxel's choice per view and
    source site (-1: none yet), and the live index and position histograms over sites."""

    candidates: np.ndarray
    chosen: np.ndarray
    source: np.ndarray
    index: np.ndarray
    position: np.ndarray

    @classmethod
    def start(cls, candidates: np.ndarray, n_voxels: int, n_views: int) -> "Sources":
        n_sites = candidates.shape[0]
        return cls(candidates=candidates, chosen=np.full((n_views, n_voxels), -1, np.int32),
                   source=np.full(n_voxels, -1, np.int32), index=np.zeros(n_sites, np.int64),
                   position=np.zeros(n_sites, np.int64))

    @property
    def phi(self) -> float:
        """The index histogram's uniform level: views x voxels / sites."""
        return self.chosen.size / self.index.size

    @property
    def theta(self) -> float:
        """The position histogram's uniform level: voxels / sites."""
        return self.source.size / self.position.size


#: Voxels of a set whose neighbourhoods are gathered at once (host memory: a set of a
#: large block would otherwise hold every voxel's neighbourhood in float64).
CHUNK = 1 << 16


def choose(level: Level, queries: np.ndarray, best: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Among each best match's candidate set, the candidate of least index-weighted distance
    (the first in the set on a tie). Returns ``(site (m,), distance (m,))``."""
    src = level.sources
    cand = src.candidates[best]  # (m, count)
    dist = level.matcher.distances(queries, cand, level.w_first).astype(np.float64)
    j = np.argmin(spread_rank(dist, EPS_REL * level.span, excess_factor(src.index[cand], src.phi)), axis=1)
    rows = np.arange(cand.shape[0])
    return cand[rows, j], dist[rows, j]


def solve(values: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The discrete solver: per column of ``values (views, m)``, the row whose value is
    nearest to the weighted mean (the first row on a tie)."""
    target = (weights * values).sum(axis=0) / weights.sum(axis=0)
    return np.argmin(np.abs(values - target), axis=0)


def update(level: Level, vol: np.ndarray, coarse: np.ndarray | None, voxels: np.ndarray) -> int:
    """One conflict-free set: search, choose among candidates, weigh, solve. Returns the
    searches made."""
    src = level.sources
    n_views = len(level.params.view_names)
    chosen = np.empty((n_views, voxels.size), np.int64)
    dist = np.empty((n_views, voxels.size))
    for i, view in enumerate(level.params.view_names):
        for lo in range(0, voxels.size, CHUNK):  # a view's choices all see the same index histogram
            part = slice(lo, lo + CHUNK)
            queries = level.queries(i, voxels[part], vol, coarse)
            best = level.best(i, voxels[part], vol, coarse, level.w_first, queries)[0]
            chosen[i, part], dist[i, part] = choose(level, queries, best)
        recount(src.index, src.chosen[i, voxels], chosen[i])  # the next view sees this one's choices
        src.chosen[i, voxels] = chosen[i]
    values = level.centres[chosen]
    weights = robust_weights(dist, level.span) / excess_factor(src.position[chosen], src.theta)
    best = solve(values, weights) if level.colour is None else level.colour.solve(values, weights)
    new = chosen[best, np.arange(voxels.size)]
    recount(src.position, src.source[voxels], new)
    src.source[voxels] = new
    vol.reshape(-1)[voxels] = level.centres[new]
    return chosen.size
