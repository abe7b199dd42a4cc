"""Dissimilarities between structure tensors and between neighbourhoods of them (Akl et al.,
ICIP 2014, §2, eqs. 6-12), in float64.

Each metric compares two tensors through per-tensor *features* (:func:`features`), so that a
search computes them once a tensor, not once a pair:

- ``"ED"`` (eq. 6): ``(dS_xx)^2 + (dS_yy)^2 + 2 (dS_xy)^2`` on the tensors themselves;
- ``"FN"`` (eq. 10): the Frobenius norm of the difference, the square root of ED;
- ``"LE"`` (eq. 11): the Frobenius norm of the difference of the matrix logarithms
  (:func:`~clsolid.tensor.field.log_tensor`, eigenvalues floored at ``eps``);
- ``"SO"`` (eqs. 7-9): ``M_or^alpha * M_coh^(1 - alpha)`` with
  ``M_or = |sin(O_1 - O_2)| min(C_1, C_2)`` and ``M_coh = max(C_1 / C_2, C_2 / C_1)``, on each
  tensor's coherence C and orientation O; the coherences are floored at ``C_FLOOR`` in
  M_coh (a flat region's C = 0 would make the ratio infinite).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .field import coherence, log_tensor, orientation

METRICS = ("ED", "SO", "FN", "LE")
#: The least coherence M_coh divides by.
C_FLOOR = 1e-3


def check_metric(metric: str, alpha: float = 0.5) -> tuple[str, float]:
    """*metric* and *alpha*, checked: one of :data:`METRICS`, and SO's weight in [0, 1]."""
    if metric not in METRICS:
        raise InputError(f"metric={metric!r} must be one of {', '.join(map(repr, METRICS))}")
    alpha = float(alpha)
    if not 0.0 <= alpha <= 1.0:
        raise InputError(f"alpha={alpha!r} must lie in [0, 1] (SO's weight of the orientation term)")
    return metric, alpha


def features(tensors: np.ndarray, metric: str, eps: float = 1e-6) -> np.ndarray:
    """What *metric* compares of each tensor ``(..., 3)``: the tensor (ED, FN), its logarithm
    (LE, eigenvalues floored at *eps*), or ``(C, O, 0)`` (SO), ``(..., 3)`` float64."""
    check_metric(metric)
    s = np.asarray(tensors, np.float64)
    if metric == "LE":
        return log_tensor(s, eps)
    if metric == "SO":
        return np.stack([coherence(s), orientation(s), np.zeros(s.shape[:-1])], axis=-1)
    return s


def feature_dissimilarity(a: np.ndarray, b: np.ndarray, metric: str, alpha: float = 0.5) -> np.ndarray:
    """The dissimilarity of tensors whose :func:`features` are *a* and *b* (broadcast)."""
    if metric == "SO":
        c1, c2 = np.maximum(a[..., 0], C_FLOOR), np.maximum(b[..., 0], C_FLOOR)
        m_or = np.abs(np.sin(a[..., 1] - b[..., 1])) * np.minimum(a[..., 0], b[..., 0])
        m_coh = np.maximum(c1 / c2, c2 / c1)
        return m_or**alpha * m_coh ** (1.0 - alpha)
    d = a - b
    ed = d[..., 0] ** 2 + 2.0 * d[..., 1] ** 2 + d[..., 2] ** 2
    return ed if metric == "ED" else np.sqrt(ed)


def dissimilarity(s1: np.ndarray, s2: np.ndarray, metric: str = "ED", alpha: float = 0.5,
                  eps: float = 1e-6) -> np.ndarray:
    """The dissimilarity M_i of tensors *s1* and *s2* ``(..., 3)`` (broadcast; eqs. 6-11).

    Parameters
    ----------
    s1, s2 : array_like, (..., 3)
        Tensors as ``(S_xx, S_xy, S_yy)``.
    metric : {"ED", "SO", "FN", "LE"}
        Euclidean, shape-orientation, Frobenius norm or log-Euclidean.
    alpha : float
        SO's weight of the orientation term against the coherence term, in [0, 1].
    eps : float
        LE's floor on the eigenvalues.

    Returns
    -------
    numpy.ndarray
        float64, the broadcast shape without the last axis.
    """
    metric, alpha = check_metric(metric, alpha)
    return feature_dissimilarity(features(s1, metric, eps), features(s2, metric, eps), metric, alpha)


def neighbourhood_dissimilarity(f1: np.ndarray, f2: np.ndarray, metric: str = "ED", alpha: float = 0.5,
                                eps: float = 1e-6, weights: np.ndarray | None = None) -> np.ndarray:
    """STD (eq. 12): the sum, over the N tensors of two neighbourhoods ``(..., N, 3)``, of their
    dissimilarities, each weighted by *weights* ``(N,)`` (default 1: the paper's sum; 0 leaves
    a tensor out, as a causal neighbourhood does)."""
    per = dissimilarity(f1, f2, metric, alpha, eps)
    if weights is None:
        return per.sum(axis=-1)
    return (per * np.asarray(weights, np.float64)).sum(axis=-1)
