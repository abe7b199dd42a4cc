"""Tiles (issue 12, point 2): a volume larger than the device holds, synthesised a tile at a time.

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
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.tiles import Tiling, gather
from ..errors import DeviceMemoryError, InputError
from .model import ScaleModel
from .params import MLParams
from .pruned import COHERENCE_REACH


def halo_width(model: ScaleModel) -> int:
    """How far from a voxel the kernels read while updating it: the views' neighbourhoods
    (values and temperatures) and the pruned sum's window of sources."""
    return max(int(np.abs(model.union_offsets).max()), COHERENCE_REACH)


def scale_tiling(model: ScaleModel, edge: int) -> Tiling:
    """The tiles of a scale: cores at most *edge* on a side, with the scale's halo."""
    return Tiling(model.shape, edge, halo_width(model))


def check_tile(engine: Any, models: list[ScaleModel], edge: int) -> None:
    """Refuse (:class:`~clsolid.errors.DeviceMemoryError`), before allocating, tiles of *edge*
    whose buffers exceed the device's limits at some scale of *models* (the *engine*'s
    ``check_memory``); the message names the tile and what to do."""
    for model in models:
        block = scale_tiling(model, edge).largest_block
        try:
            engine.check_memory(model, block)
        except DeviceMemoryError as exc:
            raise exc.advised(
                f"with tile={edge} the device holds {'x'.join(map(str, block))} voxels (a tile and its halo "
                f"of {halo_width(model)}) of the {'x'.join(map(str, model.shape))} scale: use a smaller tile "
                "(tile=, --tile)") from None


def largest_tile(engine: Any, models: list[ScaleModel]) -> int | None:
    """The largest tile edge whose buffers fit the device at every scale of *models*; None
    where none does (the exemplar's tables alone are too large)."""

    def fits(edge: int) -> bool:
        try:
            check_tile(engine, models, edge)
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


class TiledBackend:
    """Runs :func:`clsolid.ml.driver.run_ml` a tile at a time; the same interface as
    :class:`clsolid.ml.opencl.CLBackend`, and the same volume.

    Parameters
    ----------
    engine : CLBackend
        Holds a scale's tables and one tile's state on its device.
    tile : int
        Most voxels on a side of a tile's core; each tile takes a halo of the
        neighbourhood's half-width on top (:func:`halo_width`).
    """

    def __init__(self, engine: Any, tile: int) -> None:
        if isinstance(tile, bool) or not isinstance(tile, (int, np.integer)) or tile < 1:
            raise InputError(f"tile={tile!r} must be a positive integer (voxels on a side of a tile)")
        self.engine, self.tile = engine, int(tile)
        self.name = engine.name

    @property
    def exact_visits(self) -> int:
        return self.engine.exact_visits

    @property
    def pruned_visits(self) -> int:
        return self.engine.pruned_visits

    def prepare(self, models: list[ScaleModel]) -> None:
        """Refuse, before allocating anything, tiles whose buffers exceed the device limits."""
        check_tile(self.engine, models, self.tile)

    def init_volume(self, shape, seed: int, pixels: np.ndarray) -> np.ndarray:
        """The random start (see :meth:`clsolid.ml.opencl.CLBackend.init_volume`)."""
        return self.engine.init_volume(shape, seed, pixels)

    def start_scale(self, model: ScaleModel, vol: np.ndarray, temp: np.ndarray, params: MLParams,
                    sources: np.ndarray | None = None) -> None:
        """Upload a scale's tables, and keep its state on the host; *sources* as for
        :meth:`clsolid.ml.opencl.CLBackend.start_scale`."""
        self.tiling = scale_tiling(model, self.tile)
        self.engine.load_scale(model, params, self.tiling.largest_block)
        views = model.offsets.shape[0]
        self._vol = np.array(vol, np.float32)
        self._temp = np.array(temp, np.float32)
        self._src = (np.full((views,) + model.shape, -1, np.int32) if sources is None
                     else np.array(sources, np.int32).reshape((views,) + model.shape))

    def start_sweep(self, seed: int, tag: int, t_in: float, bias: np.ndarray) -> None:
        """As :meth:`clsolid.ml.opencl.CLBackend.start_sweep`."""
        self.engine.start_sweep(seed, tag, t_in, bias)

    def update(self, voxels: np.ndarray) -> None:
        """Relax one conflict-free set of voxels (flat indices), tile by tile."""
        e, src = self.engine, self.sources()
        for tile, part in self.tiling.group(voxels):
            e.load_state(gather(self._vol, tile), gather(self._temp, tile), gather(self._src, tile), tile.origin)
            local = tile.local(part)
            e.update(local)
            self._vol.flat[part], self._temp.flat[part], src[:, part] = e.read_voxels(local)

    def volume(self) -> np.ndarray:
        return self._vol

    def temperature(self) -> np.ndarray:
        return self._temp

    def sources(self) -> np.ndarray:
        """Each voxel's source site per view, ``(views, voxels)`` (-1: none yet)."""
        return self._src.reshape(self._src.shape[0], -1)

    def scores(self) -> np.ndarray:
        """As :meth:`clsolid.ml.opencl.CLBackend.scores`: the whole volume's slots."""
        return self.engine.scores()
