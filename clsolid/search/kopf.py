"""NP_K's rule (Urs thesis, §3.3-3.4.1): Kopf et al.'s robust weights and grey-level histogram
re-weighting, on each view's best match.

At a voxel, each view's neighbourhood (centre left out) is matched exactly; the match
gets the IRLS weight of the robust norm ``||N(v) - N(p)||^r`` with r = 0.8, that is
``w = (||N(v) - N(p)|| + eps)^(r - 2)`` with ``||.||`` the L2 norm (Kopf's, the square
root of the SSD) and ``eps`` a thousandth of the exemplar's range (a perfect match would
have an infinite weight); then ``w / (1 + s * max(0, H_solid(g) - H_exemplar(g)))`` at the
match's grey level g, with H the histograms as fractions of the block and of the level's
exemplar, and s the number of bins (a scale relative to the uniform level: with plain
fractions the correction is negligible, with counts overwhelming). The voxel takes
the weighted mean of the matches' centre values; on a categorical exemplar (at most 8
values) the value with the largest total weight instead, so a voxel is always a phase.
The block's histogram follows every voxel that changes, set by set (the thesis updates it
voxel by voxel; a set's voxels see the histogram as the set began).

``rule="overlap"`` is Kopf et al.'s own rule instead (:func:`overlap_pass`): every voxel's
neighbourhood in every view is matched against the block as it stands, then every voxel
takes the weighted mean (or, categorical, the weighted vote) of the values that all the
matched squares overlapping it propose for it: k*k proposals per view, not one. Each
proposal carries its square's robust weight and the histogram factor of the value it
proposes. The whole block is matched, then updated (Kopf's alternation of a search step
and an optimisation step), so a pass does not depend on a visiting order.
"""

from __future__ import annotations

import numpy as np

from ..core.views import VIEW_AXES
from ..balance import project_bias, sweep_target
from .level import Level, vote
from .match import square_offsets
from .wl import matches

#: The robust norm's exponent ("as indicated by [Kwa05]").
R = 0.8
#: ``eps`` in the weight, relative to the exemplar's range.
EPS_REL = 1e-3
#: Scale of the log supports in the balanced vote's fit (:func:`vote_balanced`).
SHARPNESS = 16.0


def robust_norm(ssd: np.ndarray, span: float) -> np.ndarray:
    """``||.|| + eps`` of squared distances *ssd*: the L2 norm, kept off 0 by eps (a
    thousandth of the exemplar's range *span*)."""
    return np.sqrt(np.maximum(ssd, 0.0)) + EPS_REL * span


def robust_weights(ssd: np.ndarray, span: float) -> np.ndarray:
    """Kopf's IRLS weight ``(||.|| + eps)^(r - 2)`` of squared distances *ssd*."""
    return robust_norm(ssd, span) ** (R - 2.0)


def histogram_factor(level: Level, bins: np.ndarray, view: str | None = None,
                     voxels: np.ndarray | None = None) -> np.ndarray:
    """``1 / (1 + s * max(0, H_solid(g) - H_exemplar(g)))`` for each proposed value's bin g
    (*bins*, from ``level.histogram.bin``).

    H_solid is the whole block's histogram, or with ``histogram="slice"`` that of the slice
    of *view* holding each of *voxels* (one per bin).
    """
    hist = level.histogram
    if level.params.histogram == "slice":
        solid = np.take_along_axis(hist.slice_fractions(view, voxels), bins.reshape(-1, 1), axis=1).reshape(bins.shape)
    else:
        solid = hist.volume[bins]
    return 1.0 / (1.0 + hist.values.size * np.maximum(0.0, solid - hist.exemplar[bins]))


def update(level: Level, vol: np.ndarray, coarse: np.ndarray | None, voxels: np.ndarray) -> int:
    """One conflict-free set: search, weigh, re-weigh by the histogram, combine. Returns the searches made."""
    hist = level.histogram
    sites, ssd = matches(level, vol, coarse, voxels, level.w_first)
    values = level.centres[sites]  # (views, m)
    bins = level.centre_bins[sites]
    factor = np.stack([histogram_factor(level, bins[i], view, voxels)
                       for i, view in enumerate(level.params.view_names)])
    w = robust_weights(ssd, level.span) * factor
    flat = vol.reshape(-1)
    old = flat[voxels].copy()
    if level.categorical:
        # the balance counts phases: only at a level whose exemplar holds nothing but phases
        balanced = level.params.balance and level.phases
        new = balanced_set_vote(level, values, w, old) if balanced else vote(values, w)
    else:
        new = level.blend(values, w)
    flat[voxels] = new
    hist.replace(old, new, voxels)
    return sites.size


def balanced_set_vote(level: Level, values: np.ndarray, weights: np.ndarray, old: np.ndarray) -> np.ndarray:
    """The weighted vote of one conflict-free set, biased toward the exemplar's phase fractions.

    The set's voxels aim at the fractions that bring the whole block (the other voxels as they
    are, *old* the set's current values) to the exemplar's, ``balance`` of the way
    (:func:`clsolid.balance.sweep_target`); :func:`vote_balanced` meets them where the
    views' matches disagree. A phase no view proposes for a voxel stays out of its vote.
    """
    hist = level.histogram
    phases = hist.values
    support = np.stack([(weights * (values == p)).sum(axis=0) for p in phases])
    fixed = hist.counts - np.bincount(hist.bin(old), minlength=phases.size)
    unbiased = support / np.maximum(support.sum(axis=0), np.finfo(np.float64).tiny)
    target = sweep_target(hist.exemplar, fixed, old.size, unbiased.mean(axis=1), level.params.balance)
    return phases[vote_balanced(support, target)]


def overlap_pass(level: Level, vol: np.ndarray, coarse: np.ndarray | None) -> int:
    """One pass of Kopf's own rule over the whole block (in place). Returns the searches made."""
    phases, num, den, searches = overlap_support(level, vol, coarse)
    old = vol.ravel().copy()
    if phases is None:
        vol[...] = num[0] / den
    else:
        vol[...] = phases[vote_balanced(num.reshape(phases.size, -1), level.histogram.exemplar).reshape(vol.shape)]
    level.histogram.replace(old, vol.ravel(), np.arange(vol.size))
    return searches


def overlap_support(level: Level, vol: np.ndarray,
                    coarse: np.ndarray | None) -> tuple[np.ndarray | None, np.ndarray, np.ndarray, int]:
    """Match every voxel in every view, and gather what the matched squares propose.

    Returns ``(phases, num, den, searches)``. The square of voxel u matched at site p
    proposes ``patches[p, j]`` for the voxel ``u + offset_j`` of the view's plane (wrapping),
    with weight ``w_u * h(value)`` (robust weight, histogram factor). ``den`` sums the
    weights each voxel receives; ``num[0]`` the weighted values (``phases`` None), or,
    where the level's exemplar holds only phases (:attr:`Level.phases`: the
    finest level of a categorical exemplar), ``num[i]`` the weight proposing ``phases[i]``.
    """
    k = level.params.neighborhood
    every = np.arange(vol.size)
    sites, ssd = matches(level, vol, coarse, every, level.w_first)  # (views, n)
    hist = level.histogram
    w = robust_weights(ssd, level.span)
    patch_bins = hist.bin(level.patches).reshape(level.patches.shape)  # once a pass, not once a proposal
    # Coarser levels of a categorical exemplar's pyramid are blends: they take the mean.
    phases = level.values if level.phases else None
    num = np.zeros((1 if phases is None else phases.size,) + vol.shape)
    den = np.zeros(vol.shape)
    for i, view in enumerate(level.params.view_names):
        axes = VIEW_AXES[view]
        for j, shift in enumerate(square_offsets(k)):
            proposed = level.patches[sites[i], j]  # what u's match says of u + offset_j
            weight = (w[i] * histogram_factor(level, patch_bins[sites[i], j], view, every)).reshape(vol.shape)
            proposed = proposed.reshape(vol.shape)
            den += np.roll(weight, tuple(shift), axis=axes)
            if phases is None:
                num[0] += np.roll(weight * proposed, tuple(shift), axis=axes)
            else:
                for p, value in enumerate(phases):
                    num[p] += np.roll(weight * (proposed == value), tuple(shift), axis=axes)
    return phases, num, den, sites.size


def vote_balanced(support: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Per voxel, the phase of largest ``log support + b`` (``support`` is ``(phases, n)``).

    The per-phase bias b is the likelihood method's balance (:func:`clsolid.balance.project_bias`)
    fitted to the sharpened scores ``SHARPNESS * log support``: with them, the softmax that
    the balance matches to the *target* fractions is close to the argmax that decides (at
    sharpness 1, diffuse supports miss the target widely). Kopf's histogram factor only
    lowers the weight of a phase the block has too much of, by at most 1 / (1 + s): too
    little to bring a minority phase back to its fraction (docs/design.md#kopf-balance). A phase no square proposes anywhere (support 0) stays out.
    """
    logs = SHARPNESS * np.log(np.maximum(support.T, np.finfo(np.float64).tiny))
    return np.argmax(logs + project_bias(logs, target), axis=1)
