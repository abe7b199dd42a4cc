"""Dask: the tiles of every conflict-free set as tasks on ``dask.distributed``
workers, each worker with its own OpenCL device.

:class:`DaskTiles` is a runner of :class:`clsolid.ml.tiled.TiledBackend`: the host keeps the
whole state and, for every set, submits one task per tile that holds voxels of the set (all at
once), gathers what they give back and writes it into the state; the balance's bias for the
next set is fitted on the host, from the score rows the tasks give back. Each worker process
keeps one engine (:class:`~clsolid.ml.opencl.CLBackend`) per scale in a process-wide cache:
the scale's tables reach every worker once (``client.scatter(..., broadcast=True)``) and the
engine is built on the first task that needs it; the sweep's arguments (seed, tag, global
temperature, bias: the bias changes after every set; the sweep's relaxation) travel with each task. Each task is
:func:`clsolid.ml.tiled.run_tile`, the same as in one process, so the volume is the one-process
run's, bit for bit, when the workers' devices are the host's kind.

Every set ships each of its tiles' state (halo included) to a worker and the updated voxels
back: meant for tiles large enough that their compute outweighs that.

Dask is an optional extra: ``pip install "clsolid[dask]"``.
"""

from __future__ import annotations

import contextlib
import threading
import uuid
from typing import Any, Iterable, Iterator

import numpy as np

from ..errors import InputError, NoDeviceError
from .model import ScaleModel
from .params import MLParams
from .contracts import TileJob, TileResult
from .tiled import check_tile, run_tile

#: Voxels of the random start one task draws (16 MB of float32).
_INIT_RUN = 1 << 22

INSTALL = 'pip install "clsolid[dask]"'


def require_distributed():
    """The ``distributed`` module; an :class:`~clsolid.errors.InputError` saying what to install
    when it is missing."""
    try:
        import distributed
    except ImportError as exc:
        raise InputError(f"running on Dask workers needs dask.distributed, which is not installed ({exc}): "
                         f"{INSTALL}") from None
    return distributed


@contextlib.contextmanager
def dask_client(scheduler: str | None = None, workers: int | None = None):
    """A ``distributed.Client`` for the CLI: connected to the scheduler at *scheduler*, or to a
    ``LocalCluster`` of *workers* processes of one thread each; closed (cluster and all) on exit."""
    distributed = require_distributed()
    if scheduler is not None:
        with distributed.Client(scheduler) as client:
            yield client
        return
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"workers={workers!r} must be a positive integer (local worker processes)")
    # A free port for the scheduler's web pages (None would mean 8787, perhaps another cluster's).
    with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:
        yield client


# -- on the workers -------------------------------------------------------------------------

_DEVICES: dict = {}  # device spec -> Device, opened once per worker process
_ENGINES: dict = {}  # scale token -> CLBackend holding that scale's tables
_KEEP = 2  # scales' engines a worker keeps (two runs sharing the cluster need not rebuild every set)
_LOCK = threading.Lock()  # one engine's buffers serve one task at a time


def _engine(spec: str | None, options: dict):
    from ..core.device import select_device
    from .opencl import CLBackend

    if spec not in _DEVICES:
        _DEVICES[spec] = select_device(spec)
    return CLBackend(_DEVICES[spec], **options)


def _scale_engine(token: str, tables: tuple, spec: str | None, options: dict):
    """This process's engine for the scale *token*, built from its *tables* on first use."""
    engine = _ENGINES.get(token)
    if engine is None:
        while len(_ENGINES) >= _KEEP:
            _ENGINES.pop(next(iter(_ENGINES)))
        model, params, block = tables
        engine = _ENGINES[token] = _engine(spec, options)
        engine.load_scale(model, params, block)
    return engine


def tile_task(token: str, tables: tuple, spec: str | None, options: dict, sweep: tuple,
              job: TileJob) -> TileResult:
    """A Dask task: relax one tile's voxels of a set with the sweep's arguments *sweep*."""
    with _LOCK:
        engine = _scale_engine(token, tables, spec, options)
        engine.start_sweep(*sweep)
        return run_tile(engine, job)


def device_name(spec: str | None, options: dict) -> str:
    """A Dask task: the name of the device this worker runs on."""
    with _LOCK:
        return _engine(spec, options).name


def check_task(spec: str | None, options: dict, models: list[ScaleModel], edge: int,
               params: MLParams | None = None) -> None:
    """A Dask task: :func:`clsolid.ml.tiled.check_tile` on this worker's device."""
    with _LOCK:
        check_tile(_engine(spec, options), models, edge, params)


def init_task(spec: str | None, options: dict, shape, seed: int, pixels: np.ndarray, first: int,
              count: int) -> np.ndarray:
    """A Dask task: *count* voxels from flat index *first* of the random start
    (:meth:`clsolid.ml.opencl.CLBackend.init_part`)."""
    with _LOCK:
        return _engine(spec, options).init_part(shape, seed, pixels, first, np.empty(count, np.float32))


# -- on the host ----------------------------------------------------------------------------


def device_spec(device) -> str | None:
    """What a worker opens for *device*: a spec string as given (or None: clsolid's choice on
    each worker), or the ``"platform:device"`` index of a :class:`~clsolid.core.device.Device`
    (the same device where the workers share this machine's OpenCL platforms)."""
    from ..core.device import Device, device_index

    if device is None or isinstance(device, str):
        return device
    if isinstance(device, Device):
        return device_index(device)
    raise InputError(f"device={device!r} must be a device spec string, a Device or None for Dask workers")


class DaskTiles:
    """Runs the tiles of each set as tasks on the workers of a ``distributed.Client``.

    Parameters
    ----------
    client : distributed.Client
    device : str, Device or None
        The device each worker opens (:func:`device_spec`); None: clsolid's choice on each.
    **options
        The workers' :class:`~clsolid.ml.opencl.CLBackend` options (``vector_width`` ...).
    """

    def __init__(self, client: Any, device=None, **options) -> None:
        require_distributed()
        self.client, self.spec, self.options = client, device_spec(device), options
        workers = list(client.scheduler_info().get("workers", {}))
        if not workers:
            raise NoDeviceError("the Dask cluster has no workers: start some (dask worker ADDRESS), or use --workers N")
        self.workers = workers
        self.parallel = len(workers)  # tiles run at once, at most (the tiles' search time shared among them)
        self.keeps_state = False  # each set's tiles go to whichever worker is free
        names = sorted(set(self._on_each(device_name, self.spec, options)))
        self.name = names[0] if len(names) == 1 else "; ".join(names)
        self.token = self.tables = self.sweep = None

    def _on_each(self, function, *args) -> list:
        """*function*(*args*) on every worker, as tasks; their results."""
        futures = [self.client.submit(function, *args, workers=[w], allow_other_workers=False, pure=False)
                   for w in self.workers]
        return self.client.gather(futures)

    def prepare(self, models: list[ScaleModel], edge: int, params: MLParams | None = None) -> None:
        """Refuse tiles whose buffers (for a run of *params*) exceed some worker's device (checked there)."""
        self._on_each(check_task, self.spec, self.options, models, edge, params)

    def init_volume(self, shape, seed: int, pixels: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """The random start, drawn by the workers a run of voxels each (a few runs in flight, so
        neither side holds the whole block), into *out* (such as a scratch file's) if given."""
        out = np.empty(shape, np.float32) if out is None else out
        flat = out.reshape(-1)
        runs = [(first, min(_INIT_RUN, flat.size - first)) for first in range(0, flat.size, _INIT_RUN)]
        window = 2 * max(1, len(self.client.scheduler_info()["workers"]))
        for lo in range(0, len(runs), window):
            batch = [(first, self.client.submit(init_task, self.spec, self.options, tuple(shape), seed, pixels,
                                                first, count, pure=False)) for first, count in runs[lo: lo + window]]
            for first, future in batch:  # the batch's tasks run at once; each result is waited for in turn
                part = future.result()
                flat[first: first + part.size] = part
        return out

    def load_scale(self, model: ScaleModel, params: MLParams, block) -> None:
        """Send the scale's tables to every worker (each builds its engine on its first tile)."""
        self.token = f"clsolid-scale-{uuid.uuid4().hex}"
        [self.tables] = self.client.scatter([(model, params, tuple(block))], broadcast=True, hash=False)

    def start_sweep(self, seed: int, tag: int, t_in: float, bias: np.ndarray, relaxation: str | None = None) -> None:
        self.sweep = (seed, tag, float(t_in), np.array(bias, np.float64), relaxation)

    def map(self, jobs: Iterable[TileJob]) -> Iterator[TileResult]:
        """Every job as a task at once; their results in the jobs' order."""
        futures = [self.client.submit(tile_task, self.token, self.tables, self.spec, self.options, self.sweep, job,
                                      pure=False) for job in jobs]
        return iter(self.client.gather(futures))
