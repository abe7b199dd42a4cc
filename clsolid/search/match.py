"""Nearest-neighbourhood search over an exemplar: the table of its neighbourhoods, NumPy
float64 references and the OpenCL matcher (``kernels/search/match.cl``): the exact K
nearest sites of each query (K = 1: the best match), and the distances from each query to
its own list of candidate sites (``chen-wang``'s candidate sets).

A neighbourhood is the k x k square centred on a pixel, read row by row (offsets from
:func:`square_offsets`); the distance is the weighted sum of squared differences, with
weight 1 everywhere (full square) or 0 on the centre and the terms after it
(:func:`causal_weights`, the L-shaped causal neighbourhood). With ``mismatch = n`` the
first n terms of a row are phase codes (:mod:`clsolid.search.codes`) and each adds the
weighted mismatch instead: 0 where the two codes are equal, else their sum. Only exemplar sites whose
whole square lies inside the exemplar are candidates (Urs thesis, §3.2.4: no wrap-around in
the exemplar). The best match is the candidate of least distance, the lowest site index
on a tie, on the device as in the reference: for integer grey levels every partial sum is
an integer below 2^24, exact in float32, so the two agree exactly. The K nearest are
ordered by distance, then by site index.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from ..core.launch import launch
from ..core import programs
from ..core.device import Device
from ..core.probe import VECTOR_WIDTHS, probe
from ..errors import DeviceMemoryError, InputError

#: Value of the padding candidates: its square overflows float32 to +inf, so it never wins.
PAD = 1e19
#: Work-group size of the matcher (queries a group scans the table with).
LOCAL = 64
#: Neighbourhood sides the matcher accepts (odd).
MIN_SIDE, MAX_SIDE = 3, 31
#: Most nearest sites kept per query (each work-item keeps them sorted in private memory).
MAX_K = 64


def check_side(k: Any) -> int:
    """Validate a neighbourhood side: an odd integer in [MIN_SIDE, MAX_SIDE]."""
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not MIN_SIDE <= k <= MAX_SIDE or k % 2 == 0:
        raise InputError(f"neighborhood={k!r} must be an odd integer in [{MIN_SIDE}, {MAX_SIDE}]")
    return int(k)


def square_offsets(k: int) -> np.ndarray:
    """``(k*k, 2)`` offsets ``(dy, dx)`` of a k x k square, row by row, centre at row ``k*k // 2``."""
    r = check_side(k) // 2
    dy, dx = np.mgrid[-r : r + 1, -r : r + 1]
    return np.stack([dy.ravel(), dx.ravel()], axis=1)


def causal_weights(k: int) -> np.ndarray:
    """Weights of the L-shaped causal neighbourhood: 1 on the rows above the centre and on
    the centre row's left half, 0 on the centre and everything after it."""
    w = np.zeros(check_side(k) ** 2, np.float32)
    w[: k * k // 2] = 1.0
    return w


def exemplar_table(exemplar: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Every complete k x k neighbourhood of a 2D exemplar.

    Returns
    -------
    table : ndarray, float32, ``(n_sites, k*k)``
        Row s is the neighbourhood of site s, read as :func:`square_offsets`.
    sites : ndarray, int64, ``(n_sites, 2)``
        ``(row, column)`` of each site's centre, row-major: ``n_sites = (H-k+1)(W-k+1)``.
    """
    ex = np.asarray(exemplar)
    k = check_side(k)
    if ex.ndim != 2 or min(ex.shape) < k:
        raise InputError(f"the exemplar must be a 2D image at least {k} x {k} for a {k} x {k} "
                         f"neighbourhood; got shape {ex.shape}")
    windows = np.lib.stride_tricks.sliding_window_view(ex.astype(np.float32), (k, k))
    table = np.ascontiguousarray(windows.reshape(-1, k * k))
    r = k // 2
    rows, cols = np.mgrid[r : ex.shape[0] - r, r : ex.shape[1] - r]
    return table, np.stack([rows.ravel(), cols.ravel()], axis=1).astype(np.int64)


def _check_queries(queries: np.ndarray, dim: int) -> np.ndarray:
    q = np.asarray(queries)
    if q.ndim != 2 or q.shape[1] != dim:
        raise InputError(f"queries must be an (m, {dim}) array of neighbourhoods; got shape {q.shape}")
    return q


def _weights(weights: np.ndarray | None, dim: int) -> np.ndarray:
    w = np.ones(dim, np.float32) if weights is None else np.asarray(weights, np.float32)
    if w.shape != (dim,) or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise InputError(f"weights must be {dim} finite, non-negative numbers; got shape {w.shape}")
    return w


def check_mismatch(mismatch: Any, dim: int) -> int:
    """Validate the number of leading terms compared as phase codes: an integer in [0, dim]."""
    if isinstance(mismatch, bool) or not isinstance(mismatch, (int, np.integer)) or not 0 <= mismatch <= dim:
        raise InputError(f"mismatch={mismatch!r} must be an integer in [0, {dim}] (the leading terms of a "
                         "neighbourhood compared as phase codes)")
    return int(mismatch)


def term_distances(q: np.ndarray, t: np.ndarray, mismatch: int = 0) -> np.ndarray:
    """Float64, broadcast like ``q - t``: each term's squared difference, or on the first
    *mismatch* terms (the last axis) the weighted mismatch of codes, ``[q != t] (q + t)``."""
    d = (q - t) ** 2
    if mismatch:
        a, b = q[..., :mismatch], t[..., :mismatch]
        d[..., :mismatch] = np.where(a != b, a + b, 0.0)
    return d


def k_nearest_reference(queries: np.ndarray, table: np.ndarray, count: int,
                        weights: np.ndarray | None = None, mismatch: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Float64 brute force: for each query the *count* sites of least weighted distance
    (squared differences; weighted mismatches on the first *mismatch* terms), nearest first,
    the lower index first among equal distances.

    Returns ``(site indices (m, count) int64, distances (m, count) float64)``.
    """
    t = np.asarray(table, np.float64)
    q = _check_queries(queries, t.shape[1]).astype(np.float64)
    w = _weights(weights, t.shape[1]).astype(np.float64)
    count = _check_count(count, t.shape[0])
    mismatch = check_mismatch(mismatch, t.shape[1])
    idx = np.empty((q.shape[0], count), np.int64)
    dist = np.empty((q.shape[0], count))
    for i in range(0, q.shape[0], 256):  # bounded memory: 256 x n_sites distances at a time
        d = (term_distances(q[i : i + 256, None, :], t[None, :, :], mismatch) * w).sum(axis=2)
        if count == 1:  # argmin: the first minimum, the lowest index (and far cheaper than a sort)
            order = np.argmin(d, axis=1)[:, None]
        else:
            order = np.argsort(d, axis=1, kind="stable")[:, :count]  # stable: ties by index
        idx[i : i + 256] = order
        dist[i : i + 256] = np.take_along_axis(d, order, axis=1)
    return idx, dist


def best_match_reference(queries: np.ndarray, table: np.ndarray, weights: np.ndarray | None = None,
                         mismatch: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Float64 brute force: for each query the lowest-index site of least weighted distance
    (as :func:`k_nearest_reference`).

    Returns ``(site index (m,) int64, distance (m,) float64)``.
    """
    idx, dist = k_nearest_reference(queries, table, 1, weights, mismatch)
    return idx[:, 0], dist[:, 0]


def candidate_distances_reference(queries: np.ndarray, table: np.ndarray, candidates: np.ndarray,
                                  weights: np.ndarray | None = None, mismatch: int = 0) -> np.ndarray:
    """Float64: the weighted distance (as :func:`k_nearest_reference`) between each query and
    each of its candidate sites.

    *candidates* is ``(m, C)`` site indices (a negative one: no candidate, distance +inf).
    Returns ``(m, C)`` float64.
    """
    t = np.asarray(table, np.float64)
    q = _check_queries(queries, t.shape[1]).astype(np.float64)
    w = _weights(weights, t.shape[1]).astype(np.float64)
    cand = _check_candidates(candidates, q.shape[0], t.shape[0])
    mismatch = check_mismatch(mismatch, t.shape[1])
    d = (term_distances(q[:, None, :], t[np.maximum(cand, 0)], mismatch) * w).sum(axis=2)
    return np.where(cand < 0, np.inf, d)


def _check_count(count, n_sites: int) -> int:
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or not 1 <= count <= min(n_sites, MAX_K):
        raise InputError(f"count={count!r} must be an integer in [1, {min(n_sites, MAX_K)}] (the sites "
                         f"kept per query, at most the {n_sites} sites of the table and {MAX_K})")
    return int(count)


def _check_candidates(candidates: np.ndarray, m: int, n_sites: int) -> np.ndarray:
    c = np.asarray(candidates)
    if c.ndim != 2 or c.shape[0] != m or not np.issubdtype(c.dtype, np.integer) or np.any(c >= n_sites):
        raise InputError(f"candidates must be an ({m}, C) integer array of site indices below {n_sites}; "
                         f"got shape {c.shape}, dtype {c.dtype}")
    return c


def candidate_sets(matcher: Any, table: np.ndarray, count: int, weights: np.ndarray) -> np.ndarray:
    """``(n_sites, count)`` site indices: each site first, then its ``count - 1`` nearest
    other sites (nearest first, lower index first on a tie), by *weights*' distance.

    "Each pixel is considered to belong to his own set": among equal neighbourhoods (the
    flat squares of a binary exemplar) the nearest by index need not include the site
    itself, so it is put first and the nearest others follow. The sets of a smaller count
    are the first columns of a larger count's.
    """
    n_sites = table.shape[0]
    count = min(count, n_sites)
    near = matcher.nearest(table, count, weights)[0]
    self_ = np.arange(n_sites)[:, None]
    others = np.take_along_axis(near, np.argsort(near == self_, axis=1, kind="stable"), axis=1)[:, : count - 1]
    return np.concatenate([self_, others], axis=1)


def _queries_per_item(device: Device, count: int) -> int:
    """Queries a work-item of ``k_nearest`` takes. On a CPU, 8 for the best match: each table
    vector loaded then serves eight, and the terms a second grow with the queries an item
    takes up to eight (``tools/bench_search.py``; docs/design.md#queries-per-work-item).
    Otherwise 1: longer lists, and a GPU's work-items, would hold eight queries' private
    arrays (unmeasured on a GPU)."""
    return 8 if count == 1 and device.is_cpu else 1


class _Layout:
    """A table on the device for one set of weights: only the terms of nonzero weight (a
    term of weight 0 adds exactly 0 to every distance), transposed for the exhaustive
    search (sites along the vectors, padded with :data:`PAD`) and row by row for
    candidates; ``unit`` when every weight kept is 1, so the kernels leave the multiply out;
    ``nmis`` the kept terms that are codes (the first *mismatch* of a row)."""

    def __init__(self, device: Device, table: np.ndarray, weights: np.ndarray, n_pad: int, vw: int,
                 mismatch: int = 0) -> None:
        import pyopencl as cl

        keep = np.flatnonzero(weights > 0)
        self.keep = keep if keep.size else np.array([0])  # all zero: one term of weight 0
        self.unit = bool(np.all(weights[self.keep] == 1.0))
        self.nmis = int(np.count_nonzero(self.keep < mismatch))  # keep is sorted: the codes come first
        dim, width = self.keep.size, -(-self.keep.size // vw) * vw
        table_t = np.full((dim, n_pad), PAD, np.float32)  # sites along the vectors
        table_t[:, : table.shape[0]] = table[:, self.keep].T
        rows = np.zeros((table.shape[0], width), np.float32)  # whole vectors a row, zero padded
        rows[:, :dim] = table[:, self.keep]
        kept = np.zeros(width, np.float32)
        kept[:dim] = weights[self.keep]
        mf, ctx = cl.mem_flags, device.context
        self.table_t = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=table_t)
        self.rows = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=rows)
        self.weights = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=kept)
        self.places = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=self.keep.astype(np.int32))


class CLMatcher:
    """Nearest-neighbourhood search on an OpenCL device, for a fixed table.

    Parameters
    ----------
    device : Device
        From :func:`clsolid.select_device`.
    table : ndarray, ``(n_sites, dim)``
        The sites (:func:`exemplar_table`).
    weights : ndarray, ``(dim,)``, optional
        Per-term weights of the distance (default: all 1).
    max_batch : int
        Queries per launch.
    mismatch : int
        The leading terms of a row that are phase codes, compared by weighted mismatch
        (:mod:`clsolid.search.codes`); 0 (default): every term by squared difference.
    vector_width : int, optional
        Sites per vector in the kernels (4, 8 or 16); None: the widest the device's compiler
        handles (:func:`clsolid.core.probe.probe`).
    """

    def __init__(self, device: Device, table: np.ndarray, weights: np.ndarray | None = None,
                 max_batch: int = 65536, mismatch: int = 0, vector_width: int | None = None) -> None:
        import pyopencl as cl

        self.table = np.ascontiguousarray(table, np.float32)
        if self.table.ndim != 2 or self.table.shape[0] == 0:
            raise InputError(f"the table must be a non-empty (n_sites, dim) array; got shape {self.table.shape}")
        self.device, self.dim, self.max_batch = device, self.table.shape[1], int(max_batch)
        self.mismatch = check_mismatch(mismatch, self.dim)
        for name, nbytes in (("match table", self.table.nbytes + 16 * self.dim * 4),  # each of two copies
                             ("match queries", self.max_batch * self.dim * 4),
                             ("match results", self.max_batch * MAX_K * 4)):
            if nbytes > device.max_alloc:
                raise DeviceMemoryError(name, nbytes, device.max_alloc)
        if vector_width is None:
            vector_width = probe(device.device).vector_width or VECTOR_WIDTHS[0]
        if vector_width not in VECTOR_WIDTHS:
            raise InputError(f"vector_width={vector_width!r} must be one of {VECTOR_WIDTHS}")
        self._vw = vector_width
        self.n_pad = -(-self.table.shape[0] // self._vw) * self._vw
        self._layouts: dict[bytes, _Layout] = {}
        self._layout = self._layout_of(_weights(weights, self.dim))
        mf = cl.mem_flags
        # READ_WRITE: the gather kernels write the queries here on the device (voxel_queries,
        # project_queries), and a kernel's write to a READ_ONLY buffer is undefined in OpenCL
        self._queries = cl.Buffer(device.context, mf.READ_WRITE, self.max_batch * self.dim * 4)
        self._site = cl.Buffer(device.context, mf.READ_WRITE, self.max_batch * MAX_K * 4)
        self._dist = cl.Buffer(device.context, mf.WRITE_ONLY, self.max_batch * MAX_K * 4)

    def _layout_of(self, weights: np.ndarray) -> "_Layout":
        """The device tables for *weights* (built once per distinct weights; a run uses two)."""
        key = weights.tobytes()
        if key not in self._layouts:
            self._layouts[key] = _Layout(self.device, self.table, weights, self.n_pad, self._vw, self.mismatch)
        return self._layouts[key]

    def kernel(self, name: str, count: int = 1, **defines: int):
        """Kernel *name* of ``search/match.cl`` built for the current weights (and *defines*;
        with ``KSIDE``, after ``search/gather.cl``, whose gathering ``coherence_best`` uses)."""
        lay = self._layout
        defines.update(QDIM=self.dim, DIM=lay.keep.size, VW=self._vw, K=count, UNIT=int(lay.unit), NMIS=lay.nmis,
                       QB=_queries_per_item(self.device, count))
        files = ("search/gather.cl", "search/match.cl") if "KSIDE" in defines else "search/match.cl"
        return programs.build(self.device, files, defines)[name]

    def layout(self, weights: np.ndarray | None = None) -> "_Layout":
        """The device tables of *weights*, which replace the current ones (if given)."""
        if weights is not None:
            self._layout = self._layout_of(_weights(weights, self.dim))
        return self._layout

    def _as_queries(self, queries: np.ndarray) -> np.ndarray:
        """The queries, float32, contiguous (the kernels read only the terms kept)."""
        return np.ascontiguousarray(_check_queries(queries, self.dim), np.float32)

    def nearest(self, queries: np.ndarray, count: int,
                weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """For each query row the *count* nearest sites, nearest first (lower index first on
        a tie), and their distances.

        *weights*, if given, replace the distance's per-term weights from now on.
        Returns ``(site indices (m, count) int64, distances (m, count) float32)``.
        """
        import pyopencl as cl

        self.layout(weights)
        q = self._as_queries(queries)
        return self.nearest_filled(q.shape[0], count,
                                   lambda i, n: cl.enqueue_copy(self.device.queue, self._queries, q[i : i + n]))

    @property
    def query_buffer(self) -> Any:
        """The device buffer the queries of one launch are read from (``max_batch`` rows)."""
        return self._queries

    def nearest_filled(self, n_queries: int, count: int,
                       fill: Callable[[int, int], None]) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`nearest` of *n_queries* queries that ``fill(start, n)`` writes into
        :attr:`query_buffer` (queries ``start`` to ``start + n``, row by row), at most
        ``max_batch`` at a time: gathered on the device (:class:`~clsolid.search.block.DeviceBlock`)
        or copied from the host. The current weights (:meth:`layout`)."""
        import pyopencl as cl

        count = _check_count(count, self.table.shape[0])
        idx, dist = np.empty((n_queries, count), np.int32), np.empty((n_queries, count), np.float32)
        queue, kernel, batch = self.device.queue, self.kernel("k_nearest", count), self.max_batch
        lay, per_item = self._layout, _queries_per_item(self.device, count)
        for i in range(0, n_queries, batch):
            n = min(batch, n_queries - i)
            fill(i, n)
            items = -(-n // per_item)
            launch(self.device, kernel, items, LOCAL, self._queries, lay.places, lay.table_t, lay.weights,
                   np.int32(n), np.int32(self.n_pad), self._site, self._dist)
            cl.enqueue_copy(queue, idx[i : i + n], self._site)
            cl.enqueue_copy(queue, dist[i : i + n], self._dist)
        return idx.astype(np.int64), dist

    def best(self, queries: np.ndarray, weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """For each query row the lowest-index site of least distance, and that distance.

        *weights*, if given, replace the distance's per-term weights from now on.
        Returns ``(site index (m,) int64, distance (m,) float32)``.
        """
        idx, dist = self.nearest(queries, 1, weights)
        return idx[:, 0], dist[:, 0]

    def distances(self, queries: np.ndarray, candidates: np.ndarray,
                  weights: np.ndarray | None = None) -> np.ndarray:
        """The distance from each query row to each of its candidate sites, ``(m, C)`` float32
        (+inf for a negative candidate). *weights* as for :meth:`best`."""
        import pyopencl as cl

        self.layout(weights)
        q = self._as_queries(queries)
        cand = np.ascontiguousarray(_check_candidates(candidates, q.shape[0], self.table.shape[0]), np.int32)
        n_cand = cand.shape[1]
        out = np.empty(cand.shape, np.float32)
        queue, kernel = self.device.queue, self.kernel("candidate_distances")
        batch = max(1, min(self.max_batch, self.max_batch * MAX_K // max(n_cand, 1)))  # pairs fit _site/_dist
        for i in range(0, q.shape[0], batch):
            n = min(batch, q.shape[0] - i)
            cl.enqueue_copy(queue, self._queries, q[i : i + n])
            cl.enqueue_copy(queue, self._site, cand[i : i + n])
            lay = self._layout
            launch(self.device, kernel, n, LOCAL, self._queries, lay.places, lay.rows, lay.weights,
                   self._site, np.int32(n), np.int32(n_cand), self._dist)
            cl.enqueue_copy(queue, out[i : i + n], self._dist)
        return out


class ReferenceMatcher:
    """:class:`CLMatcher`'s interface on the float64 references (for tests)."""

    def __init__(self, table: np.ndarray, weights: np.ndarray | None = None, mismatch: int = 0) -> None:
        self.table = np.asarray(table, np.float32)
        self.weights = _weights(weights, self.table.shape[1])
        self.mismatch = check_mismatch(mismatch, self.table.shape[1])

    def _set_weights(self, weights: np.ndarray | None) -> None:
        if weights is not None:
            self.weights = _weights(weights, self.table.shape[1])

    def nearest(self, queries: np.ndarray, count: int,
                weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        self._set_weights(weights)
        return k_nearest_reference(queries, self.table, count, self.weights, self.mismatch)

    def best(self, queries: np.ndarray, weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        self._set_weights(weights)
        return best_match_reference(queries, self.table, self.weights, self.mismatch)

    def distances(self, queries: np.ndarray, candidates: np.ndarray,
                  weights: np.ndarray | None = None) -> np.ndarray:
        self._set_weights(weights)
        return candidate_distances_reference(queries, self.table, candidates, self.weights, self.mismatch)
