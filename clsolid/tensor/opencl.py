"""The structure tensor field and the tensor dissimilarities on an OpenCL device
(``kernels/tensor/tensor.cl``), float32; :mod:`~clsolid.tensor.field` and
:mod:`~clsolid.tensor.dissimilarity` are their float64 references."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core import programs
from ..core.device import Device
from ..core.launch import launch
from ..errors import InputError
from .dissimilarity import METRICS, check_metric
from .field import BOUNDARIES, _check, check_radius, gaussian_taps

_FILE = "tensor/tensor.cl"
#: Work-items a group, as the kernels ask (the device may allow fewer).
_GROUP = 64


def _buffer(device: Device, array: np.ndarray | None = None, nbytes: int = 0) -> Any:
    import pyopencl as cl

    mf = cl.mem_flags
    if array is None:
        return cl.Buffer(device.context, mf.READ_WRITE, max(int(nbytes), 4))
    data = np.ascontiguousarray(array, np.float32)
    return cl.Buffer(device.context, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=data if data.size else np.zeros(1, np.float32))


def _read(device: Device, buf: Any, shape: tuple[int, ...], dtype: Any = np.float32) -> np.ndarray:
    import pyopencl as cl

    out = np.empty(shape, dtype)
    cl.enqueue_copy(device.queue, out, buf)
    return out


def structure_tensor(device: Device, image: np.ndarray, grad_sigma: float = 1.0, window_sigma: float = 1.5,
                     boundary: str = "reflect") -> np.ndarray:
    """:func:`clsolid.tensor.field.structure_tensor` on *device*: ``(H, W, 3)`` float32."""
    img = _check(image, boundary)
    h, w = img.shape
    kernels = programs.build(device, _FILE)
    conv, prod = kernels["convolve"], kernels["products"]
    wrap = np.int32(BOUNDARIES.index(boundary))
    taps = {name: gaussian_taps(sigma, deriv) for name, sigma, deriv in
            (("g", grad_sigma, False), ("dg", grad_sigma, True), ("w", window_sigma, False))}
    for t in taps.values():
        check_radius(min(h, w), t.size // 2)
    tap_bufs = {name: _buffer(device, t) for name, t in taps.items()}
    src = _buffer(device, img)
    n = h * w
    a, b, ix, iy = (_buffer(device, nbytes=4 * n) for _ in range(4))

    def run(inp, out, name, axis, channels):
        launch(device, conv, n * channels, _GROUP, inp, out, np.int32(h), np.int32(w), np.int32(channels),
               tap_bufs[name], np.int32(taps[name].size // 2), np.int32(axis), wrap, np.int32(name == "dg"))

    run(src, a, "dg", 1, 1)
    run(a, ix, "g", 0, 1)
    run(src, b, "dg", 0, 1)
    run(b, iy, "g", 1, 1)
    s, t = _buffer(device, nbytes=12 * n), _buffer(device, nbytes=12 * n)
    launch(device, prod, n, _GROUP, ix, iy, np.int32(n), s)
    run(s, t, "w", 1, 3)
    run(t, s, "w", 0, 3)
    return _read(device, s, (h, w, 3))


class TensorMatcher:
    """The STD search (eq. 12) of tensor neighbourhoods on an OpenCL device, for a fixed table.

    Parameters
    ----------
    device : Device
        From :func:`clsolid.select_device`.
    table : ndarray, ``(n_sites, N, 3)``
        Each site's neighbourhood of N tensors.
    metric : {"ED", "SO", "FN", "LE"}
        The tensor dissimilarity (:mod:`clsolid.tensor.dissimilarity`).
    alpha : float
        SO's weight of the orientation term.
    eps : float
        LE's floor on the eigenvalues.
    weights : ndarray, ``(N,)``, optional
        Each tensor's weight in the sum (default 1).
    """

    def __init__(self, device: Device, table: np.ndarray, metric: str = "ED", alpha: float = 0.5, eps: float = 1e-6,
                 weights: np.ndarray | None = None) -> None:
        self.metric, self.alpha = check_metric(metric, alpha)
        table = np.asarray(table, np.float32)
        if table.ndim != 3 or table.shape[2] != 3 or table.shape[0] == 0:
            raise InputError(f"the table must be a non-empty (n_sites, N, 3) array of tensors; got {table.shape}")
        self.device, self.eps = device, float(eps)
        self.n_sites, self.size = table.shape[0], table.shape[1]
        w = np.ones(self.size) if weights is None else np.asarray(weights, np.float64)
        if w.shape != (self.size,):
            raise InputError(f"weights of shape {w.shape}: one per tensor of a neighbourhood, ({self.size},)")
        self._weights = _buffer(device, w)
        self._kernels = programs.build(device, _FILE, {"METRIC": METRICS.index(self.metric), "NT": self.size})
        self._table = self._features(table)

    def _features(self, tensors: np.ndarray) -> Any:
        """The device buffer of *tensors*' features (``tensor_features``)."""
        n = int(np.prod(tensors.shape[:-1]))
        src, out = _buffer(self.device, tensors), _buffer(self.device, nbytes=12 * n)
        launch(self.device, self._kernels["tensor_features"], n, _GROUP, src, np.int32(n), np.float32(self.eps), out)
        return out

    def _queries(self, queries: np.ndarray) -> tuple[Any, int]:
        q = np.asarray(queries, np.float32)
        if q.ndim != 3 or q.shape[1:] != (self.size, 3):
            raise InputError(f"queries of shape {q.shape}: expected (m, {self.size}, 3)")
        return self._features(q), q.shape[0]

    def distances(self, queries: np.ndarray) -> np.ndarray:
        """``(m, n_sites)`` float32: the STD between each query neighbourhood and each site's."""
        q, m = self._queries(queries)
        out = _buffer(self.device, nbytes=4 * m * self.n_sites)
        launch(self.device, self._kernels["tensor_std"], m * self.n_sites, _GROUP, q, np.int32(m), self._table,
               np.int32(self.n_sites), self._weights, np.float32(self.alpha), out)
        return _read(self.device, out, (m, self.n_sites))

    def best(self, queries: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each query's site of least STD (the lowest index on a tie) and that STD:
        ``(site (m,) int64, distance (m,) float32)``."""
        q, m = self._queries(queries)
        site, dist = _buffer(self.device, nbytes=4 * m), _buffer(self.device, nbytes=4 * m)
        launch(self.device, self._kernels["tensor_best"], m, _GROUP, q, np.int32(m), self._table,
               np.int32(self.n_sites), self._weights, np.float32(self.alpha), site, dist)
        return _read(self.device, site, (m,), np.int32).astype(np.int64), _read(self.device, dist, (m,))
