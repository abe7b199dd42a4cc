"""What the likelihood driver asks of a back end, and what a tiled back end asks of its runner.

Three back ends do the per-voxel work of :func:`clsolid.ml.driver.run_ml`: the float64
reference (:class:`~clsolid.ml.reference.ReferenceBackend`), one OpenCL device
(:class:`~clsolid.ml.opencl.CLBackend`) and that device a tile at a time
(:class:`~clsolid.ml.tiled.TiledBackend`). A tiled back end hands each conflict-free set's
tiles to a runner: :class:`~clsolid.ml.tiled.LocalTiles` (one engine, in this process) or
:class:`~clsolid.ml.distributed.DaskTiles` (Dask workers). Each side is written down here, so
that a new one knows what to provide and nothing is probed for at run time.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Iterable, Iterator, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:
    from ..core.scratch import Scratch
    from .model import ScaleModel
    from .params import MLParams


@dataclass
class TileJob:
    """What a tile needs to relax its voxels of one set: its state, halo included (gathered
    by :func:`clsolid.core.tiles.gather`), where it lies, the voxels (the tile's flat
    indices) and the balance's score rows of those voxels that have one."""

    volume: np.ndarray | None  # None: the engine holds the tile's current state already (resident)
    temperature: np.ndarray | None
    sources: np.ndarray | None
    origin: tuple[int, int, int]
    voxels: np.ndarray
    score_rows: np.ndarray
    parent: np.ndarray | None = None  # the tile's parent block, halo included (parent terms only)


@dataclass
class TileResult:
    """What a tile gives back: its voxels' values, temperatures and sources ``(views, m)``,
    the rows of scores asked for, the visits it made with each sum ``(exact, pruned)`` and the
    seconds its projected search took."""

    values: np.ndarray
    temperatures: np.ndarray
    sources: np.ndarray
    scores: np.ndarray
    visits: tuple[int, int]
    searched: float = 0.0


@runtime_checkable
class Backend(Protocol):
    """A back end of :func:`~clsolid.ml.driver.run_ml`."""

    #: The device, as a result records it.
    name: str
    #: Where the whole block's state lives when the back end keeps it on the host (a tiled
    #: run's, in memory or on disk); None: in the back end itself.
    scratch: Scratch | None
    #: Seconds spent in the projected candidate search so far (the ETA's rate).
    search_seconds: float
    #: Voxel visits summed exactly and pruned so far.
    exact_visits: int
    pruned_visits: int

    def prepare(self, models: list[ScaleModel], params: MLParams | None = None) -> None:
        """Refuse, before allocating, what the device cannot hold at some scale of *models*."""

    def init_volume(self, shape: tuple[int, int, int], seed: int, pixels: np.ndarray) -> np.ndarray:
        """The random start: exemplar pixels drawn by Philox on (seed, voxel)."""

    def start_scale(self, model: ScaleModel, vol: np.ndarray, temp: np.ndarray, params: MLParams,
                    sources: np.ndarray | None = None, parent: np.ndarray | None = None) -> None:
        """Take a scale's tables and its start state."""

    def start_sweep(self, seed: int, tag: int, t_in: float, bias: np.ndarray, relaxation: str | None = None) -> None:
        """The arguments of the sweep's sets (random stream, global temperature, balance bias,
        and the relaxation where it is not the run's: ``"icm"`` in a polish sweep)."""

    def update(self, voxels: np.ndarray) -> None:
        """Relax one conflict-free set of voxels (flat indices)."""

    def values(self, voxels: np.ndarray) -> np.ndarray:
        """The current values of some voxels."""

    def read_scores(self, rows: np.ndarray) -> np.ndarray:
        """Some rows of the balance's scores of the last set."""

    def volume(self) -> np.ndarray:
        """The block's current values."""

    def temperature(self) -> np.ndarray:
        """The block's current temperatures."""

    def sources(self) -> np.ndarray:
        """Each voxel's source site per view, ``(views, voxels)`` (-1: none yet)."""


@runtime_checkable
class TileRunner(Protocol):
    """Runs the tiles of a set for :class:`~clsolid.ml.tiled.TiledBackend`."""

    name: str
    #: Whether the engine that ran the last tile still holds that tile's state (one engine
    #: runs every tile): the next set's same tile need not be sent again.
    keeps_state: bool
    #: Tiles run at once, at most (their projected search time is shared among them).
    parallel: int

    def prepare(self, models: list[ScaleModel], edge: int, params: MLParams | None = None) -> None:
        """Refuse tiles of *edge* whose buffers exceed the device(s)."""

    def init_volume(self, shape: tuple[int, int, int], seed: int, pixels: np.ndarray,
                    out: np.ndarray | None = None) -> np.ndarray:
        """The random start, into *out* if given."""

    def load_scale(self, model: ScaleModel, params: MLParams, block: tuple[int, int, int]) -> None:
        """Take a scale's tables, with buffers for tiles of *block* voxels."""

    def start_sweep(self, seed: int, tag: int, t_in: float, bias: np.ndarray, relaxation: str | None = None) -> None:
        """As :meth:`Backend.start_sweep`."""

    def map(self, jobs: Iterable[TileJob]) -> Iterator[TileResult]:
        """The jobs' results, in their order."""
