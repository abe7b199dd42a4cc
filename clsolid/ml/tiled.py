"""Tiles: a volume larger than the device holds, synthesised a tile at a time.

The host keeps the whole volume, its temperatures and its sources; the device keeps a scale's
exemplar tables once and the state of one tile, its halo included (:mod:`clsolid.core.tiles`),
reusing the same buffers for every tile. For every conflict-free set, each tile whose core
holds voxels of the set is given the current state of its core and halo, updates those
voxels, and gives them back (the rest of its core is unchanged). The volume is the one-piece
run's, bit for bit:

* no voxel of a set reads another voxel of the same set (:mod:`clsolid.core.schedule`), so
  each voxel of a set sees the state as it was before the set, whichever tile it is in;
* the halo is as wide as the farthest read of an update (:func:`halo_width`), so a core voxel
  never reads past its tile, and the tile wraps round only along an axis it takes whole,
  where its wrap is the volume's;
* every random number is drawn from Philox keyed by the seed, counted by the voxel's
  coordinates in the whole volume, and the balance's scores go to the whole volume's slots
  (the kernels are told where the tile lies), so nothing depends on the tiles.

The price is moving each tile's state between host and device for every set (``tools/bench_scale.py
--tile``). Only the OpenCL back end is tiled; the float64 reference holds everything on the host.

Who runs a set's tiles is a *runner*: :class:`LocalTiles` runs them one after another on one
engine in this process; :class:`clsolid.ml.distributed.DaskTiles` runs them at once as tasks on
Dask workers, each with its own engine. Both run :func:`run_tile` on a :class:`TileJob`, and the
host keeps the balance's score rows the tiles give back, so the volume is the same.
"""

from __future__ import annotations

from typing import Any, Iterable, Iterator

import numpy as np

from ..balance import n_score_slots, score_rows, score_stride
from ..core.scratch import Scratch
from ..core.tiles import Tiling, gather
from ..errors import DeviceMemoryError, InputError
from .model import ScaleModel
from .params import MLParams
from .contracts import TileJob, TileResult, TileRunner
from .pruned import COHERENCE_REACH


def halo_width(model: ScaleModel) -> int:
    """How far from a voxel the kernels read while updating it: the views' neighbourhoods
    (values and temperatures; parent terms, read from the parent block, as far) and the pruned
    sum's window of sources."""
    return max(int(np.abs(model.offsets).max()), COHERENCE_REACH)


def scale_tiling(model: ScaleModel, edge: int) -> Tiling:
    """The tiles of a scale: cores at most *edge* on a side, with the scale's halo."""
    return Tiling(model.shape, edge, halo_width(model))


def check_tile(engine: Any, models: list[ScaleModel], edge: int, params: MLParams | None = None) -> None:
    """Refuse (:class:`~clsolid.errors.DeviceMemoryError`), before allocating, tiles of *edge*
    whose buffers exceed the device's limits at some scale of *models* (the *engine*'s
    ``check_memory``, with the run's *params*); the message names the tile and what to do."""
    for model in models:
        block = scale_tiling(model, edge).largest_block
        try:
            engine.check_memory(model, block, params)
        except DeviceMemoryError as exc:
            raise exc.advised(
                f"with tile={edge} the device holds {'x'.join(map(str, block))} voxels (a tile and its halo "
                f"of {halo_width(model)}) of the {'x'.join(map(str, model.shape))} scale: use a smaller tile "
                "(tile=, --tile)") from None


def largest_tile(engine: Any, models: list[ScaleModel], params: MLParams | None = None) -> int | None:
    """The largest tile edge whose buffers fit the device at every scale of *models* (of a
    run of *params*); None where none does (the exemplar's tables alone are too large)."""

    def fits(edge: int) -> bool:
        try:
            check_tile(engine, models, edge, params)
        except DeviceMemoryError:
            return False
        return True

    if not fits(1):
        return None
    lo, hi = 1, max(max(m.shape) for m in models)
    while lo < hi:  # a larger edge never makes a smaller tile, so the fitting edges are 1..lo
        mid = (lo + hi + 1) // 2
        lo, hi = (mid, hi) if fits(mid) else (lo, mid - 1)
    return lo


def check_edge(tile) -> int:
    """*tile* as an int; refuse (:class:`~clsolid.errors.InputError`) anything but a positive integer."""
    if isinstance(tile, bool) or not isinstance(tile, (int, np.integer)) or tile < 1:
        raise InputError(f"tile={tile!r} must be a positive integer (voxels on a side of a tile)")
    return int(tile)


def run_tile(engine: Any, job: TileJob) -> TileResult:
    """Relax a tile's voxels of a set on *engine* (a :class:`~clsolid.ml.opencl.CLBackend`
    holding the scale's tables and the sweep's arguments)."""
    before = engine.exact_visits, engine.pruned_visits, engine.search_seconds
    if job.volume is not None:
        engine.load_state(job.volume, job.temperature, job.sources, job.origin, job.parent)
    engine.update(job.voxels)
    values, temperatures, sources = engine.read_voxels(job.voxels)
    return TileResult(values, temperatures, sources, engine.read_scores(job.score_rows),
                      (engine.exact_visits - before[0], engine.pruned_visits - before[1]),
                      engine.search_seconds - before[2])


class LocalTiles:
    """Runs a set's tiles one after another on one engine in this process.

    A runner of :class:`TiledBackend` (see :class:`clsolid.ml.distributed.DaskTiles` for the
    other): ``prepare``, ``init_volume``, ``load_scale``, ``start_sweep`` and ``map``.
    """

    #: One engine runs every tile, so the state of the last tile it ran stays on its device.
    keeps_state = True
    #: One tile at a time.
    parallel = 1

    def __init__(self, engine: Any) -> None:
        self.engine, self.name = engine, engine.name

    def prepare(self, models: list[ScaleModel], edge: int, params: MLParams | None = None) -> None:
        check_tile(self.engine, models, edge, params)

    def init_volume(self, shape, seed: int, pixels: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        return self.engine.init_volume(shape, seed, pixels, out)

    def load_scale(self, model: ScaleModel, params: MLParams, block) -> None:
        self.engine.load_scale(model, params, block)

    def start_sweep(self, seed: int, tag: int, t_in: float, bias: np.ndarray, relaxation: str | None = None) -> None:
        self.engine.start_sweep(seed, tag, t_in, bias, relaxation)

    def map(self, jobs: Iterable[TileJob]) -> Iterator[TileResult]:
        """The jobs' results in their order, each run when asked for (one tile's state at a time)."""
        return (run_tile(self.engine, job) for job in jobs)


class TiledBackend:
    """Runs :func:`clsolid.ml.driver.run_ml` a tile at a time; the same interface as
    :class:`clsolid.ml.opencl.CLBackend`, and the same volume.

    Parameters
    ----------
    runner : CLBackend or runner
        An engine (run in this process by :class:`LocalTiles`), or a runner of the tiles,
        such as :class:`clsolid.ml.distributed.DaskTiles`.
    tile : int
        Most voxels on a side of a tile's core; each tile takes a halo of the
        neighbourhood's half-width on top (:func:`halo_width`).
    scratch : Scratch, optional
        Where the whole block's state is kept (:class:`clsolid.core.scratch.Scratch`; default:
        in memory). The driver allocates its own whole-block arrays there too.
    """

    def __init__(self, runner: TileRunner, tile: int, scratch: Scratch | None = None) -> None:
        self.tile = check_edge(tile)
        self.scratch = Scratch() if scratch is None else scratch
        self.runner = runner
        self.name = self.runner.name
        self.exact_visits = self.pruned_visits = 0  # voxel visits by sum, in the pruned mode
        self.search_seconds = 0.0  # the tiles' projected search, per worker running them at once
        self._held = None

    def prepare(self, models: list[ScaleModel], params: MLParams | None = None) -> None:
        """Refuse, before allocating anything, tiles whose buffers (for a run of *params*)
        exceed the device limits."""
        self.runner.prepare(models, self.tile, params)

    def init_volume(self, shape, seed: int, pixels: np.ndarray) -> np.ndarray:
        """The random start (see :meth:`clsolid.ml.opencl.CLBackend.init_volume`), on the scratch."""
        return self.runner.init_volume(shape, seed, pixels, self.scratch.empty(shape, np.float32))

    def start_scale(self, model: ScaleModel, vol: np.ndarray, temp: np.ndarray, params: MLParams,
                    sources: np.ndarray | None = None, parent: np.ndarray | None = None) -> None:
        """Upload a scale's tables, and keep its state on the host; *sources* and *parent* as
        for :meth:`clsolid.ml.opencl.CLBackend.start_scale` (each tile gets its part of it)."""
        for old in (getattr(self, name, None) for name in ("_vol", "_temp", "_src")):
            self.scratch.free(old)  # the last scale's state (its volume is the start's, made already)
        self.tiling = scale_tiling(model, self.tile)
        self.runner.load_scale(model, params, self.tiling.largest_block)
        self._held = None  # the start of the tile whose current state the runner's engine holds
        self._parent = parent  # read only: each tile's part is gathered with its state
        views = model.offsets.shape[0]
        # the driver's own start, not copied (host memory): float32 on this back end's scratch
        self._vol = vol if vol.dtype == np.float32 else self.scratch.copy(vol, np.float32)
        self._temp = self.scratch.copy(temp, np.float32)
        self._src = (self.scratch.full((views,) + model.shape, -1, np.int32) if sources is None
                     else self.scratch.copy(np.asarray(sources).reshape((views,) + model.shape), np.int32))
        self.stride = score_stride(model.shape)
        self._scores = np.zeros((n_score_slots(model.shape), model.labels.size), np.float32)

    def start_sweep(self, seed: int, tag: int, t_in: float, bias: np.ndarray, relaxation: str | None = None) -> None:
        """As :meth:`clsolid.ml.opencl.CLBackend.start_sweep`."""
        self.runner.start_sweep(seed, tag, t_in, bias, relaxation)

    def update(self, voxels: np.ndarray) -> None:
        """Relax one conflict-free set of voxels (flat indices), tile by tile. A tile whose
        state the runner's one engine still holds, no other tile having run since (the next
        set of a region-by-region sweep, ``region`` = ``tile``), is not gathered and sent again."""
        groups = [(tile, part, score_rows(part, self.stride)) for tile, part in self.tiling.group(voxels)]
        held = self._held
        jobs = (TileJob(None, None, None, tile.origin, tile.local(part), rows) if i == 0 and tile.start == held
                else TileJob(gather(self._vol, tile), gather(self._temp, tile), gather(self._src, tile), tile.origin,
                             tile.local(part), rows, None if self._parent is None else gather(self._parent, tile))
                for i, (tile, part, rows) in enumerate(groups))
        if groups and self.runner.keeps_state:
            self._held = groups[-1][0].start
        src = self.sources()
        for (tile, part, rows), r in zip(groups, self.runner.map(jobs)):
            self._vol.flat[part], self._temp.flat[part], src[:, part] = r.values, r.temperatures, r.sources
            self._scores[rows] = r.scores
            self.exact_visits += r.visits[0]
            self.pruned_visits += r.visits[1]
            self.search_seconds += r.searched / self.runner.parallel

    def volume(self) -> np.ndarray:
        return self._vol

    def temperature(self) -> np.ndarray:
        return self._temp

    def sources(self) -> np.ndarray:
        """Each voxel's source site per view, ``(views, voxels)`` (-1: none yet)."""
        return self._src.reshape(self._src.shape[0], -1)

    def values(self, voxels: np.ndarray) -> np.ndarray:
        """The values of some voxels (flat indices of the whole block)."""
        return self._vol.ravel()[voxels]

    def read_scores(self, rows: np.ndarray) -> np.ndarray:
        """Some *rows* of :meth:`scores`."""
        return self._scores[rows]

    def scores(self) -> np.ndarray:
        """As :meth:`clsolid.ml.opencl.CLBackend.scores`: the whole volume's slots, as the tiles
        gave back those of the voxels they updated."""
        return self._scores
