"""A level's block on the matcher's device, for the kernels that gather the voxels' queries
there (``kernels/search/gather.cl``: ``voxel_queries`` for the exhaustive search, and
``coherence_best``): sending the block, 4 bytes a voxel, costs far less than gathering a
set's k x k squares on the host and sending those (docs/design.md#queries-gathered-on-the-device)."""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from ..core.launch import launch
from ..core import programs
from ..core.views import VIEW_AXES
from ..errors import DeviceMemoryError
from .match import LOCAL, CLMatcher
from .projection import Projection


class DeviceBlock:
    """The block, its coarser level and a set's voxels on *matcher*'s device (room made at
    the first :meth:`send`).

    The block is sent with every set (the method changes it between sets), the coarser
    level once (it does not change during a level), the voxels with every set.
    """

    def __init__(self, matcher: CLMatcher) -> None:
        self.matcher = matcher
        self._vol, self._vol_room = None, 0
        self._coarse, self._coarse_of = None, None
        self._voxels, self._room = None, 0

    def send(self, vol: np.ndarray, coarse: np.ndarray | None, voxels: np.ndarray) -> tuple[Any, ...]:
        """Send *vol*, *coarse* (if new) and *voxels*; returns the kernels' leading arguments:
        ``(vol, vz, vy, vx, coarse, cz, cy, cx)``, then the voxels' buffer."""
        import pyopencl as cl

        device = self.matcher.device
        queue, ctx, mf = device.queue, device.context, cl.mem_flags
        if vol.size > self._vol_room:
            if 4 * vol.size > device.max_alloc:  # float32 a voxel
                raise DeviceMemoryError("search block", 4 * vol.size, device.max_alloc)
            self._vol, self._vol_room = cl.Buffer(ctx, mf.READ_ONLY, 4 * vol.size), vol.size
        cl.enqueue_copy(queue, self._vol, np.ascontiguousarray(vol, np.float32))
        if voxels.size > self._room:
            self._room = voxels.size
            self._voxels = cl.Buffer(ctx, mf.READ_ONLY, 4 * voxels.size)
        cl.enqueue_copy(queue, self._voxels, np.ascontiguousarray(voxels, np.int32))
        if coarse is None:
            coarse_buf, cshape = self._vol, (1, 1, 1)  # not read (PARENT = 0)
        else:
            if coarse is not self._coarse_of:
                self._coarse = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR,
                                         hostbuf=np.ascontiguousarray(coarse, np.float32))
                self._coarse_of = coarse
            coarse_buf, cshape = self._coarse, coarse.shape
        return (self._vol, *map(np.int32, vol.shape), coarse_buf, *map(np.int32, cshape)), self._voxels

    def _gatherer(self, view: str, voxels: np.ndarray, vol: np.ndarray, coarse: np.ndarray | None, k: int,
                  **defines: int) -> tuple[dict, Callable[[int, int], None]]:
        """Send the block and *voxels*, and build ``kernels/search/gather.cl`` (a small program
        of its own: the same for every weighting and every count; *defines* added). Returns
        its kernels and ``gather(start, n)``, which writes the queries of voxels ``start`` to
        ``start + n`` in *view* into the matcher's :attr:`~CLMatcher.query_buffer`."""
        matcher = self.matcher
        leading, voxels_buf = self.send(vol, coarse, voxels)
        program = programs.build(matcher.device, "search/gather.cl",
                                 {"QDIM": matcher.dim, "KSIDE": k, "PARENT": int(coarse is not None), **defines})
        axes = tuple(map(np.int32, VIEW_AXES[view]))

        def gather(start: int, n: int) -> None:
            launch(matcher.device, program["voxel_queries"], n, LOCAL, *leading, *axes,
                   voxels_buf, np.int32(start), np.int32(n), matcher.query_buffer)

        return program, gather

    def best(self, view: str, voxels: np.ndarray, vol: np.ndarray, coarse: np.ndarray | None, k: int,
             weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The exhaustive best match of *voxels* of *vol* (as the matcher compares it; *coarse*
        its parent level, scaled as the table's parents are) in *view*, their queries gathered
        on the device: :meth:`CLMatcher.best` of
        :func:`~clsolid.search.features.voxel_features`. Returns ``(site (m,) int64,
        distance (m,) float32)``."""
        self.matcher.layout(weights)
        _, gather = self._gatherer(view, voxels, vol, coarse, k)
        site, dist = self.matcher.nearest_filled(voxels.size, 1, gather)
        return site[:, 0], dist[:, 0]

    def best_projected(self, view: str, voxels: np.ndarray, vol: np.ndarray, coarse: np.ndarray | None, k: int,
                       projection: Projection) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`best`, the sites compared on *projection*'s principal components: the
        queries gathered, then projected (``project_queries``), on the device; each found
        site's distance on every term (:meth:`Projection.distances`). Returns ``(site (m,)
        int64, distance (m,) float32)``."""
        import pyopencl as cl

        matcher, queue = self.matcher, self.matcher.device.queue
        projected, basis, offset = projection.on_device(matcher)
        program, gather = self._gatherer(view, voxels, vol, coarse, k, COMPONENTS=projection.components)
        queries = np.empty((voxels.size, matcher.dim), np.float32)  # read back for the distances

        def fill(start: int, n: int) -> None:
            gather(start, n)
            launch(matcher.device, program["project_queries"], n, LOCAL, matcher.query_buffer, np.int32(n),
                   basis, offset, projected.query_buffer)
            cl.enqueue_copy(queue, queries[start : start + n], matcher.query_buffer)

        site = projected.nearest_filled(voxels.size, 1, fill)[0][:, 0]
        return site, projection.distances(queries, site)
