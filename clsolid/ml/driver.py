"""The multi-scale ICM driver (Urs thesis, §4.2.6, §4.3; Urs et al., TIP 2014, Fig. 1), shared by
the OpenCL and reference back ends."""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..balance import project_bias, score_rows, score_stride, softmax, sweep_target
from .forecast import affordable, forecast_visits, polish_visits, proxy_visits
from ..exemplar import nearest_level_index
from .model import ScaleModel, build_scale, check_exemplar_fits, parent_block
from .params import MLParams
from .pruned import projects
from ..core.philox import relax_tag
from ..core.schedule import regions, set_order
from ..core.scratch import Scratch
from ..core.slices import insert_slices
from ..core.threads import serial_blas
from ..core.synthesis import SweepInfo, SynthesisResult, check_shape, resolve_seed  # noqa: F401 (re-exported)

log = logging.getLogger(__name__)


def start_state(model: ScaleModel, base: np.ndarray, coarse: np.ndarray | None, params: MLParams, seed: int = 0,
                scratch: Scratch | None = None):
    """Volume and temperatures at the start of a scale (Urs thesis, §4.3.5.2); t = 0 marks
    trusted voxels.

    The random start *base* (full resolution) is decimated; the coarser scale's result is
    copied in (1/8 or 8/8), then the ``+in`` slices get this scale's exemplar. Both arrays are
    made on *scratch* (default: in memory).
    """
    scratch = Scratch() if scratch is None else scratch
    step = 2**model.level
    vol = scratch.copy(base[::step, ::step, ::step], np.float32)  # label indices: exact in float32
    temp = scratch.full(model.shape, params.initial_temperature, np.float64)
    if coarse is not None:
        if params.upsampling == "8/8":
            up = coarse.repeat(2, 0).repeat(2, 1).repeat(2, 2)
            vol[...] = up[: model.shape[0], : model.shape[1], : model.shape[2]]
        else:
            vol[::2, ::2, ::2] = coarse
        # Only the voxel at the even corner is inherited (t = 0), under 1/8 and 8/8 alike.
        temp[::2, ::2, ::2] = 0.0
    inserted = insert_slices(vol, model.exemplar, params, model.level, seed, base.shape,
                             scratch.full(model.shape, False, bool))
    np.copyto(temp, 0.0, where=inserted)
    scratch.free(inserted)
    return vol, temp


def label_fractions(values: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Fraction of *values* on each of the sorted *labels* (a value off the labels, as
    ``h1-mean`` can write, counts for the nearest)."""
    return np.bincount(nearest_level_index(values, labels), minlength=labels.size) / max(np.size(values), 1)


_INDEX_RUN = 1 << 20  # voxels whose label index is found, or counted, at once


class Balance:
    """The label-histogram balance of one scale: the bias that keeps the volume's label
    fractions at the exemplar's (the departure of clsolid.balance).

    :meth:`after` is called after every conflict-free set and returns the bias for the
    next one, so the bias follows the volume within a sweep: a bias fitted once per sweep
    lags it (the scores drift as the labels change, and the fractions swing from sweep
    to sweep by several points).

    It keeps each voxel's label index (one byte a voxel up to 256 labels), the whole
    volume's label counts, and the sweep's counts (:meth:`start_sweep`): of the voxels still
    to come, as their labels were when the sweep began (a voxel's label changes only when it
    is relaxed), and of all the sweep's voxels as they are now; so the voxels still to come
    are counted without listing them.
    """

    def __init__(self, model: ScaleModel, beta: float, volume: np.ndarray, bias: np.ndarray,
                 scratch: Scratch | None = None) -> None:
        self.model, self.beta = model, beta
        self.scratch = Scratch() if scratch is None else scratch
        self.pi = label_fractions(model.pixels, model.labels)  # with an exemplar per view, their pixels pooled
        self.stride = score_stride(model.shape)
        self.bias = bias  # zeros at a scale's start (a coarser scale's labels mean other grey levels)
        self.dtype = np.min_scalar_type(max(model.labels.size - 1, 0))
        self.index = self._index(volume, self.scratch.empty(np.size(volume), self.dtype))  # each voxel's label
        self.total = self._count(self.index)

    def _index(self, values: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        flat = np.ravel(values)
        out = np.empty(flat.size, self.dtype) if out is None else out
        for lo in range(0, flat.size, _INDEX_RUN):  # searchsorted's int64 a run at a time (host memory)
            out[lo:lo + _INDEX_RUN] = nearest_level_index(flat[lo:lo + _INDEX_RUN], self.model.labels)
        return out

    def _count(self, index: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        """Each label's count in *index* (only where *mask*, if given), a run at a time:
        bincount widens to int64, and a masked selection is a copy."""
        n = self.model.labels.size
        runs = (index[lo:lo + _INDEX_RUN] if mask is None else index[lo:lo + _INDEX_RUN][mask[lo:lo + _INDEX_RUN]]
                for lo in range(0, index.size, _INDEX_RUN))
        return sum((np.bincount(run, minlength=n) for run in runs), np.zeros(n, np.int64))

    def start_sweep(self, active: np.ndarray) -> None:
        """Count the labels of the voxels this sweep relaxes (*active*), none relaxed yet."""
        mask = np.ravel(active)
        self.coming, self.n_coming = self._count(self.index, mask), int(np.count_nonzero(mask))
        self.swept, self.n_swept = self.coming.copy(), self.n_coming

    def after(self, backend: Any, updated: np.ndarray) -> np.ndarray:
        """The bias for the voxels still to come after the set *updated* was relaxed.

        Those voxels are the sweep's later sets' or, after its last set, all the sweep's
        voxels again; they aim at whatever brings the whole volume to the exemplar's
        fractions, given the labels of all the others.
        """
        new = self._index(backend.values(updated))
        old_counts, new_counts = self._count(self.index[updated]), self._count(new)
        self.index[updated] = new
        self.total += new_counts - old_counts
        self.swept += new_counts - old_counts
        self.coming -= old_counts
        self.n_coming -= updated.size
        later, pending = (self.coming, self.n_coming) if self.n_coming else (self.swept, self.n_swept)
        rows = score_rows(updated, self.stride)
        if rows.size == 0 or pending == 0:
            return self.bias
        scores = np.asarray(backend.read_scores(rows), np.float64)
        fixed = self.total - later
        target = sweep_target(self.pi, fixed, pending, softmax(scores).mean(axis=0), self.beta)
        with serial_blas():  # small matrices, while the device's threads hold the cores
            self.bias = project_bias(scores, target, self.bias)
        return self.bias


_MIN_TIMED_SWEEP = 0.5  # seconds; shorter sweeps do not predict the finer scales


class _Clock:
    """Per-sweep timing and an estimate of the time left.

    Within a scale the sweeps still to come and the voxels each visits are known in
    advance under ICM and Gibbs (:func:`~clsolid.ml.forecast.forecast_visits`), so the
    time left there is those visits at the last sweep's rate per visit (for a scale too large
    to replay, a smaller block's visits scaled up, :func:`~clsolid.ml.forecast.proxy_visits`).
    Otherwise (annealing, or such a scale resumed midway) it is extrapolated from the fall of
    the global temperature. The scales still to come are estimated from their size.
    """

    def __init__(self, models: list[ScaleModel], params: MLParams):
        self.t0 = time.perf_counter()
        self.params = params
        # Work of a full sweep at each scale: voxels x exemplar sites summed x window terms.
        self.work = [np.prod(m.shape) * self._unit(m) for m in models]
        self.rate: float | None = None  # seconds per unit of work, measured
        self.visits: dict[int, int] = {}  # this scale's forecast: sweep -> voxels it visits
        # What a sweep costs beside its projected search, per visit, over a sweep without one
        # (its sum takes the search's candidates too): learnt at a scale, applied at the next.
        self.extra = 1.0
        self._searching_rate: float | None = None  # this scale's searching sweep, less its search, per visit

    def _unit(self, model: ScaleModel) -> int:
        """Terms per voxel visit: every site's window, or, pruned, at most the candidates and the sample."""
        sites = model.n_sites // (model.offsets.shape[0] if model.per_view else 1)  # a view's own
        if self.params.likelihood == "pruned":
            sites = min(sites, 9 * self.params.n_similar + self.params.n_sample)
        return sites * model.patches.shape[0]

    def plan(self, first: int, visits: list[int]) -> None:
        """The forecast visits of this scale's sweeps from *first* on."""
        self.visits = {first + k: v for k, v in enumerate(visits)}
        self._searching_rate = None

    def _left_here(self, sweep: int, sweep_s: float, visited: int, t: float, t_prev: float, target: float,
                   sweeps_left: int, searched: float, level: int, polish_left: int) -> float:
        if self.visits:
            if not visited:
                return 0.0
            coming = {s: v for s, v in self.visits.items() if s > sweep}
            searching = sum(v for s, v in coming.items() if projects(self.params, relax_tag(level, s)))
            plain = (sweep_s - searched) / self.extra if searched else sweep_s
            # the sweeps to come at this one's rate without its search, plus the search where they search too
            return (plain * (sum(coming.values()) - searching) + sweep_s * searching) / visited
        ratio = t / t_prev if t_prev > 0 else 0.0
        if t <= target or ratio <= 0:
            left = 0
        elif ratio >= 1 or target <= 0:
            left = sweeps_left
        else:
            left = min(sweeps_left, math.ceil(math.log(target / t) / math.log(ratio)))
        return sweep_s * (left + polish_left)

    def eta(self, i: int, sweep: int, sweep_s: float, visited: int, model: ScaleModel, t: float, t_prev: float,
            target: float, sweeps_left: int, searched: float = 0.0, polish_left: int = 0) -> float:
        """Seconds left after *sweep* of scale *i*, which took *sweep_s*, *searched* of them in
        the projected search (the pruned sum's first sweeps only, by default: a sweep that
        searches costs several that do not, so the sweeps to come that do not are timed without it).
        *sweeps_left*: at most so many sweeps of the relaxation to come, then *polish_left* polish sweeps."""
        unit = self._unit(model)
        if visited:
            self.rate = sweep_s / (visited * unit)
            if searched:
                self._searching_rate = (sweep_s - searched) / visited
            elif self._searching_rate:
                self.extra = self._searching_rate * visited / sweep_s
        if self.rate is None:
            return math.nan
        here = 0.0 if sweeps_left == polish_left == 0 else self._left_here(
            sweep, sweep_s, visited, t, t_prev, target, sweeps_left, searched, model.level, polish_left)
        if i + 1 == len(self.work):
            return float(here)
        if sweep_s < _MIN_TIMED_SWEEP:
            return math.nan  # launch overhead dominates tiny sweeps: their rate would mislead
        # A finer scale relaxes about as many voxel-visits per voxel as the coarsest did.
        later = sum(self.work[i + 1 :]) * self.rate * 2.5
        return float(here + later)


@dataclass
class RunState:
    """Where a relaxation stands after a sweep: everything it needs to go on identically.

    ``scale`` indexes the scales coarsest first; ``done`` says the scale ended with this
    sweep; ``relaxed``, the sweep that ended its relaxation where polish sweeps follow (0:
    not yet). The random streams need no saving: Philox draws are keyed by (seed, voxel,
    scale, sweep), and each sweep's set order by (seed, scale, sweep).
    """

    scale: int
    sweep: int
    done: bool
    volume: np.ndarray
    temperature: np.ndarray
    inherited: np.ndarray
    t_init: float
    target: float
    t_now: float
    bias: np.ndarray
    timings: dict
    sources: np.ndarray | None = None  # the pruned likelihood's per-view sources (None: exact)
    parent: np.ndarray | None = None  # the scale's parent block (parent_weight > 0, below the coarsest)
    relaxed: int = 0

    def arrays(self) -> dict[str, np.ndarray]:
        """The state as named arrays (for :func:`clsolid.core.checkpoint.write_checkpoint`)."""
        out = {"volume": self.volume, "temperature": self.temperature, "inherited": self.inherited,
               "bias": self.bias, "scalars": np.array([self.t_init, self.target, self.t_now]),
               "position": np.array([self.scale, self.sweep, int(self.done)]),
               "relaxed": np.array([self.relaxed])}
        for name in ("sources", "parent"):
            if getattr(self, name) is not None:
                out[name] = getattr(self, name)
        return out

    @classmethod
    def from_arrays(cls, a: dict[str, np.ndarray], timings: dict) -> "RunState":
        scale, sweep, done = (int(v) for v in a["position"])
        t_init, target, t_now = (float(v) for v in a["scalars"])
        relaxed = int(a["relaxed"][0]) if "relaxed" in a else 0  # none before polish sweeps
        return cls(scale, sweep, bool(done), a["volume"], a["temperature"], np.asarray(a["inherited"], bool),
                   t_init, target, t_now, a["bias"], timings, a.get("sources"), a.get("parent"), relaxed)


def run_ml(
    labels_img: np.ndarray | dict[str, np.ndarray],
    shape: tuple[int, int, int],
    params: MLParams,
    seed: int,
    backend: Any,
    progress: Callable[[SweepInfo], None] | None = None,
    checkpoint: Any = None,
    resume: RunState | None = None,
    palette: np.ndarray | None = None,
) -> tuple[np.ndarray, dict, list[float]]:
    """Run the multi-scale relaxation on quantised exemplar labels (one image, or one per view)
    with a back end; a colour exemplar's labels with its *palette* ``(L, 3)`` in CIELAB
    (``LevelMap.features``).

    Each sweep draws its random numbers from Philox keyed by *seed*, counter (x, y, z,
    :func:`clsolid.core.philox.relax_tag` (level, sweep)). Under ``relaxation="annealing"``
    there are no voxel temperatures (every neighbour counts fully, Urs et al., TIP 2014, Fig. 1) and
    every voxel is visited in every sweep (trusted ones too, unless ``inherited="fixed"``);
    the global temperature t_in starts each scale at ``anneal_start`` and is multiplied by
    ``anneal_cooling`` after each sweep, and the stop rule applies to it.

    After the sweep that ends a scale's relaxation come :meth:`MLParams.polish_at` polish
    sweeps (``polish_sweeps``, at the finest scale): each voxel takes the argmax of its
    LCPDF, as under ICM, the balance on as in any sweep, and every voxel is visited but
    the inherited ones kept fixed (``inherited="fixed"``), those that cooled to t = 0 too.
    A draw now and then takes a label no neighbour shares; the argmax undoes some of those
    (fewer with the balance, which flips uncertain voxels to keep the fractions).

    *checkpoint*, if given (a :class:`clsolid.ml.checkpoints.Checkpointer`), is asked after
    every sweep whether it is ``due`` and then given the :class:`RunState`; *resume*
    continues from one (its volume, temperatures and bias restored on the back end), and
    gives the same volume as the run that was never stopped.

    Returns the full-resolution volume, the timings and the per-scale bandwidths.
    """
    check_exemplar_fits({v: im.shape for v, im in labels_img.items()} if isinstance(labels_img, dict)
                        else labels_img.shape, params)
    scratch = backend.scratch or Scratch()  # a tiled back end's, where it keeps the state
    levels = list(range(params.scales - 1, -1, -1))
    models = [build_scale(labels_img, shape, params, lv, palette) for lv in levels]
    backend.prepare(models, params)  # refuses, before allocating, what the device cannot hold
    clock = _Clock(models, params)
    base = backend.init_volume(shape, seed, models[0].pixels)
    resynth = params.inherited == "resynthesize"
    annealing = params.relaxation == "annealing"
    pruned = params.likelihood == "pruned"
    n_sweeps = params.sweeps or params.max_sweeps
    coarse = active = None
    timings: dict = {"scales": []}
    if resume is not None:
        timings = {"scales": [dict(r) for r in resume.timings["scales"]]}
        if resume.done:  # the checkpoint ended a scale: the next one starts from its volume
            coarse = np.asarray(resume.volume).reshape(models[resume.scale].shape)
    for i, model in enumerate(models):
        if resume is not None and (i < resume.scale or (i == resume.scale and resume.done)):
            continue
        t_scale = time.perf_counter()
        first, sources, parent, relaxed = 1, None, None, 0
        polish = params.polish_at(model.level)
        if resume is not None and i == resume.scale:  # go on with the sweep after the checkpoint's
            r = resume
            vol, temp, inherited = r.volume.reshape(model.shape), r.temperature.reshape(model.shape), r.inherited
            t_init, target, t_now, first, relaxed = r.t_init, r.target, r.t_now, r.sweep + 1, r.relaxed
            bias = np.array(r.bias, dtype=np.float64)
            sources, parent = r.sources, r.parent
            record = timings["scales"].pop()
        else:
            vol, temp = start_state(model, base, coarse, params, seed, scratch)
            if model.parent_rows:
                parent = parent_block(coarse, model.shape, scratch.empty(model.shape, np.float32))
            if model.level == 0:
                scratch.free(base)
                base = None  # the finest scale has taken all it needs from the random start
            inherited = scratch.apply(lambda t: t == 0, bool, temp)
            if annealing:
                temp[...] = 0.0  # no pixel temperatures: every neighbour's weight 1 - t is 1
            t_init = params.anneal_start if annealing else float(temp.sum())
            target = 0.0 if params.sweeps else (1.0 - params.stop_fraction) * t_init
            t_now = t_init
            bias = np.zeros(model.labels.size)
            record = {"level": model.level, "shape": list(model.shape), "bandwidth": model.bandwidth,
                      "n_sites": model.n_sites, "n_sets": model.n_sets, "initial_temperature": t_init,
                      "temperatures": [], "visited": [], "sweep_seconds": []}
        if model.parent_rows and parent is None:
            raise ValueError("this checkpoint has no parent block; resume it with the clsolid that wrote it")
        backend.start_scale(model, vol, temp, params, sources=sources, parent=parent)
        balance = Balance(model, params.balance, vol, bias, scratch) if params.balance else None
        if progress is not None and not annealing:  # the ETA's sweeps, known before they run where affordable
            if relaxed:  # resumed among the polish sweeps
                visits = [polish_visits(inherited, resynth)] * (relaxed + polish + 1 - first)
            elif affordable(model):
                visits = forecast_visits(model, temp, inherited, resynth, params.xi, seed, first, n_sweeps,
                                         None if params.sweeps else target, polish)
            else:  # a smaller block in its place; none for a scale resumed midway
                visits = proxy_visits(model, params, seed, n_sweeps) if first == 1 else []
            clock.plan(first, visits)
        scratch.free(temp)  # the back end holds the state now (its own temperatures): free the host's copies
        vol = temp = None
        sweep = first - 1
        while True:
            sweep += 1
            t_sweep, searched_before = time.perf_counter(), backend.search_seconds
            scratch.free(active)  # the last sweep's
            if annealing or relaxed:  # a polish sweep visits the voxels that cooled too
                active = scratch.apply(lambda i: ~i | resynth, bool, inherited)
            else:
                temp = np.asarray(backend.temperature()).reshape(model.shape)
                active = scratch.apply(lambda t, i: (t > 0) | (i & resynth), bool, temp, inherited)
            how = "icm" if relaxed else None  # a polish sweep takes the argmax whatever the relaxation
            backend.start_sweep(seed, relax_tag(model.level, sweep), t_now, bias, how)
            order = set_order(model.n_sets, seed, model.level, sweep)
            if balance is not None:
                balance.start_sweep(active)
            for box, c in ((box, c) for box in regions(model.shape, params.region) for c in order):
                voxels = model.set_voxels(c, active, box)  # one set's indices at a time (host memory)
                if not voxels.size:
                    continue
                backend.update(voxels)
                if balance is not None:
                    bias = balance.after(backend, voxels)
                    backend.start_sweep(seed, relax_tag(model.level, sweep), t_now, bias, how)
            if annealing:
                t_prev, t_now = t_now, t_now * params.anneal_cooling
            else:
                t_prev, t_now = t_now, float(np.sum(backend.temperature(), dtype=np.float64))
            visited = int(active.sum())
            sweep_s = time.perf_counter() - t_sweep
            searched = backend.search_seconds - searched_before
            record["temperatures"].append(t_now)
            record["visited"].append(visited)
            record["sweep_seconds"].append(sweep_s)
            if relaxed:
                done = sweep == relaxed + polish
            else:
                if params.sweeps:
                    done = sweep == n_sweeps
                else:
                    done = t_now <= target or t_now == 0.0 or sweep == n_sweeps
                if done and polish:  # the relaxation ended: the polish sweeps follow
                    relaxed, done = sweep, False
            log.debug("scale %d sweep %d: T=%.1f visited=%d %.2fs", i + 1, sweep, t_now, visited, sweep_s)
            if checkpoint is not None and checkpoint.due(done):  # before progress: a Ctrl-C there keeps it
                # written before save returns: the back end's arrays need no copies (host memory)
                checkpoint.save(RunState(i, sweep, done, np.asarray(backend.volume()),
                                         np.asarray(backend.temperature()), inherited, t_init,
                                         target, t_now, np.array(bias, dtype=np.float64),
                                         {"scales": timings["scales"] + [record]},
                                         np.asarray(backend.sources()) if pruned else None, parent, relaxed))
            if progress is not None:
                left, polish_left = (0, relaxed + polish - sweep) if relaxed else (n_sweeps - sweep, polish)
                eta = clock.eta(i, sweep, sweep_s, visited, model, t_now, t_prev, target, 0 if done else left,
                                searched, 0 if done else polish_left)
                progress(SweepInfo(scale=i + 1, n_scales=len(models), shape=model.shape, sweep=sweep,
                                   max_sweeps=n_sweeps + polish, temperature=t_now,
                                   initial_temperature=t_init, target=target, visited=visited,
                                   elapsed=time.perf_counter() - clock.t0, eta=eta,
                                   exemplar=model.exemplar, volume=lambda: np.array(backend.volume(), copy=True)))
            if done:
                break
        for done_with in (inherited, active, parent, balance.index if balance is not None else None):
            scratch.free(done_with)  # this scale's masks and labels (on disk: their files)
        active = None
        coarse = np.asarray(backend.volume()).reshape(model.shape)  # float32 on a device, as the state
        record["sweeps"] = len(record["temperatures"])
        record["polish_sweeps"] = sweep - relaxed if relaxed else 0
        record["seconds"] = time.perf_counter() - t_scale
        timings["scales"].append(record)
    timings["total_s"] = time.perf_counter() - clock.t0
    return coarse, timings, [m.bandwidth for m in models]
