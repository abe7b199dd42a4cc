"""Slow, obviously correct float64 NumPy back end of the ML method.

It evaluates the Parzen LCPDF straight from its definition (every exemplar site, every
label; no grouping by centre value, no online log-sum-exp) and is the yardstick the
OpenCL kernels are tested against. The voxels of one colour set are computed together:
no voxel of a set lies in another's neighbourhood, so this equals visiting them one by
one (tests check the colouring property).
"""

from __future__ import annotations

import numpy as np

from .ml_model import ScaleModel
from .philox import TAG_INIT, bounded, voxel_uint32

_CHUNK = 128  # voxels per vectorised step, to bound memory

#: Scores within TIE_TOL * max(1, |best|) of the best are ties; the lowest label (or the
#: earlier view) wins. Exact ties are common: two views each dominated by one exemplar
#: site, centred on levels a and b, tie at (a + b) / 2 under the product. The kernels use
#: the same rule, so float32 and float64 break them alike.
TIE_TOL = 1e-4


def logsumexp(a: np.ndarray, axis: int) -> np.ndarray:
    m = np.max(a, axis=axis, keepdims=True)
    return np.squeeze(m, axis) + np.log(np.sum(np.exp(a - m), axis=axis))


def wrapped_coords(voxels: np.ndarray, shape, offsets: np.ndarray) -> tuple:
    """Flat indices of ``voxels + offsets`` on the torus: returns an ``(m, R)`` array."""
    z, y, x = np.unravel_index(voxels, shape)
    zz = (z[:, None] + offsets[None, :, 0]) % shape[0]
    yy = (y[:, None] + offsets[None, :, 1]) % shape[1]
    xx = (x[:, None] + offsets[None, :, 2]) % shape[2]
    return np.ravel_multi_index((zz, yy, xx), shape)


def log_lcpdf(model: ScaleModel, vol: np.ndarray, temp: np.ndarray, voxels: np.ndarray, view: int) -> np.ndarray:
    """Unnormalised ``log f_v(lambda)`` for each voxel and label: ``(m, |Lambda|)``."""
    nb = wrapped_coords(voxels, model.shape, model.offsets[view])
    x = vol.ravel()[nb].astype(np.float64)
    w = 1.0 - temp.ravel()[nb].astype(np.float64)
    diff = w[:, :, None] * (x[:, :, None] - model.patches[None, :, :])  # (m, R, n)
    a = np.sum(diff**2, axis=1)  # (m, n)
    dist = (model.labels[None, :, None] - model.centres[None, None, :]) ** 2 + a[:, None, :]
    return logsumexp(-dist / (2.0 * model.bandwidth**2), axis=2)


def normalise(logf: np.ndarray) -> np.ndarray:
    """Log LCPDF normalised over the labels (eq. 4.4)."""
    return logf - logsumexp(logf, axis=1)[:, None]


def first_best(score: np.ndarray) -> np.ndarray:
    """Index of the first score within the tie tolerance of the maximum, along the last axis."""
    best = score.max(axis=-1, keepdims=True)
    return np.argmax(score >= best - TIE_TOL * np.maximum(1.0, np.abs(best)), axis=-1)


def decide(code: int, logl: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Apply a heuristic to normalised per-view log LCPDFs ``(views, m, L)``; ties -> lowest."""
    if code <= 2:  # h2-product, h2-min, h2-max
        combine = (np.sum, np.min, np.max)[code]
        return labels[first_best(combine(logl, axis=0))]
    best = first_best(logl)  # (views, m)
    if code == 5:  # h1-mean, rounded half up to a whole grey level
        return np.floor(labels[best].mean(axis=0) + 0.5)
    value = np.take_along_axis(logl, best[:, :, None], axis=2)[:, :, 0]
    pick = np.zeros(best.shape[1], dtype=int)
    chosen = value[0].copy()
    for v in range(1, value.shape[0]):  # a near-tie between views keeps the earlier view
        tol = TIE_TOL * np.maximum(1.0, np.abs(chosen))
        better = value[v] < chosen - tol if code == 3 else value[v] > chosen + tol
        pick[better], chosen[better] = v, value[v][better]
    return labels[best[pick, np.arange(best.shape[1])]]


def new_temperature(model: ScaleModel, temp: np.ndarray, voxels: np.ndarray, xi: float) -> np.ndarray:
    """``max(0, (xi + sum_r t_r) / |N|)`` over the union of the views' neighbourhoods (eq. 4.9)."""
    nb = wrapped_coords(voxels, model.shape, model.union_offsets)
    total = temp.ravel()[nb].astype(np.float64).sum(axis=1)
    return np.maximum(0.0, (xi + total) / model.union_offsets.shape[0])


class ReferenceBackend:
    """The float64 NumPy back end; same interface as :class:`clsolid.cl_backend.CLBackend`."""

    name = "numpy-float64-reference"

    def prepare(self, models) -> None:
        """Nothing to reserve on the host."""

    def init_volume(self, shape, seed: int, pixels: np.ndarray) -> np.ndarray:
        """Random exemplar pixels, drawn by Philox on (seed, x, y, z)."""
        u = voxel_uint32(seed, shape, TAG_INIT)
        return pixels.ravel()[bounded(u, pixels.size)].astype(np.float64)

    def start_scale(self, model: ScaleModel, vol: np.ndarray, temp: np.ndarray, params) -> None:
        self.model, self.params = model, params
        self.vol = vol.astype(np.float64).copy()
        self.temp = temp.astype(np.float64).copy()

    def update(self, voxels: np.ndarray) -> None:
        """Relax one conflict-free set of voxels (flat indices)."""
        for i in range(0, voxels.size, _CHUNK):
            self._update_chunk(voxels[i : i + _CHUNK])

    def _update_chunk(self, voxels: np.ndarray) -> None:
        m = self.model
        views = m.offsets.shape[0]
        logl = np.stack([normalise(log_lcpdf(m, self.vol, self.temp, voxels, v)) for v in range(views)])
        labels = decide(self.params.heuristic_code, logl, m.labels)
        hot = self.temp.ravel()[voxels] > 0  # t held at 0 for inherited (re-synthesised) voxels
        t_new = new_temperature(m, self.temp, voxels, self.params.xi)
        self.vol.ravel()[voxels] = labels
        self.temp.ravel()[voxels[hot]] = t_new[hot]

    def temperature(self) -> np.ndarray:
        return self.temp

    def volume(self) -> np.ndarray:
        return self.vol

    def lcpdf(self, voxels: np.ndarray) -> np.ndarray:
        """Normalised per-view log LCPDFs ``(views, m, L)`` at the current state (for tests)."""
        m = self.model
        return np.stack([normalise(log_lcpdf(m, self.vol, self.temp, voxels, v)) for v in range(m.offsets.shape[0])])
