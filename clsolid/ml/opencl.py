"""OpenCL back end of the ML method: device buffers and kernel launches, one scale at a time."""

from __future__ import annotations

import functools
import re
import time

import numpy as np

from ..core import programs
from ..core.launch import launch
from ..balance import n_score_slots, score_stride
from ..core.device import Device
from ..errors import DeviceMemoryError, InputError
from .model import ScaleModel
from .params import RELAXATIONS, MLParams
from ..core.philox import TAG_INIT, sample_tag, seed_key
from ..core.probe import VECTOR_WIDTHS, probe
from . import pruned
from .pruned import source_of_site
from .tiled import largest_tile

_F4 = 4  # bytes per float32 / int32
_INIT_RUN = 1 << 24  # most voxels the random start draws per launch
#: The likelihood program's sources, built as one program in this order (each needs those before it).
SOURCES = ("ml/common.cl", "ml/exact.cl", "ml/pruned.cl", "ml/relax.cl")
_C_TYPES = {"int": np.int32, "uint": np.uint32, "float": np.float32}


@functools.lru_cache(maxsize=None)
def scalar_dtype() -> np.dtype:
    """The NumPy twin of the kernels' scalar block ``ml_scalars`` (kernels/ml/common.cl), read from
    its definition there, so that the two cannot disagree: fields in order, all 4-byte (no padding)."""
    source = programs.read_source("ml/common.cl")
    body = re.search(r"typedef struct \{(.*?)\} ml_scalars;", source, re.S).group(1)
    fields = []
    for decl in re.sub(r"/\*.*?\*/", "", body, flags=re.S).split(";"):
        if decl.strip():
            kind, names = decl.split(None, 1)
            fields += [(name.strip(), _C_TYPES[kind]) for name in names.split(",")]
    return np.dtype(fields)


def _group_table(centres: np.ndarray, patches: np.ndarray, values: np.ndarray, vw: int):
    """One exemplar's sites (*centres* ``(n,)``, coded *patches* ``(R, n)``) sorted by centre value,
    each a group of *values*, and padded per group to whole vectors (see :func:`group_tables`)."""
    group_of_site = np.searchsorted(values, centres)
    counts = np.bincount(group_of_site, minlength=values.size)
    order = np.argsort(group_of_site, kind="stable")
    chunks_per_group = -(-counts // vw)
    chunk_group = np.repeat(np.arange(values.size), chunks_per_group).astype(np.int32)
    first_chunk = np.concatenate([[0], np.cumsum(chunks_per_group)[:-1]])
    group_start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    rank = np.arange(centres.size) - group_start[group_of_site[order]]  # position within group
    slot = first_chunk[group_of_site[order]] * vw + rank  # padded position of each sorted site
    n_chunks = chunk_group.size
    padded = np.zeros((patches.shape[0], n_chunks * vw), np.float32)
    padded[:, slot] = patches[:, order]
    chunk_valid = np.minimum(vw, counts[chunk_group] - (np.arange(n_chunks) - first_chunk[chunk_group]) * vw)
    chunk_site = np.zeros(n_chunks * vw, np.int32)
    chunk_site[slot] = order
    return padded.reshape(-1, n_chunks, vw).transpose(1, 0, 2), chunk_group, chunk_valid.astype(np.int32), chunk_site


def group_tables(model: ScaleModel, vw: int):
    """Exemplar sites sorted by centre value and padded per group to whole vectors; with an
    exemplar per view, each view's in turn, every view's groups one set of values.

    Returns ``patches`` ``(chunks, R, vw)`` float32, ``chunk_group`` and ``chunk_valid``
    (int32 per chunk), the group values (float32, ascending), ``chunk_site``
    ``(chunks * vw,)`` int32, the site in each lane (0 in padding lanes), and
    ``view_chunks`` ``(views, 2)`` int32, the chunks each view sums over (all, with one exemplar).
    """
    values = np.unique(model.centres)
    views = model.offsets.shape[0]
    parts = [_group_table(model.centres[s], model.coded(model.patches[:, s]), values, vw)
             for s in (model.sites_of(v) for v in (range(views) if model.per_view else [0]))]
    sizes = np.array([p[1].size for p in parts])
    begin = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    if model.per_view:
        view_chunks = np.stack([begin, begin + sizes], axis=1)
        site_start = [model.sites_of(v).start for v in range(views)]
    else:
        view_chunks = np.tile([0, sizes[0]], (views, 1))
        site_start = [0]
    patches = np.concatenate([p[0] for p in parts]).copy()
    chunk_site = np.concatenate([p[3] + start for p, start in zip(parts, site_start)]).astype(np.int32)
    return (patches, np.concatenate([p[1] for p in parts]), np.concatenate([p[2] for p in parts]),
            values.astype(np.float32), chunk_site, view_chunks.astype(np.int32))


class CLBackend:
    """Runs the per-voxel work of :func:`clsolid.ml.driver.run_ml` on an OpenCL device.

    Parameters
    ----------
    device : Device
    vector_width : int or None
        Exemplar sites per vector in the distance kernel (4, 8 or 16); None: the widest
        the device's compiler handles (found by :func:`clsolid.core.probe.probe`; 16 on most).
    voxels_per_item : int
        Voxel-views per work item; they share each exemplar load.
    local_size : int
        Work-group size. The result does not depend on it. On a CPU device the kernels that
        keep per-item arrays (the decision, the pruned sum and its flags) use at most 4: a
        CPU runtime that vectorises a work-group across its items turns those arrays into
        gathers, which cost more than the wider work-group gains.
    max_batch : int
        Most voxels relaxed per launch (bounds the scratch buffer).
    """

    #: The state lives on the device.
    scratch = None

    def __init__(self, device: Device, *, vector_width: int | None = None, voxels_per_item: int = 4,
                 local_size: int = 16, max_batch: int = 32768):
        if vector_width is None:
            vector_width = probe(device.device).vector_width or VECTOR_WIDTHS[0]
        for name, value, allowed in (("vector_width", vector_width, (4, 8, 16)),
                                     ("voxels_per_item", voxels_per_item, (1, 2, 4, 8))):
            if value not in allowed:  # the kernel is written for exactly these
                raise InputError(f"{name}={value!r} must be one of {allowed}")
        for name, value in (("local_size", local_size), ("max_batch", max_batch)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise InputError(f"{name}={value!r} must be a positive integer")
        self.device = device
        self.vw, self.vb, self.local, self.max_batch = vector_width, voxels_per_item, local_size, max_batch
        self.item_local = min(local_size, 4) if device.is_cpu else local_size
        self.name = device.name
        self.exact_visits = self.pruned_visits = 0  # voxel visits by sum, in the pruned mode
        self.search_seconds = 0.0  # spent in the projected search (its sweeps cost more: the ETA's rate)

    # -- memory ------------------------------------------------------------------------
    def buffer_sizes(self, model: ScaleModel, n_labels: int, block=None,
                     params: MLParams | None = None) -> dict[str, int]:
        """Bytes of every device buffer a scale needs, its state (volume, temperatures,
        sources) held for a *block* ``(Z, Y, X)``: the whole volume (default), or one tile
        with its halo (:mod:`clsolid.ml.tiled`). With *params* of a pruned run, its tables too,
        counted as if every site's window were distinct (they are found only when built)."""
        n_vox = int(np.prod(model.shape if block is None else block))
        views, nr = model.offsets.shape[:2]
        chunks = int(np.sum(-(-np.bincount(np.unique(model.centres, return_inverse=True)[1]) // self.vw)))
        batch = min(self.max_batch, n_vox)
        sizes = {
            "volume": model.state_blocks * n_vox * _F4,
            "temperature": model.state_blocks * n_vox * _F4,
            "exemplar patches": chunks * nr * model.channels * self.vw * _F4,
            "group log-sums": batch * views * self._pad(n_labels) * _F4,
            "voxel indices": batch * _F4,
            "packed state": batch * (2 + views) * _F4,
            "balance scores": n_score_slots(model.shape) * n_labels * _F4,
            "sources": views * n_vox * _F4,
        }
        if params is not None and params.likelihood == "pruned":
            sizes.update(_pruned_sizes(model, params, batch))
        return sizes

    def check_memory(self, model: ScaleModel, block=None, params: MLParams | None = None) -> None:
        """Refuse (:class:`~clsolid.errors.DeviceMemoryError`), before allocating anything, a
        scale whose buffers (see :meth:`buffer_sizes`) exceed the device limits."""
        sizes = self.buffer_sizes(model, model.labels.size, block, params)
        for name, nbytes in sizes.items():
            if nbytes > self.device.max_alloc:
                raise DeviceMemoryError(name, nbytes, self.device.max_alloc)
        total = sum(sizes.values())
        if total > self.device.global_mem:
            raise DeviceMemoryError("all buffers together", total, self.device.global_mem, "global_mem_size")

    def prepare(self, models: list[ScaleModel], params: MLParams | None = None) -> None:
        """Refuse, before allocating anything, a run (of *params*) whose buffers exceed the
        device limits; where tiles would fit, the error says which (``tile=``, ``--tile``)."""
        try:
            for model in models:
                self.check_memory(model, None, params)
        except DeviceMemoryError as exc:
            edge = largest_tile(self, models, params)
            if edge is None:  # the exemplar's tables alone are too large
                raise
            raise exc.advised(f"synthesize it in tiles: tile={edge} (--tile {edge}) is the largest that fits, "
                              "and gives the same volume") from None

    # -- kernels -----------------------------------------------------------------------
    def _kernels(self, model: ScaleModel, n_labels: int, projected: pruned.ProjectedWindows | None = None) -> dict:
        """The likelihood program for *model*; *projected*: the pruned sum's projected candidates, if any.

        Only what changes the code is compiled in (array sizes, which terms exist); the exemplar's
        tables and every size are arguments, so one build serves every exemplar of the same options."""
        views, nr = model.offsets.shape[:2]
        p = self.params
        return programs.build(self.device, SOURCES, {
            "NR": nr, "NCHILD": nr - model.parent_rows,  # the rows after NCHILD: parent terms
            "VW": self.vw, "VB": self.item_vb, "NLV": -(-n_labels // self.vw), "NVIEW": views,
            "NS": p.n_similar if p.likelihood == "pruned" else 1,
            # PROJ_P: the option, not projected.probe (which a small exemplar's fewer lists clamp):
            # the kernel stops at the last list there is
            **({"PROJ_K": p.prune_projected_k, "PROJ_D": projected.axes.shape[1],
                "PROJ_P": max(p.prune_projected_probe, 1)} if projected is not None else {}),
            "MISMATCH": 2 if model.costs is not None else int(model.mismatch),
            "NCH": model.channels,
            "TERM_WEIGHTS": int(model.term_weight is not None),
        })

    def _set_scalars(self, **fields) -> None:
        """Set *fields* of the kernels' scalar block (``ml_scalars``) and copy it to the device; the
        copy blocks, and the queue is in order, so launches already queued read the old values."""
        import pyopencl as cl

        for name, value in fields.items():
            self.scalars[name] = value
        cl.enqueue_copy(self.device.queue, self.scalars_buf, self.scalars)

    def _pad(self, n: int) -> int:
        return -(-n // self.vw) * self.vw

    def _buf(self, array: np.ndarray, writable: bool = False):
        import pyopencl as cl

        mf = cl.mem_flags
        flags = (mf.READ_WRITE if writable else mf.READ_ONLY) | mf.COPY_HOST_PTR
        return cl.Buffer(self.device.context, flags, hostbuf=np.ascontiguousarray(array))

    # -- the back-end interface ----------------------------------------------------------
    def init_volume(self, shape, seed: int, pixels: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Random exemplar pixels, drawn by Philox on (seed, x, y, z) in a kernel, in runs of
        voxels that fit one buffer (the volume may be larger than the device holds); into
        *out* (float32 of *shape*, such as a scratch file's) if given."""
        n = int(np.prod(shape))
        out = np.empty(shape, np.float32) if out is None else out
        flat = out.reshape(n)  # a view: written through, memory-mapped or not
        run = max(1, min(n, self.device.max_alloc // _F4, _INIT_RUN))
        for first in range(0, n, run):
            self.init_part(shape, seed, pixels, first, flat[first: first + run])
        return out  # float32, as on the device: start_state widens one scale at a time

    def init_part(self, shape, seed: int, pixels: np.ndarray, first: int, part: np.ndarray) -> np.ndarray:
        """Voxels ``first, first + 1, ...`` (flat) of :meth:`init_volume`'s random start, into
        the float32 array *part* (as many as it holds, at most a buffer's worth), returned."""
        import pyopencl as cl

        k = programs.build(self.device, "core/init.cl")
        buf = cl.Buffer(self.device.context, cl.mem_flags.WRITE_ONLY, part.size * _F4)
        key = seed_key(seed)
        px = self._buf(pixels.astype(np.float32).ravel())
        launch(self.device, k["init_random"], part.size, self.local, buf,
               np.int32(shape[0]), np.int32(shape[1]), np.int32(shape[2]), np.int64(first),
               np.int32(part.size), np.uint32(key[0]), np.uint32(key[1]), np.uint32(TAG_INIT), px,
               np.uint32(pixels.size))
        cl.enqueue_copy(self.device.queue, part, buf)
        return part

    def start_scale(self, model: ScaleModel, vol: np.ndarray, temp: np.ndarray, params: MLParams,
                    sources: np.ndarray | None = None, parent: np.ndarray | None = None) -> None:
        """Upload a scale's tables and state; *sources* ``(views, voxels)``: each voxel's source
        site per view (a resumed run's; default: none yet, -1); *parent*: the parent block
        (:func:`clsolid.ml.model.parent_block`) of a model with parent rows."""
        self.load_scale(model, params)
        self.load_state(vol, temp, sources, parent=parent)

    def load_scale(self, model: ScaleModel, params: MLParams, block=None) -> None:
        """Upload a scale's tables and allocate its buffers, the state's for a *block*
        ``(Z, Y, X)``: the whole volume (default), or the largest tile with its halo. The
        memory is checked first. :meth:`load_state` then gives the state."""
        import pyopencl as cl

        n_labels = model.labels.size
        block = tuple(model.shape if block is None else block)
        self.check_memory(model, block, params)
        self.model, self.params = model, params
        self.capacity = int(np.prod(block))
        canon = source_of_site(model)
        pruning = pruned.Pruning(model, params, canon) if params.likelihood == "pruned" else None
        # a work item's voxel-views share each chunk they load: with an exemplar per view, one per item
        self.item_vb = 1 if model.per_view else self.vb
        self.k = self._kernels(model, n_labels, None if pruning is None else pruning.projected)
        patches, chunk_group, chunk_valid, gvals, chunk_site, view_chunks = group_tables(model, self.vw)
        self.chunk_site = self._buf(canon[chunk_site])  # the source each lane records
        views = model.offsets.shape[0]
        mf, ctx = cl.mem_flags, self.device.context
        self.scalars = np.zeros(1, scalar_dtype())  # the block's fields come with load_state
        self.scalars_buf = cl.Buffer(ctx, mf.READ_ONLY, self.scalars.nbytes)
        self._set_scalars(n_views=views, n_labels=n_labels, n_groups=gvals.size, n_chunks=chunk_group.size,
                          n_union=model.union_offsets.shape[0], k=1.0 / (2.0 * model.bandwidth**2), xi=params.xi,
                          heuristic=params.heuristic_code, relaxation=params.relaxation_code,
                          score_stride=score_stride(model.shape), n_sample=min(params.n_sample, model.n_sites),
                          min_weight=params.prune_min_weight, need_source=params.n_sample == 0)
        self.vol_buf = cl.Buffer(ctx, mf.READ_WRITE, model.state_blocks * self.capacity * _F4)
        self.temp_buf = cl.Buffer(ctx, mf.READ_WRITE, model.state_blocks * self.capacity * _F4)
        self.src = cl.Buffer(ctx, mf.READ_WRITE, views * self.capacity * _F4)
        self.state = (self.vol_buf, self.temp_buf, self.src)
        self.batch = batch = min(self.max_batch, self.capacity)
        if pruning is not None:
            self._start_pruned(pruning, gvals, batch)
        self.n_groups, self.n_chunks = gvals.size, chunk_group.size
        self.patches = self._buf(patches)
        self.chunk_group, self.chunk_valid = self._buf(chunk_group), self._buf(chunk_valid)
        self.exemplar = (self.patches, self.chunk_group, self.chunk_valid, self.chunk_site, self._buf(view_chunks))
        # The Gaussian factor of every (group, label) pair and its log (decide's view_logf).
        self.kern = self._buf(kernel_tables(model, gvals, self._pad(n_labels)))
        self.labels = self._buf(model.labels.astype(np.float32))
        self.offsets = self._buf(model.offsets.astype(np.int32))
        # The window terms: offsets, each term's weight's square root and each label's cost, or
        # its colour's channels (a placeholder where the model has neither), in buffers so that
        # one build serves every exemplar.
        roots = np.ones(1) if model.term_weight is None else np.sqrt(model.term_weight)
        costs = model.palette if model.channels > 1 else np.zeros(1) if model.costs is None else model.costs
        self.terms = (self.offsets, self._buf(roots.astype(np.float32)), self._buf(costs.astype(np.float32)))
        self.union = self._buf(model.union_offsets.astype(np.int32))
        self.vox_buf = cl.Buffer(ctx, mf.READ_ONLY, batch * _F4)
        self.packed = (cl.Buffer(ctx, mf.WRITE_ONLY, 2 * batch * _F4),
                       cl.Buffer(ctx, mf.WRITE_ONLY, views * batch * _F4))
        self.sums = cl.Buffer(ctx, mf.READ_WRITE, batch * views * self._pad(n_labels) * _F4)
        self.bias = cl.Buffer(ctx, mf.READ_ONLY, self._pad(n_labels) * _F4)
        # The balance's scores are the whole volume's, whichever block the state holds.
        self._scores = np.zeros((n_score_slots(model.shape), n_labels), np.float32)
        self.scores_buf = self._buf(self._scores, writable=True)
        self._vol = self._temp = self._src = None  # host copies of the state, made when first read
        self.start_sweep(0, 0, 1.0, np.zeros(n_labels))

    def load_state(self, vol: np.ndarray, temp: np.ndarray, sources: np.ndarray | None = None,
                   origin: tuple[int, int, int] = (0, 0, 0), parent: np.ndarray | None = None) -> None:
        """Upload the state the next updates work on: the volume and temperatures of a block
        (the whole volume, or a tile with its halo whose first voxel lies at *origin* of the
        whole, see :mod:`clsolid.core.tiles`), and each voxel's sources ``(views, voxels)``
        (default: none yet, -1), and the block's *parent* block where the model has parent rows
        (:meth:`clsolid.ml.model.ScaleModel.with_parent`). Updates take the block's flat indices."""
        import pyopencl as cl

        q, views = self.device.queue, self.model.offsets.shape[0]
        self.block = tuple(int(n) for n in np.shape(vol))
        self.n_block = int(np.prod(self.block))
        if self.n_block > self.capacity:
            raise ValueError(f"a {self.block} block does not fit the buffers made for {self.capacity} voxels")
        (Z, Y, X), (oz, oy, ox), (GZ, GY, GX) = self.block, origin, self.model.shape
        self._set_scalars(Z=Z, Y=Y, X=X, n_vox=self.n_block, oz=oz, oy=oy, ox=ox, GZ=GZ, GY=GY, GX=GX)
        if sources is None:
            sources = np.full((views, self.n_block), -1, np.int32)
        cl.enqueue_copy(q, self.vol_buf, np.ascontiguousarray(vol, np.float32))
        cl.enqueue_copy(q, self.temp_buf, np.ascontiguousarray(temp, np.float32))
        if self.model.parent_rows:  # the parent block after the block, its temperatures 0 (model.with_parent)
            if np.size(parent) != self.n_block:
                raise ValueError(f"a model with parent terms needs the block's parent block, {self.block}")
            cl.enqueue_copy(q, self.vol_buf, np.ascontiguousarray(parent, np.float32), dst_offset=self.n_block * _F4)
            cl.enqueue_fill_buffer(q, self.temp_buf, np.float32(0), self.n_block * _F4, self.n_block * _F4)
        cl.enqueue_copy(q, self.src, np.ascontiguousarray(np.reshape(sources, (views, self.n_block)), np.int32))
        if self._vol is None or self._vol.shape != self.block:
            self._vol = np.empty(self.block, np.float32)
            self._temp = np.empty(self.block, np.float32)
            self._src = np.empty((views, self.n_block), np.int32)

    def _start_pruned(self, pruning: pruned.Pruning, gvals: np.ndarray, batch: int) -> None:
        """The pruned sum's tables: distinct windows, their similar sets, coherence offsets."""
        import pyopencl as cl

        model, table = pruning.model, pruning.table
        first = table.first_site
        ns = pruning.params.n_similar  # the kernel reads NS columns: pad a small exemplar's table
        similar = np.concatenate([table.similar, np.repeat(table.similar[:, :1], ns - table.similar.shape[1], 1)], 1)
        group = np.searchsorted(gvals, model.centres[first].astype(np.float32)).astype(np.int32)
        coded = model.coded(model.patches).T[first]  # a colour's: every neighbour's channels
        nt = coded.shape[1]
        rows = np.zeros((first.size, -(-nt // 8) * 8), np.float32)  # whole float8 vectors, zero-padded
        rows[:, :nt] = coded
        self.coherence = (self._buf(pruning.voxel_offsets), self._buf(pruning.exemplar_offsets))
        self.windows = (self._buf(table.window_of), self._buf(similar.astype(np.int32)),
                        self._buf(rows), self._buf(group),
                        self._buf(np.log(table.count).astype(np.float32)), self._buf(table.source))
        self._set_scalars(grid_rows=table.grid[0], grid_cols=table.grid[1])
        self.flags_buf = cl.Buffer(self.device.context, cl.mem_flags.WRITE_ONLY, batch * _F4)
        proj, views = pruning.projected, model.offsets.shape[0]
        k = 0 if proj is None else pruning.params.prune_projected_k
        self.projected_out = cl.Buffer(self.device.context, cl.mem_flags.READ_WRITE, max(1, batch * views * k) * _F4)
        self.projection = None if proj is None else self._projection(proj)

    def _projection(self, proj: pruned.ProjectedWindows) -> tuple:
        """The projected search's arguments: the sites sorted by list (the lower site first)."""
        order = np.argsort(proj.list_of, kind="stable")
        start = np.searchsorted(proj.list_of[order], np.arange(proj.centres.shape[0] + 1))
        self._set_scalars(n_lists=proj.centres.shape[0])
        return (self._buf(proj.scale.astype(np.float32)), self._buf(proj.mean.astype(np.float32)),
                self._buf(_float8_rows(proj.axes)), self._buf(_float8_rows(proj.centres)),
                self._buf(start.astype(np.int32)), self._buf(order.astype(np.int32)),
                self._buf(_float8_rows(proj.sites[order])), self.windows[0])

    def start_sweep(self, seed: int, tag: int, t_in: float, bias: np.ndarray, relaxation: str | None = None) -> None:
        """Random stream (Philox key *seed*, counter tag *tag*), global temperature *t_in*,
        per-label balance term *bias* and *relaxation* (None: the run's) for the updates of
        the coming sweep."""
        import pyopencl as cl

        padded = np.zeros(self._pad(self.model.labels.size), np.float32)
        padded[: bias.size] = bias
        cl.enqueue_copy(self.device.queue, self.bias, padded)
        key = seed_key(seed)
        # the projected candidates parzen_candidates reads this sweep (projected_nearest runs if any)
        self.n_projected = self.params.prune_projected_k if pruned.projects(self.params, tag) else 0
        self._set_scalars(key0=key[0], key1=key[1], tag=tag, sample_tag=sample_tag(tag), t_in=t_in,
                          n_projected=self.n_projected,
                          relaxation=RELAXATIONS.index(relaxation or self.params.relaxation))

    def update(self, voxels: np.ndarray) -> None:
        """Relax one conflict-free set of voxels (flat indices), batch by batch."""
        for i in range(0, voxels.size, self.max_batch):
            self._update_batch(voxels[i : i + self.max_batch].astype(np.int32))

    def _parzen(self, voxels: np.ndarray) -> int:
        """Upload a batch of voxels and enqueue the Parzen sums (exact, or pruned where the
        pruned mode allows); return the item count. The batch may be reordered in place:
        the voxels that need the exact sum first."""
        import pyopencl as cl

        q, m = self.device.queue, self.model
        views = m.offsets.shape[0]
        n_items = voxels.size * views
        cl.enqueue_copy(q, self.vox_buf, voxels)
        n_exact = voxels.size
        if self.params.likelihood == "pruned":  # with the default settings no voxel can need the exact sum
            n_exact = self._exact_first(voxels) if pruned.may_need_exact(self.params) else 0
        if n_exact:
            launch(self.device, self.k["parzen_groups"], -(-n_exact * views // self.item_vb), self.local,
                   self.scalars_buf, np.int32(n_exact * views), *self.state, self.vox_buf,
                   self.sums, *self.terms, *self.exemplar)
        if self.params.likelihood == "pruned":
            self.exact_visits += n_exact
            self.pruned_visits += voxels.size - n_exact
        if n_exact < voxels.size:
            items = n_items - n_exact * views
            item_range = (np.int32(n_exact * views), np.int32(n_items))
            if self.projection is not None and self.n_projected:
                q.finish()  # timed alone: the sweeps without it are the ETA's rate
                t0 = time.perf_counter()
                launch(self.device, self.k["projected_nearest"], items, self.item_local, self.scalars_buf, *item_range,
                       self.vol_buf, self.vox_buf, self.offsets, *self.projection,
                       self.projected_out)
                q.finish()
                self.search_seconds += time.perf_counter() - t0
            launch(self.device, self.k["parzen_candidates"], items, self.item_local, self.scalars_buf, *item_range,
                   *self.state, self.vox_buf, self.sums, *self.terms, *self.coherence,
                   *self.windows, self.projected_out)
        return n_items

    def _exact_first(self, voxels: np.ndarray) -> int:
        """Flag the batch's voxels that need the exact sum, put them first (in *voxels* and on
        the device) and return how many there are."""
        import pyopencl as cl

        q = self.device.queue
        flags = np.empty(voxels.size, np.int32)
        launch(self.device, self.k["prune_flags"], voxels.size, self.item_local, self.scalars_buf,
               np.int32(voxels.size), self.temp_buf, self.src, self.vox_buf, self.offsets,
               self.flags_buf)
        cl.enqueue_copy(q, flags, self.flags_buf)
        exact = flags.astype(bool)
        voxels[:] = np.concatenate([voxels[exact], voxels[~exact]])
        cl.enqueue_copy(q, self.vox_buf, voxels)
        return int(exact.sum())

    def _update_batch(self, voxels: np.ndarray) -> None:
        self._parzen(voxels)
        launch(self.device, self.k["decide"], voxels.size, self.item_local,
               self.scalars_buf, np.int32(voxels.size), self.vol_buf, self.temp_buf, self.vox_buf,
               self.sums, self.kern, self.labels, self.union, self.bias, self.scores_buf)

    def read_voxels(self, voxels: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The values, temperatures and sources ``(views, m)`` of some voxels of the block (its
        flat indices): what a tile gives back after updating them."""
        import pyopencl as cl

        q, views, m = self.device.queue, self.model.offsets.shape[0], np.size(voxels)
        values, sources = np.empty((2, m), np.float32), np.empty((views, m), np.int32)
        for i in range(0, m, self.batch):
            batch = np.ascontiguousarray(voxels[i: i + self.batch], np.int32)
            n = batch.size
            cl.enqueue_copy(q, self.vox_buf, batch)
            launch(self.device, self.k["pack_state"], n, self.local, self.scalars_buf, np.int32(n), *self.state,
                   self.vox_buf, *self.packed)
            part_values, part_sources = np.empty((2, n), np.float32), np.empty((views, n), np.int32)
            cl.enqueue_copy(q, part_values, self.packed[0])
            cl.enqueue_copy(q, part_sources, self.packed[1])
            values[:, i: i + n], sources[:, i: i + n] = part_values, part_sources
        return values[0], values[1], sources

    def values(self, voxels: np.ndarray) -> np.ndarray:
        """The values of some voxels of the block (flat indices), gathered on the device: the
        balance's read after every set, which would otherwise copy the whole block."""
        return self.read_voxels(voxels)[0]

    def sources(self) -> np.ndarray:
        """Each voxel's source site per view, ``(views, voxels)`` (-1: none yet), of the block
        the state holds (the whole volume, or a tile)."""
        import pyopencl as cl

        cl.enqueue_copy(self.device.queue, self._src, self.src)
        return self._src

    def temperature(self) -> np.ndarray:
        import pyopencl as cl

        cl.enqueue_copy(self.device.queue, self._temp, self.temp_buf)
        return self._temp

    def volume(self) -> np.ndarray:
        import pyopencl as cl

        cl.enqueue_copy(self.device.queue, self._vol, self.vol_buf)
        return self._vol

    def scores(self) -> np.ndarray:
        """Combined log scores before the bias, ``(slots, labels)``, of the voxels whose flat
        index is a multiple of :func:`clsolid.balance.score_stride` (row = index / stride), as
        their last visit left them."""
        import pyopencl as cl

        cl.enqueue_copy(self.device.queue, self._scores, self.scores_buf)
        return self._scores

    def read_scores(self, rows: np.ndarray) -> np.ndarray:
        """Some *rows* of :meth:`scores` (what a tile gives back of the voxels it updated):
        copies only the span of rows between the first and the last."""
        import pyopencl as cl

        rows = np.asarray(rows, np.int64)
        n_labels = self.model.labels.size
        if rows.size == 0:
            return np.empty((0, n_labels), np.float32)
        first = int(rows.min())
        span = np.empty((int(rows.max()) + 1 - first, n_labels), np.float32)
        cl.enqueue_copy(self.device.queue, span, self.scores_buf, src_offset=first * n_labels * _F4)
        return span[rows - first]

    def _diagnostic_sums(self, voxels: np.ndarray) -> tuple[int, np.ndarray]:
        """Run the Parzen sums on distinct *voxels*; return the item count and, for each of
        *voxels*, its row in the (possibly reordered) batch. Sources are updated as in a visit."""
        batch = np.array(voxels, np.int32)
        n_items = self._parzen(batch)
        order = np.argsort(batch)
        return n_items, order[np.searchsorted(batch[order], voxels)]

    def group_log_sums(self, voxels: np.ndarray) -> np.ndarray:
        """Run only the Parzen kernels on distinct *voxels*; return ``(m, views, groups)`` (for tests)."""
        import pyopencl as cl

        n_items, rows = self._diagnostic_sums(voxels)
        stride = self._pad(self.model.labels.size)
        out = np.empty(n_items * stride, np.float32)
        cl.enqueue_copy(self.device.queue, out, self.sums)
        return out.reshape(voxels.size, -1, stride)[rows, :, : self.n_groups]

    def lcpdf(self, voxels: np.ndarray) -> np.ndarray:
        """Normalised per-view log LCPDFs ``(views, m, labels)`` of distinct *voxels* at the
        current state (for tests and diagnostics)."""
        import pyopencl as cl

        n_items, rows = self._diagnostic_sums(voxels)
        n_labels = self.model.labels.size
        out = np.empty(n_items * n_labels, np.float32)
        buf = cl.Buffer(self.device.context, cl.mem_flags.WRITE_ONLY, out.nbytes)
        launch(self.device, self.k["lcpdf"], n_items, self.local, self.scalars_buf,
               np.int32(n_items), self.sums, self.kern, buf)
        cl.enqueue_copy(self.device.queue, out, buf)
        return out.reshape(voxels.size, -1, n_labels)[rows].transpose(1, 0, 2)


def kernel_tables(model: ScaleModel, group_values: np.ndarray, width: int) -> np.ndarray:
    """The decision's tables ``(2, groups, width)``, float32: ``exp(L)`` and ``L``, the log Gaussian
    factor ``L = -difference(value, label) / (2 h^2)`` of every (group value, label) pair, label rows
    padded to *width* with 1 and 0 (a padding lane then never looks underflowed)."""
    table = np.zeros((2, group_values.size, width))
    table[1, :, : model.labels.size] = -model.distance(group_values[:, None], model.labels[None, :]) / (
        2.0 * model.bandwidth**2)
    table[0] = np.exp(table[1])
    return table.astype(np.float32)


def _pruned_sizes(model: ScaleModel, params: MLParams, batch: int) -> dict[str, int]:
    """Bytes of the pruned sum's buffers (:meth:`CLBackend._start_pruned`), at most: every
    site's window taken as distinct, as many site lists as :func:`~clsolid.ml.pruned.n_site_lists` asks for."""
    views, nr = model.offsets.shape[:2]
    n = model.n_sites
    sizes = {"pruned windows": n * -(-nr * model.channels // 8) * 8 * _F4,
             # window_of, similar, group, log count, source
             "pruned window tables": n * (params.n_similar + 4) * _F4,
             "pruned flags": batch * _F4}
    if params.prune_projected:
        dims = -(-min(params.prune_projected, nr) // 8) * 8
        lists = pruned.n_site_lists(n) if params.prune_projected_probe else 1
        sizes["projected sites"] = (n * (dims + 1) + lists * (dims + 1) + 1 + nr * (dims + 2)) * _F4
    k = params.prune_projected_k if params.prune_projected else 0
    sizes["projected candidates"] = max(1, batch * views * k) * _F4
    return sizes


def _float8_rows(a: np.ndarray) -> np.ndarray:
    """*a* ``(n, d)`` as float32 rows of whole float8 vectors, zero-padded (a zero term adds nothing)."""
    out = np.zeros((a.shape[0], -(-a.shape[1] // 8) * 8), np.float32)
    out[:, : a.shape[1]] = a
    return out
