"""NP_WL's rule (Urs thesis, §3.2.6.1): each view's best match, averaged, re-searched.

At a voxel, each constrained view's neighbourhood (centre left out) is matched exactly
against every exemplar site; the voxel takes the mean of the matched centre values; then,
up to ``inner - 1`` more times, the search is repeated with the centre term included,
until every view's match is unchanged.
"""

from __future__ import annotations

import numpy as np

from .level import Level


def matches(level: Level, vol: np.ndarray, coarse: np.ndarray | None, voxels: np.ndarray,
            weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each view's best site and its weighted squared distance, ``(views, m)`` each."""
    found = [level.best(i, voxels, vol, coarse, weights) for i in range(len(level.params.view_names))]
    return np.stack([f[0] for f in found]), np.stack([f[1] for f in found]).astype(np.float64)


def update(level: Level, vol: np.ndarray, coarse: np.ndarray | None, voxels: np.ndarray) -> int:
    """One conflict-free set: search, average, and the inner repetition. Returns the searches made."""
    flat = vol.reshape(-1)
    sites = matches(level, vol, coarse, voxels, level.w_first)[0]  # (views, m)
    flat[voxels] = level.blend(level.centres[sites])
    searches = sites.size
    todo = np.arange(voxels.size)
    for _ in range(level.params.inner - 1):
        again = matches(level, vol, coarse, voxels[todo], level.w_again)[0]
        searches += again.size
        moved = np.any(again != sites[:, todo], axis=0)
        if not moved.any():
            break
        todo = todo[moved]
        sites[:, todo] = again[:, moved]
        flat[voxels[todo]] = level.blend(level.centres[sites[:, todo]])
    return searches
