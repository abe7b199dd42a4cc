"""How many sweeps a scale will take, known before it runs (for the ETA).

Under ICM and Gibbs relaxation a voxel's temperature becomes ``max(0, (xi + sum_r t_r) /
|N|)`` over its neighbours (Urs thesis, §4.2.5, eq. 4.9), whatever labels it or they hold; which
voxels a sweep visits and in what order follow from the temperatures, the trusted voxels
and the seed alone. So the whole temperature trajectory of a scale can be replayed
without a single likelihood: the same conflict-free sets, in the same seeded order, with
the float64 reference's temperature update. The replay costs one neighbourhood sum per
voxel and sweep, against the run's sum over every exemplar site; but it runs in NumPy, on
one core, and the pruned sum is cheap: on a large block the finest scale's replay would
take a large share of the run, all of it before the first sweep (docs/design.md#progress-estimate). So a scale whose sweep would sum more than
:data:`REPLAY_TERMS` neighbour terms is not replayed (:func:`affordable`); a smaller block
with the same structure is replayed in its place (:func:`proxy_visits`): the same rule,
inherited corners and ``+in`` slice spacing, on a torus of a side that fits the budget,
its visits scaled by the ratio of the volumes. Its sweeps are not the run's voxel for
voxel (other set colours, other slice depths), but its share of hot voxels per sweep and
its number of sweeps follow the same local dynamics.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ..core.schedule import set_count, set_order
from ..core.slices import insert_slices
from .model import ScaleModel
from .reference import new_temperature

#: Most neighbour terms (voxels x neighbours in the union of the views) a replayed sweep may
#: sum: 2^26, an 11 x 11 run up to about 65^3 (241 neighbours), 9 x 9 to 74^3; a larger scale
#: replays a proxy of that side, a second or two. A larger budget makes the replay a sizeable
#: share of a pruned run; a smaller one, a proxy too small to forecast the run's sweeps
#: (docs/design.md#progress-estimate).
REPLAY_TERMS = 2**26


def affordable(model: ScaleModel) -> bool:
    """Whether a scale's sweeps are cheap enough to replay (:data:`REPLAY_TERMS`)."""
    return int(np.prod(model.shape)) * int(model.union_offsets.shape[0]) <= REPLAY_TERMS


def polish_visits(inherited: np.ndarray, resynth: bool) -> int:
    """Voxels a polish sweep visits (``polish_sweeps``): every one but the inherited ones kept fixed."""
    return int(np.size(inherited)) if resynth else int(np.size(inherited) - np.count_nonzero(inherited))


def forecast_visits(model: ScaleModel, temp: np.ndarray, inherited: np.ndarray, resynth: bool, xi: float,
                    seed: int, first: int, last: int, target: float | None, polish: int = 0) -> list[int]:
    """Voxels visited by each sweep from *first* to the one that ends the scale's relaxation
    (at most *last*; with a *target*, also the first whose global temperature is at most the
    target or 0), replaying the driver's temperature schedule from the temperatures *temp*
    (ICM and Gibbs; not annealing, whose visits do not depend on temperatures), then by
    its *polish* sweeps (:func:`polish_visits`)."""
    temp = np.array(temp, dtype=np.float64).reshape(model.shape)
    inherited = np.asarray(inherited, dtype=bool).reshape(model.shape)
    flat = temp.reshape(-1)
    visits = []
    for sweep in range(first, last + 1):
        active = (temp > 0) | (inherited & resynth)
        for c in set_order(model.n_sets, seed, model.level, sweep):
            voxels = model.set_voxels(c, active)
            if voxels.size:
                hot = flat[voxels] > 0  # inherited voxels are re-synthesised at t = 0, which stays
                flat[voxels[hot]] = new_temperature(model, temp, voxels[hot], xi)
        visits.append(int(active.sum()))
        t_now = float(flat.sum())
        if target is not None and (t_now <= target or t_now == 0.0):
            break
    return visits + [polish_visits(inherited, resynth)] * polish


def proxy_shape(model: ScaleModel, multiple: int) -> tuple[int, int, int]:
    """The block replayed in place of *model*'s: each axis at most the side whose cube sums
    :data:`REPLAY_TERMS` terms a sweep, a multiple of *multiple* (so that slice depths and
    the inherited corners repeat as in the run's block)."""
    side = int((REPLAY_TERMS / model.union_offsets.shape[0]) ** (1 / 3))
    side = max(multiple, side // multiple * multiple)
    return tuple(min(n, side) for n in model.shape)


def proxy_visits(model: ScaleModel, params: Any, seed: int, last: int) -> list[int]:
    """Forecast visits of a scale too large to replay, from its first sweep to the one that
    ends it (at most *last*, then its polish sweeps): a :func:`proxy_shape` block started as the run's (t = 0 on the
    inherited corners below the coarsest scale and on the ``+in`` slices, at the run's
    spacing), replayed by :func:`forecast_visits`, scaled to the run's volume."""
    step = 2 ** (params.scales - 1 - model.level)  # slice depths at this scale are multiples of it
    shape = proxy_shape(model, 2 * step)
    proxy = dataclasses.replace(model, shape=shape, n_sets=set_count(shape, model.half))
    full = tuple(n * 2**model.level for n in shape)
    plan = params
    if params.insert_slices:  # a fixed count: keep the run's spacing, not its count, on the smaller block
        spacing = np.mean([n * 2**model.level for n in model.shape]) / params.insert_slices
        plan = dataclasses.replace(params, insert_slices=None, insert_spacing=max(1.0, float(spacing)))
    temp = np.full(shape, params.initial_temperature)
    if model.level < params.scales - 1:
        temp[::2, ::2, ::2] = 0.0
    temp[insert_slices(np.zeros(shape, np.float32), model.exemplar, plan, model.level, seed, full)] = 0.0
    target = None if params.sweeps else (1.0 - params.stop_fraction) * float(temp.sum())
    visits = forecast_visits(proxy, temp, temp == 0, params.inherited == "resynthesize", params.xi, seed, 1,
                             last, target, params.polish_at(model.level))
    scale = np.prod(model.shape) / np.prod(shape)
    return [int(round(v * scale)) for v in visits]
