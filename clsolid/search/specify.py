"""Histogram specification: a block's grey levels mapped by rank onto an exemplar's.

The blending search rules (``wl``, ``kopf``) set a voxel to a mean of matched values, and a
mean of two or more grey levels is nearer the middle than either: pass after pass the
block's histogram narrows and grey textures flatten. Specifying the block's histogram after
every pass (the step Heeger & Bergen alternate with their pyramid matching) gives the
voxels back the exemplar's contrast while keeping their order, so the next pass matches
neighbourhoods as contrasted as the exemplar's.
"""

from __future__ import annotations

import numpy as np


def specify_histogram(block: np.ndarray, exemplar: np.ndarray) -> np.ndarray:
    """*block* with its values replaced, rank for rank, by the quantiles of *exemplar*.

    The i-th smallest of n voxels takes the exemplar's quantile at (i + 1/2) / n; equal
    voxels are ranked by flat index (stable sort), so the result is deterministic. Returns
    a new float64 array of *block*'s shape.
    """
    flat = np.asarray(block, np.float64).ravel()
    order = np.argsort(flat, kind="stable")
    levels = np.sort(np.asarray(exemplar, np.float64).ravel())
    at = ((np.arange(flat.size) + 0.5) * levels.size / flat.size).astype(np.int64)
    out = np.empty_like(flat)
    out[order] = levels[np.minimum(at, levels.size - 1)]
    return out.reshape(np.shape(block))
