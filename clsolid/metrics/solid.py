"""Properties of a segmented volume that no slice shows: surface area, two-point correlation
along each axis, how much of a phase spans the block, and its tortuosity factor.

Every function takes a label volume ``(Z, Y, X)`` (axis 0 = z, 1 = y, 2 = x) or a 2D label
image, whose values are phase values (as a segmented exemplar's, e.g. 0 and 255), and the
value of the phase to measure. Nothing wraps around: a block grown by clsolid is not
periodic, so only pairs, faces and paths inside it count. Results are float64.
"""

from __future__ import annotations

import numbers
from typing import Any, Literal

import numpy as np
from scipy import ndimage, sparse
from scipy.sparse import linalg as sparse_linalg

from ..errors import InputError
from ._common import as_image_or_volume, check_int, neighbour_pairs
from .phases import two_point_correlation

#: Conductance between a voxel of the first or last layer and the fixed concentration held
#: on the block's face, half a voxel away (TauFactor's boundary condition).
FACE_CONDUCTANCE = 2.0


def _check_phase(phase: Any) -> None:
    # A bool is a phase value too: that of a boolean mask.
    if not isinstance(phase, (numbers.Real, np.bool_)) or not np.isfinite(phase):
        raise InputError(f"phase={phase!r} must be a finite real number, a value of labels")


def _phase_mask(labels: Any, phase: Any) -> np.ndarray:
    """Boolean mask of ``labels == phase`` for a 2D or 3D label array."""
    arr = as_image_or_volume(labels, "labels")
    _check_phase(phase)
    return arr == phase


def _check_axis(axis: Any, ndim: int) -> int:
    if isinstance(axis, bool) or not isinstance(axis, numbers.Integral) or not 0 <= axis < ndim:
        raise InputError(f"axis={axis!r} must be an integer 0 to {ndim - 1} (0 = z, 1 = y, 2 = x for a volume)")
    return int(axis)


def _layer(ndim: int, axis: int, index: int) -> tuple:
    """Index of one layer (``index`` along ``axis``) of an ``ndim``-D array."""
    key = [slice(None)] * ndim
    key[axis] = index
    return tuple(key)


def _clusters(mask: np.ndarray) -> np.ndarray:
    """Face-connected clusters of a mask (6-connected in 3D, 4-connected in 2D); 0 = background."""
    clusters, _ = ndimage.label(mask)  # scipy's default structure is face connectivity
    return clusters


def _spanning(clusters: np.ndarray, axis: int) -> np.ndarray:
    """Mask of the voxels in clusters that touch both faces normal to ``axis``."""
    first = np.unique(clusters[_layer(clusters.ndim, axis, 0)])
    last = np.unique(clusters[_layer(clusters.ndim, axis, -1)])
    keep = np.zeros(int(clusters.max()) + 1, dtype=bool)
    keep[np.intersect1d(first, last)] = True
    keep[0] = False
    return keep[clusters]


def specific_surface_area(labels: Any, phase: Any) -> float:
    """Faces between ``phase`` and any other label, per voxel of the block.

    Parameters
    ----------
    labels : array_like, (Z, Y, X) or (rows, cols)
        A label volume, or a label image (then edges per pixel).
    phase : int or float
        The value of the phase in ``labels``.

    Returns
    -------
    float
        The number of faces shared by a voxel of ``phase`` and a face neighbour of
        another label, along every axis, divided by ``labels.size``. Only faces inside
        the block count; the block's own faces do not. In units of 1 / voxel side.
    """
    mask = _phase_mask(labels, phase)
    faces = sum(np.count_nonzero(np.diff(mask, axis=a)) for a in range(mask.ndim))  # diff of bools is !=
    return faces / mask.size


def two_point_correlation_axes(labels: Any, phase: Any, *, max_lag: int | None = None) -> tuple[np.ndarray, ...]:
    """Two-point probability ``S2(r)`` of a phase along each axis separately.

    ``S2(r)`` along axis ``a`` is the probability that two voxels ``r`` apart along ``a``
    both lie in ``phase``, averaged over every such pair inside the block (no
    wrap-around): :func:`clsolid.metrics.two_point_correlation` applied to the planes that
    contain ``a``.

    Parameters
    ----------
    labels : array_like, (Z, Y, X) or (rows, cols)
        A label volume or image.
    phase : int or float
        The value of the phase in ``labels``; as in ``two_point_correlation``, labels are
        rounded to whole numbers first.
    max_lag : int or None
        The largest lag; clipped to each axis's length minus one. None: every lag. Each
        lag is one pass over the volume, so give a bound on large volumes.

    Returns
    -------
    tuple of numpy.ndarray
        One float64 curve per axis, in axis order (z, y, x for a volume); curve ``a`` has
        ``min(max_lag, labels.shape[a] - 1) + 1`` values and ``curve[0]`` is the phase's
        fraction.
    """
    arr = as_image_or_volume(labels, "labels")
    _check_phase(phase)
    max_lag = check_int(max_lag, "max_lag", 0, allow_none=True)
    curves = []
    for a, n in enumerate(arr.shape):
        lag = n - 1 if max_lag is None else min(max_lag, n - 1)
        # The measured axis becomes the rows of a stack of planes: axis 0 of each plane.
        curves.append(two_point_correlation(np.moveaxis(arr, a, -2), phase, 0, lag))
    return tuple(curves)


def s2_error(s2: Any, reference: Any, *, fraction: float | None = None) -> float:
    """Largest gap between two S2 curves, in percent of the phase's fraction.

    Parameters
    ----------
    s2, reference : array_like, 1D
        Two S2 curves starting at lag 0 (as :func:`two_point_correlation_axes` or
        :func:`clsolid.metrics.two_point_correlation` give); the lags both cover are compared.
    fraction : float or None
        The phase's fraction, the scale of S2. None: ``reference[0]``, the reference's fraction.

    Returns
    -------
    float
        ``100 * max_r |s2(r) - reference(r)| / fraction``.
    """
    a, b = (np.asarray(c, dtype=np.float64) for c in (s2, reference))
    for name, c in (("s2", a), ("reference", b)):
        if c.ndim != 1 or c.size == 0 or not np.isfinite(c).all():
            raise InputError(f"{name} must be a non-empty 1D curve of finite values, got shape {c.shape}")
    if fraction is None:
        fraction = float(b[0])
    if isinstance(fraction, bool) or not isinstance(fraction, numbers.Real) or not 0 < fraction <= 1:
        raise InputError(f"fraction={fraction!r} must lie in (0, 1]; with fraction=None it is reference[0], "
                         "which is 0 when the phase is absent from the reference")
    n = min(a.size, b.size)
    return float(100.0 * np.max(np.abs(a[:n] - b[:n])) / fraction)


def connected_fraction(labels: Any, phase: Any, *, axis: int | None = None) -> float | tuple[float, ...]:
    """Share of a phase's voxels in clusters that span the block along an axis.

    Parameters
    ----------
    labels : array_like, (Z, Y, X) or (rows, cols)
        A label volume or image.
    phase : int or float
        The value of the phase in ``labels``.
    axis : int or None
        The axis the clusters must span (0 = z, 1 = y, 2 = x). None: every axis.

    Returns
    -------
    float or tuple of float
        The number of voxels of ``phase`` in face-connected clusters (6-connected in 3D,
        4-connected in 2D) that touch both faces of the block normal to ``axis``, over
        the number of voxels of ``phase``; NaN when the phase is absent. With
        ``axis=None``, one value per axis, in axis order.
    """
    mask = _phase_mask(labels, phase)
    axes = range(mask.ndim) if axis is None else [_check_axis(axis, mask.ndim)]
    total = np.count_nonzero(mask)
    clusters = _clusters(mask)
    shares = tuple(np.count_nonzero(_spanning(clusters, a)) / total if total else float("nan") for a in axes)
    return shares if axis is None else shares[0]


def tortuosity_factor(labels: Any, phase: Any, axis: int, *, solver: Literal["cg", "direct"] = "cg",
                      rtol: float = 1e-8, maxiter: int | None = None) -> float:
    """Tortuosity factor ``tau`` of a phase along an axis, as TauFactor defines it.

    Steady diffusion is solved in the phase alone: concentration 1 on the block's face at
    the start of ``axis``, 0 on the face at its end, no flux through the other faces or
    the phase's boundary. Then ``tau = eps * D_open / D_eff``, with ``eps`` the phase's
    volume fraction, ``D_eff`` the block's effective diffusivity and ``D_open`` that of the
    same block filled with the phase (Cooper et al., "TauFactor: an open-source application
    for calculating tortuosity factors from tomographic data", *SoftwareX* 5, 2016).

    Discretisation: voxel-centred finite volumes with unit voxels and unit diffusivity,
    as TauFactor's. One unknown concentration per voxel; conductance 1 between two
    face-adjacent voxels of the phase, none across the phase's boundary or the side faces;
    a voxel of the first (last) layer along ``axis`` is joined to concentration 1 (0),
    held on the block's face half a voxel away, by conductance 2. The flux ``F`` is the
    total flow in through the first face (averaged with the flow out through the last;
    they agree once solved), ``D_eff = F L / A`` with ``L`` the block's length along
    ``axis`` and ``A`` its cross-section in voxels, and ``D_open = 1`` exactly (a column
    of ``L`` voxels has resistance ``(L - 1) + 2 * 1/2 = L``): straight channels give
    ``tau = 1`` at any size. Only clusters that span the block are solved for; clusters
    that do not still count in ``eps`` (TauFactor's convention), so they raise ``tau``.

    Parameters
    ----------
    labels : array_like, (Z, Y, X) or (rows, cols)
        A label volume or image.
    phase : int or float
        The value of the conducting phase in ``labels``.
    axis : int
        The direction of transport (0 = z, 1 = y, 2 = x).
    solver : {"cg", "direct"}, default "cg"
        ``"cg"``: conjugate gradients (``scipy.sparse.linalg.cg``) with a Jacobi
        preconditioner, started from the linear profile; ``"direct"``: a sparse LU
        factorisation (``scipy.sparse.linalg.spsolve``, SuperLU), exact to rounding but
        with memory that grows fast with the block, for small blocks.
    rtol : float, default 1e-8
        Conjugate gradients stop when ``||b - A c|| <= rtol * ||b||``.
    maxiter : int or None
        Most conjugate-gradient iterations; None: scipy's default (10 per unknown).

    Returns
    -------
    float
        ``tau >= 1`` for any geometry (1 for straight channels along ``axis``); ``inf``
        when no cluster of ``phase`` spans the block along ``axis``.

    Raises
    ------
    InputError
        A bad argument, or conjugate gradients not reaching ``rtol`` within ``maxiter``.
    """
    mask = _phase_mask(labels, phase)
    axis = _check_axis(axis, mask.ndim)
    if solver not in ("cg", "direct"):
        raise InputError(f"solver={solver!r} must be 'cg' or 'direct'")
    if isinstance(rtol, bool) or not isinstance(rtol, numbers.Real) or not 0 < rtol < 1:
        raise InputError(f"rtol={rtol!r} must be a number in (0, 1)")
    maxiter = check_int(maxiter, "maxiter", 1, allow_none=True)
    live = _spanning(_clusters(mask), axis)
    n = int(np.count_nonzero(live))
    if n == 0:
        return float("inf")

    index = np.full(mask.shape, -1, dtype=np.int64)
    index[live] = np.arange(n)
    rows, cols = [], []
    for a in range(mask.ndim):
        lo, hi = neighbour_pairs(mask.ndim, a)
        joined = live[lo] & live[hi]
        i, j = index[lo][joined], index[hi][joined]
        rows += [i, j]
        cols += [j, i]
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    inlet = index[_layer(mask.ndim, axis, 0)]
    outlet = index[_layer(mask.ndim, axis, -1)]
    inlet, outlet = inlet[inlet >= 0], outlet[outlet >= 0]
    diagonal = np.bincount(rows, minlength=n).astype(np.float64)
    diagonal[inlet] += FACE_CONDUCTANCE
    diagonal[outlet] += FACE_CONDUCTANCE  # separately: with one layer, inlet and outlet are the same voxels
    matrix = (sparse.coo_matrix((np.full(rows.size, -1.0), (rows, cols)), shape=(n, n))
              + sparse.diags(diagonal)).tocsr()
    rhs = np.zeros(n)
    rhs[inlet] = FACE_CONDUCTANCE  # times the inlet concentration, 1

    length = mask.shape[axis]
    if solver == "direct":
        conc = sparse_linalg.spsolve(matrix.tocsc(), rhs)
    else:
        position = np.nonzero(live)[axis]
        start = 1.0 - (position + 0.5) / length  # the open block's exact solution
        inverse = 1.0 / diagonal
        jacobi = sparse_linalg.LinearOperator((n, n), matvec=lambda r: inverse * r.ravel(), dtype=np.float64)
        conc, info = sparse_linalg.cg(matrix, rhs, x0=start, rtol=rtol, atol=0.0, maxiter=maxiter, M=jacobi)
        if info != 0:
            raise InputError(f"conjugate gradients did not reach rtol={rtol!r} within {maxiter or 10 * n} "
                             f"iterations (maxiter={maxiter!r}); allow more, give a larger rtol, or use "
                             "solver='direct'")
    flux_in = FACE_CONDUCTANCE * np.sum(1.0 - conc[inlet])
    flux_out = FACE_CONDUCTANCE * np.sum(conc[outlet])
    d_eff = 0.5 * (flux_in + flux_out) * length / (mask.size / length)
    eps = np.count_nonzero(mask) / mask.size
    return float(eps / d_eff)
