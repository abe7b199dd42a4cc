"""NP_K's rule (thesis_spec §1.6.2): Kopf et al.'s robust weights and grey-level histogram
re-weighting, on each view's best match.

At a voxel, each view's neighbourhood (centre left out) is matched exactly; the match
gets the IRLS weight of the robust norm ``||N(v) - N(p)||^r`` with r = 0.8, that is
``w = (||N(v) - N(p)|| + eps)^(r - 2)`` with ``||.||`` the L2 norm (Kopf's, the square
root of the SSD) and ``eps`` a thousandth of the exemplar's range (a perfect match would
have an infinite weight); then ``w / (1 + s * max(0, H_solid(g) - H_exemplar(g)))`` at the
match's grey level g, with H the histograms as fractions of the block and of the level's
exemplar, and s the number of bins (the spec's scale: relative to the uniform level; with
plain fractions the correction is negligible, with counts overwhelming). The voxel takes
the weighted mean of the matches' centre values; on a categorical exemplar (at most 8
values) the value with the largest total weight instead, so a voxel is always a phase.
The block's histogram follows every voxel that changes, set by set (the thesis updates it
voxel by voxel; a set's voxels see the histogram as the set began).
"""

from __future__ import annotations

import numpy as np

from .level import Level
from .wl import matches

#: The robust norm's exponent ("as indicated by [Kwa05]").
R = 0.8
#: ``eps`` in the weight, relative to the exemplar's range.
EPS_REL = 1e-3
#: An exemplar with at most this many values is categorical: its voxels take a phase, never a blend.
MAX_PHASES = 8


def update(level: Level, vol: np.ndarray, coarse: np.ndarray | None, voxels: np.ndarray) -> int:
    """One conflict-free set: search, weigh, re-weigh by the histogram, combine. Returns the searches made."""
    hist = level.histogram
    sites, ssd = matches(level, vol, coarse, voxels, level.w_first)
    values = level.centres[sites]  # (views, m)
    span = float(hist.values[-1] - hist.values[0]) or 1.0
    w = (np.sqrt(np.maximum(ssd, 0.0)) + EPS_REL * span) ** (R - 2.0)
    g = hist.bin(values).reshape(values.shape)
    w /= 1.0 + hist.values.size * np.maximum(0.0, hist.volume[g] - hist.exemplar[g])
    flat = vol.reshape(-1)
    old = flat[voxels].copy()
    if hist.values.size <= MAX_PHASES:
        new = vote(values, w)
    else:
        new = (w * values).sum(axis=0) / w.sum(axis=0)
    flat[voxels] = new
    hist.replace(old, new)
    return sites.size


def vote(values: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Per column, the value of ``values (views, m)`` with the largest total weight (the
    first view's on a tie)."""
    support = np.stack([(weights * (values == values[j])).sum(axis=0) for j in range(values.shape[0])])
    return values[np.argmax(support, axis=0), np.arange(values.shape[1])]
