"""Wei & Levoy's synthesis of a structure tensor field (Akl et al., ICIP 2014, §2): the first
stage of structure-tensor constrained synthesis, in 2D.

The exemplar's tensor field (:func:`clsolid.tensor.structure_tensor`) and the output field
each get a Gaussian pyramid (each component filtered and decimated, as the search methods'
images are: :func:`~clsolid.search.pyramid.gaussian_pyramid`). From the coarsest level
down, each output pixel's multi-resolution neighbourhood (its k x k square of tensors, and
the 3 x 3 square of the level above: :mod:`~clsolid.search.features`) is matched against
every exemplar site's by the sum of tensor dissimilarities STD (eq. 12), and the pixel takes
the matched site's tensor. The output is toroidal.

Two schemes, as the paper's Fig. 1:

- ``"random"``: the square neighbourhood, the centre left out, pixels visited in a random
  walk: conflict-free sets of pixels (no two within each other's square) in a seeded order,
  which equals one pixel at a time in that order (:mod:`clsolid.core.schedule`);
- ``"causal"``: the L-shaped causal neighbourhood and a lexicographic scan, run in
  wavefronts: pixel (r, c) in wave ``r (h + 1) + c`` (h the half side), after every pixel
  its neighbourhood reads, as in a raster scan; only where a square wraps round the left
  edge does a pixel read the row above's right end as it was before that row's pass.

A finer level starts from the coarser result up-sampled; the coarsest from tensors drawn
from the exemplar's level.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.schedule import colour_set, set_count, set_order
from ..errors import InputError
from ..tensor.dissimilarity import check_metric, neighbourhood_dissimilarity
from .features import centre_weights, exemplar_features, voxel_features
from .pyramid import gaussian_pyramid, upsampled

SCHEMES = ("random", "causal")


def tensor_pyramid(field: np.ndarray, levels: int) -> list[np.ndarray]:
    """``levels`` tensor fields ``(h, w, 3)``, finest first: each component's
    :func:`~clsolid.search.pyramid.gaussian_pyramid` (edges mirrored)."""
    parts = [gaussian_pyramid(field[..., c], levels) for c in range(3)]
    return [np.stack([p[level] for p in parts], axis=-1) for level in range(levels)]


def site_table(fine: np.ndarray, coarse: np.ndarray | None, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Every valid exemplar site's neighbourhood of tensors ``(n, N, 3)`` (the k x k square,
    then the parent 3 x 3 with a *coarse* level) and its own tensor ``(n, 3)``."""
    parts = [exemplar_features(fine[..., c], None if coarse is None else coarse[..., c], k) for c in range(3)]
    return (np.stack([t for t, _ in parts], axis=-1).astype(np.float64),
            np.stack([v for _, v in parts], axis=-1).astype(np.float64))


def pixel_queries(out: np.ndarray, coarse: np.ndarray | None, pixels: np.ndarray, k: int) -> np.ndarray:
    """The neighbourhoods ``(m, N, 3)`` of flat *pixels* of the toroidal field *out* ``(h, w, 3)``
    (with the coarser field *coarse* as parent), laid out as :func:`site_table`'s."""
    parts = [voxel_features(out[None, ..., c], None if coarse is None else coarse[None, ..., c], pixels, "front", k)
             for c in range(3)]
    return np.stack(parts, axis=-1)


class ReferenceTensorMatcher:
    """:class:`~clsolid.tensor.opencl.TensorMatcher`'s ``best`` on the float64 reference."""

    def __init__(self, table: np.ndarray, metric: str = "ED", alpha: float = 0.5, eps: float = 1e-6,
                 weights: np.ndarray | None = None) -> None:
        self.table, self.metric, self.alpha, self.eps = np.asarray(table, np.float64), metric, alpha, eps
        self.weights = weights

    def best(self, queries: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        d = neighbourhood_dissimilarity(np.asarray(queries, np.float64)[:, None], self.table[None], self.metric,
                                        self.alpha, self.eps, self.weights)
        site = np.argmin(d, axis=1)
        return site, d[np.arange(d.shape[0]), site]


def _waves(shape: tuple[int, int], half: int) -> list[np.ndarray]:
    """The causal scheme's wavefronts: flat pixels grouped by ``r (half + 1) + c``, in order."""
    rows, cols = np.indices(shape)
    wave = (rows * (half + 1) + cols).ravel()
    order = np.argsort(wave, kind="stable")
    bounds = np.flatnonzero(np.diff(wave[order])) + 1
    return np.split(order, bounds)


def synthesize_field(exemplar_field: np.ndarray, shape: tuple[int, int], *, neighborhood: int = 7, levels: int = 3,
                     iterations: int = 2, metric: str = "ED", alpha: float = 0.5, scheme: str = "random",
                     seed: int = 0, device: Any = None, eps: float | None = None) -> np.ndarray:
    """Grow a toroidal tensor field of *shape* ``(h, w)`` from an exemplar's tensor field.

    Parameters
    ----------
    exemplar_field : array_like, (H, W, 3)
        The exemplar's structure tensor field (:func:`clsolid.tensor.structure_tensor`).
    shape : tuple of 2 ints
        The output field's ``(h, w)``.
    neighborhood : int
        The square's side k (odd).
    levels : int
        Pyramid levels (the paper's "structure pyramid levels").
    iterations : int
        Passes over every pixel at each level.
    metric, alpha : str, float
        The tensor dissimilarity (:mod:`clsolid.tensor.dissimilarity`) and SO's weight.
    scheme : {"random", "causal"}
        Square neighbourhood and random walk, or causal neighbourhood and lexicographic scan.
    seed : int
        The seed: the starting tensors and the random walk's order.
    device : Device, str or None
        OpenCL device (:func:`clsolid.select_device`), or ``"reference"`` for the float64 search.
    eps : float or None
        LE's floor on the eigenvalues; None: a thousandth of the exemplar's mean trace.

    Returns
    -------
    numpy.ndarray
        ``(h, w, 3)`` float64, each tensor one of the exemplar pyramid's finest level.
    """
    field = np.asarray(exemplar_field, np.float64)
    if field.ndim != 3 or field.shape[2] != 3 or not np.isfinite(field).all():
        raise InputError(f"the exemplar field must be a finite (H, W, 3) array of tensors; got shape {field.shape}")
    metric, alpha = check_metric(metric, alpha)
    if scheme not in SCHEMES:
        raise InputError(f"scheme={scheme!r} must be one of {', '.join(map(repr, SCHEMES))}")
    shape = tuple(int(n) for n in shape)
    if len(shape) != 2 or min(shape) < 2 ** levels:
        raise InputError(f"shape={shape!r} must be (h, w), each at least 2^levels = {2 ** levels}")
    k = int(neighborhood)
    if eps is None:
        eps = 1e-3 * max(float(np.mean(field[..., 0] + field[..., 2])), 1e-300)
    rng = np.random.default_rng(seed)
    if device == "reference":
        matcher_for = ReferenceTensorMatcher
    else:
        from functools import partial

        from ..core.device import select_device
        from ..tensor.opencl import TensorMatcher

        matcher_for = partial(TensorMatcher, select_device(device))
    pyr = tensor_pyramid(field, levels)
    out, coarse = None, None
    for level in range(levels - 1, -1, -1):
        size = (max(1, shape[0] >> level), max(1, shape[1] >> level))
        parent = level + 1 < levels
        table, centres = site_table(pyr[level], pyr[level + 1] if parent else None, k)
        weights = centre_weights(k, parent, centre=False, causal=scheme == "causal")
        matcher = matcher_for(table, metric=metric, alpha=alpha, eps=eps, weights=weights)
        if coarse is None:  # noise drawn from the exemplar's level
            flat = pyr[level].reshape(-1, 3)
            out = flat[rng.integers(0, flat.shape[0], size[0] * size[1])].reshape(size + (3,))
        else:
            out = upsampled(coarse, size)
        out = np.ascontiguousarray(out)
        flat_out = out.reshape(-1, 3)  # a view: the queries read what the passes write
        waves = _waves(size, k // 2) if scheme == "causal" else None  # the same every pass
        n_sets = set_count((1,) + size, k // 2)
        for it in range(1, iterations + 1):
            groups = waves if waves is not None else (colour_set((1,) + size, n_sets, c)
                                                     for c in set_order(n_sets, seed, level, it))
            for pixels in groups:
                site, _ = matcher.best(pixel_queries(out, coarse if parent else None, pixels, k))
                flat_out[pixels] = centres[site]
        coarse = out
    return out
