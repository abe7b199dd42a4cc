"""Slow, obviously correct float64 NumPy back end of the ML method.

It evaluates the Parzen LCPDF straight from its definition (every exemplar site, every
label; no grouping by centre value, no online log-sum-exp) and is the yardstick the
OpenCL kernels are tested against. The voxels of one colour set are computed together:
no voxel of a set lies in another's neighbourhood, so this equals visiting them one by
one (tests check the colouring property).
"""

from __future__ import annotations

import numpy as np

from ..balance import n_score_slots, score_stride
from . import pruned
from .model import ScaleModel, wrapped_coords  # noqa: F401 (wrapped_coords: also this module's name)
from ..core.philox import TAG_INIT, bounded, unit_float, voxel_uint32, voxel_words

_CHUNK = 128  # voxels per vectorised step, to bound memory

#: Scores within TIE_TOL * max(1, |best|) of the best are ties; the lowest label (or the
#: earlier view) wins. Exact ties are common: two views each dominated by one exemplar
#: site, centred on levels a and b, tie at (a + b) / 2 under the product. The kernels use
#: the same rule, so float32 and float64 break them alike.
TIE_TOL = 1e-4


def logsumexp(a: np.ndarray, axis: int) -> np.ndarray:
    m = np.max(a, axis=axis, keepdims=True)
    return np.squeeze(m, axis) + np.log(np.sum(np.exp(a - m), axis=axis))


def site_distances(model: ScaleModel, vol: np.ndarray, temp: np.ndarray, voxels: np.ndarray,
                   view: int) -> np.ndarray:
    """``A_p`` ``(m, n)``: each voxel's weighted squared neighbourhood distance to every site
    (weighted mismatch count with ``model.mismatch``): neighbour r's term weighs
    (1 - t_r)^2, times ``model.term_weight[r]`` with a fall-off or parent terms (whose values
    and temperatures *vol* and *temp* then hold after the block's: ``model.with_parent``).
    The sites are *view*'s own (:meth:`ScaleModel.sites_of`)."""
    nb = model.neighbour_coords(voxels, view)
    patches = model.patches[:, model.sites_of(view)]
    x = vol.ravel()[nb].astype(np.float64)
    w = 1.0 - temp.ravel()[nb].astype(np.float64)
    if model.term_weight is not None:  # the fall-off: each term times its weight
        w = w * np.sqrt(model.term_weight)
    if model.mismatch or model.channels > 1:  # a colour's: its labels' squared distance
        diff = model.distance(x[:, :, None], patches[None, :, :])
        return np.sum((w**2)[:, :, None] * diff, axis=1)
    diff = w[:, :, None] * (x[:, :, None] - patches[None, :, :])  # (m, R, n)
    return np.sum(diff**2, axis=1)


def log_lcpdf(model: ScaleModel, vol: np.ndarray, temp: np.ndarray, voxels: np.ndarray, view: int) -> np.ndarray:
    """Unnormalised ``log f_v(lambda)`` for each voxel and label: ``(m, |Lambda|)``."""
    return parzen(model, site_distances(model, vol, temp, voxels, view), view=view)


def parzen(model: ScaleModel, a: np.ndarray, keep: np.ndarray | None = None, view: int = 0) -> np.ndarray:
    """Unnormalised ``log f_v(lambda)`` ``(m, |Lambda|)`` from each voxel's weighted squared
    neighbourhood distance to every site of *view*, *a* ``(m, n)``: the Parzen sum over the
    sites, or over those where *keep* ``(m, n)`` is True, or, if *keep* is a float array, with
    each site's term multiplied by it (0: left out)."""
    centres = model.centres[model.sites_of(view)]
    dist = model.distance(model.labels[None, :, None], centres[None, None, :]) + a[:, None, :]
    logw = -dist / (2.0 * model.bandwidth**2)
    if keep is not None:
        with np.errstate(divide="ignore"):
            factor = np.log(keep.astype(np.float64))
        logw = np.where(keep[:, None, :] > 0, logw + factor[:, None, :], -np.inf)
    return logsumexp(logw, axis=2)


def normalise(logf: np.ndarray) -> np.ndarray:
    """Log LCPDF normalised over the labels (Urs thesis, eq. 4.4)."""
    return logf - logsumexp(logf, axis=1)[:, None]


def first_best(score: np.ndarray) -> np.ndarray:
    """Index of the first score within the tie tolerance of the maximum, along the last axis."""
    best = score.max(axis=-1, keepdims=True)
    return np.argmax(score >= best - TIE_TOL * np.maximum(1.0, np.abs(best)), axis=-1)


def combine_views(code: int, values: np.ndarray, scores: np.ndarray) -> np.ndarray:
    """h1 heuristics: combine per-view solutions ``values`` with their log LCPDFs ``scores``
    (both ``(views, m)``): the least (3) or most (4) probable view, or the mean (5)."""
    if code == 5:  # h1-mean, rounded half up to a whole grey level
        return np.floor(values.mean(axis=0) + 0.5)
    pick = np.zeros(values.shape[1], dtype=int)
    chosen = scores[0].copy()
    for v in range(1, scores.shape[0]):  # a near-tie between views keeps the earlier view
        tol = TIE_TOL * np.maximum(1.0, np.abs(chosen))
        better = scores[v] < chosen - tol if code == 3 else scores[v] > chosen + tol
        pick[better], chosen[better] = v, scores[v][better]
    return values[pick, np.arange(values.shape[1])]


def combined_score(code: int, logl: np.ndarray) -> np.ndarray:
    """h2 heuristics: one log score per label, ``(m, L)``: sum (product), min or max over views."""
    return (np.sum, np.min, np.max)[code](logl, axis=0)


def decide(code: int, logl: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """ICM: apply a heuristic to normalised per-view log LCPDFs ``(views, m, L)``; ties -> lowest."""
    if code <= 2:  # h2-product, h2-min, h2-max
        return labels[first_best(combined_score(code, logl))]
    best = first_best(logl)  # (views, m)
    value = np.take_along_axis(logl, best[:, :, None], axis=2)[:, :, 0]
    return combine_views(code, labels[best], value)


def draw(score: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Gibbs: for each row of ``score`` ``(m, L)``, the index drawn from the distribution
    proportional to ``exp(score)`` by inverting its cumulative sum at ``r * total``."""
    w = np.exp(score - score.max(axis=-1, keepdims=True))
    cum = np.cumsum(w, axis=-1)
    above = cum > (r * cum[:, -1])[:, None]
    last = w.shape[-1] - 1 - np.argmax(w[:, ::-1] > 0, axis=-1)  # r * total rounded up to total
    return np.where(above.any(axis=-1), np.argmax(above, axis=-1), last)


def accept(s_new: np.ndarray, s_cur: np.ndarray, t_in: float, q: np.ndarray) -> np.ndarray:
    """Annealing (Urs et al., TIP 2014, Fig. 1): accept where ``p = exp(s_new - s_cur) > 1``
    or ``p * t_in > q``.

    Log scores within the tie tolerance of each other count as equal (p = 1).
    """
    d = s_new - s_cur
    d = np.where(np.abs(d) <= TIE_TOL * np.maximum(1.0, np.abs(s_cur)), 0.0, d)
    return (d > 0) | (np.exp(np.minimum(d, 0.0)) * t_in > q)  # d > 0 is in anyway: no overflow


def nearest_index(x: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Index of the label nearest to each value (the first on a tie)."""
    return np.argmin(np.abs(labels[None, :] - x[:, None]), axis=1)


def unbiased_score(code: int, logl: np.ndarray) -> np.ndarray:
    """The combined log score ``(m, L)`` the balance sees: the h2 combination, or for h1
    heuristics (which decide per view) the product of the views."""
    return combined_score(code if code <= 2 else 0, logl)


def relax(relaxation: str, code: int, logl: np.ndarray, labels: np.ndarray, x: np.ndarray,
          words: np.ndarray | None = None, t_in: float = 1.0, bias: np.ndarray | None = None) -> np.ndarray:
    """New values of voxels whose current values are ``x`` ``(m,)``, from their normalised
    per-view log LCPDFs ``logl`` ``(views, m, L)`` (Urs thesis, §4.2.3-4.2.6).

    ``relaxation`` is ``"icm"`` (argmax), ``"gibbs"`` (a draw from the combined, normalised
    LCPDF) or ``"annealing"`` (a uniform proposal lambda, kept if p = P(lambda)/P(x) > 1 or
    p * t_in > q). ``words`` ``(m, 4)`` are the voxels' Philox words (see ``kernels/ml/relax.cl``,
    ``decide``, for which word serves which draw); ``bias`` ``(L,)`` is added to the combined
    log score (h2) or to each view's (h1). h1 heuristics combine per-view solutions: the
    argmax, a draw from that view, or the proposal where that view alone accepts it.
    """
    if bias is not None:
        logl = logl + (bias if code > 2 else 0.0)
    views, m, n = logl.shape
    rows = np.arange(m)
    if relaxation == "annealing":
        cur, prop = nearest_index(x, labels), bounded(words[:, 0], n)
    if code <= 2:
        score = combined_score(code, logl) + (0.0 if bias is None else bias)
        if relaxation == "icm":
            return labels[first_best(score)]
        if relaxation == "gibbs":
            return labels[draw(score, unit_float(words[:, 0]))]
        ok = accept(score[rows, prop], score[rows, cur], t_in, unit_float(words[:, 1]))
        return np.where(ok, labels[prop], x)
    if relaxation == "icm":
        return decide(code, logl, labels)
    if relaxation == "gibbs":
        best = np.stack([draw(logl[v], unit_float(words[:, v])) for v in range(views)])
        values = labels[best]
    else:
        ok = np.stack([accept(logl[v, rows, prop], logl[v, rows, cur], t_in, unit_float(words[:, 1 + v]))
                       for v in range(views)])
        best = np.where(ok, prop, cur)
        values = np.where(ok, labels[prop], x)
    return combine_views(code, values, np.take_along_axis(logl, best[:, :, None], axis=2)[:, :, 0])


def new_temperature(model: ScaleModel, temp: np.ndarray, voxels: np.ndarray, xi: float) -> np.ndarray:
    """``max(0, (xi + sum_r t_r) / |N|)`` over the union of the views' neighbourhoods (Urs
    thesis, eq. 4.9)."""
    nb = wrapped_coords(voxels, model.shape, model.union_offsets)
    total = temp.ravel()[nb].astype(np.float64).sum(axis=1)
    return np.maximum(0.0, (xi + total) / model.union_offsets.shape[0])


class ReferenceBackend:
    """The float64 NumPy back end; same interface as :class:`clsolid.ml.opencl.CLBackend`."""

    name = "numpy-float64-reference"
    scratch = None  # the state lives here, in memory
    search_seconds = 0.0  # no projected search
    exact_visits = pruned_visits = 0

    def prepare(self, models, params=None) -> None:
        """Nothing to reserve on the host."""

    def init_volume(self, shape, seed: int, pixels: np.ndarray) -> np.ndarray:
        """Random exemplar pixels, drawn by Philox on (seed, x, y, z)."""
        u = voxel_uint32(seed, shape, TAG_INIT)
        return pixels.ravel()[bounded(u, pixels.size)].astype(np.float64)

    def start_scale(self, model: ScaleModel, vol: np.ndarray, temp: np.ndarray, params,
                    sources: np.ndarray | None = None, parent: np.ndarray | None = None) -> None:
        self.model, self.params = model, params
        self.vol = vol.astype(np.float64).copy()
        self.temp = temp.astype(np.float64).copy()
        self.parent = None if parent is None else np.asarray(parent, np.float64)
        views, n_vox = model.offsets.shape[0], int(np.prod(model.shape))
        self.src = (np.full((views, n_vox), -1, np.int32) if sources is None
                    else np.asarray(sources, np.int32).reshape(views, n_vox).copy())
        self.canon = pruned.source_of_site(model)
        if params.likelihood == "pruned":
            self.pruning = pruned.Pruning(model, params, self.canon)
        self._scores = np.zeros((n_score_slots(model.shape), model.labels.size))
        self.stride = score_stride(model.shape)
        self.start_sweep(0, 0, 1.0, np.zeros(model.labels.size))

    def start_sweep(self, seed: int, tag: int, t_in: float, bias: np.ndarray, relaxation: str | None = None) -> None:
        """Random stream, global temperature, balance term and *relaxation* (None: the run's)
        of the coming sweep."""
        self.seed, self.tag, self.t_in, self.bias = seed, tag, t_in, np.asarray(bias, np.float64)
        self.relaxation = relaxation or self.params.relaxation

    def update(self, voxels: np.ndarray) -> None:
        """Relax one conflict-free set of voxels (flat indices)."""
        for i in range(0, voxels.size, _CHUNK):
            self._update_chunk(voxels[i : i + _CHUNK])

    def _sums(self, voxels: np.ndarray) -> np.ndarray:
        """Unnormalised per-view log LCPDFs ``(views, m, L)`` (exact, or pruned where the pruned
        mode allows); records each voxel's source, as a visit does."""
        m = self.model
        vol = m.with_parent(self.vol, self.parent)  # the parent terms' values after the block's
        temp = m.with_parent(self.temp, np.zeros(self.temp.shape))  # and their temperatures, 0
        exact = np.ones(voxels.size, bool)
        if self.params.likelihood == "pruned":
            exact = self.pruning.exact(temp, self.src, voxels)
        out = np.empty((m.offsets.shape[0], voxels.size, m.labels.size))
        for v in range(m.offsets.shape[0]):
            a = site_distances(m, vol, temp, voxels, v)
            if exact.any():
                out[v, exact] = parzen(m, a[exact], view=v)
                self.src[v, voxels[exact]] = self.canon[m.sites_of(v).start + np.argmin(a[exact], axis=1)]
            if not exact.all():
                out[v, ~exact] = self._pruned_view(v, voxels[~exact], a[~exact], vol)
        return out

    def _pruned_view(self, view: int, voxels: np.ndarray, a: np.ndarray, vol: np.ndarray) -> np.ndarray:
        """The pruned sums of *voxels* in *view* from their distances *a* to every site (*vol*:
        the block, with its parent's as ``model.with_parent`` makes it); sets their sources."""
        weights = self.pruning.weights(self.src, self.seed, self.tag, voxels, view, vol)
        self.src[view, voxels] = pruned.nearest_source(self.pruning.table, a, weights)
        return parzen(self.model, a, weights)

    def _update_chunk(self, voxels: np.ndarray) -> None:
        m = self.model
        logl = np.stack([normalise(f) for f in self._sums(voxels)])
        words = None
        if self.relaxation != "icm":
            words = voxel_words(self.seed, *np.unravel_index(voxels, m.shape), self.tag)
        code = self.params.heuristic_code
        kept = voxels % self.stride == 0
        self._scores[voxels[kept] // self.stride] = unbiased_score(code, logl[:, kept])
        labels = relax(self.relaxation, code, logl, m.labels,
                       self.vol.ravel()[voxels], words, self.t_in, self.bias)
        hot = self.temp.ravel()[voxels] > 0  # t held at 0 for inherited (re-synthesised) voxels
        t_new = new_temperature(m, self.temp, voxels, self.params.xi)
        self.vol.ravel()[voxels] = labels
        self.temp.ravel()[voxels[hot]] = t_new[hot]

    def temperature(self) -> np.ndarray:
        return self.temp

    def volume(self) -> np.ndarray:
        return self.vol

    def scores(self) -> np.ndarray:
        """Combined log scores before the bias of the kept voxels (see ``CLBackend.scores``)."""
        return self._scores

    def read_scores(self, rows: np.ndarray) -> np.ndarray:
        """Some *rows* of :meth:`scores`."""
        return self._scores[rows]

    def values(self, voxels: np.ndarray) -> np.ndarray:
        """The values of some voxels (flat indices)."""
        return self.vol.ravel()[voxels]

    def sources(self) -> np.ndarray:
        """Each voxel's source site per view, ``(views, voxels)`` (-1: none yet)."""
        return self.src

    def lcpdf(self, voxels: np.ndarray) -> np.ndarray:
        """Normalised per-view log LCPDFs ``(views, m, L)`` at the current state (for tests);
        sources are updated as in a visit."""
        return np.stack([normalise(f) for f in self._sums(np.asarray(voxels))])
