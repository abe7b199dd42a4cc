"""The label-histogram balance: a per-label bias that makes the expected label fractions
of the voxels still to visit bring the volume to the exemplar's (the ML method's
departure for phase fractions; driven by ``clsolid.ml.driver.Balance``).

After every conflict-free set the back end hands back each sampled voxel's combined log
score per label, *without* the bias (``s_v``). The bias ``b`` for what follows is the
exact dual solution: the minimiser of the convex

    F(b) = mean_v logsumexp(s_v + b) - sum_l pi_l b_l,

whose gradient is ``mean_v softmax(s_v + b) - pi``. At its minimum a Gibbs sweep drawing
from ``softmax(s_v + b)`` produces the fractions ``pi`` in expectation (the maximum-entropy
re-weighting of the voxels' laws under a histogram constraint). Under ICM or annealing the
same bias is an approximation: their decisions are not draws from the softmax.
"""

from __future__ import annotations

import math

import numpy as np

#: Label fractions below this count as this (less than a voxel in 10^4).
BALANCE_EPS = 1e-4
#: How far, in nats, a label's bias may go beyond the widest spread of the voxels' scores:
#: past that spread the label is absent from (or alone in) every voxel's law anyway. The
#: spread grows with the views summed and the bandwidth (docs/design.md#balance-range).
MAX_BIAS = 300.0
#: The bias of a label the exemplar lacks: it is never drawn.
OFF_BIAS = -1e30
#: Largest change of any label's bias in one Newton step, in nats.
MAX_STEP = 20.0
#: About this many voxels' scores are kept per sweep (a sparse lattice of them above it).
SCORE_SAMPLES = 1 << 17


def score_stride(shape: tuple[int, int, int]) -> int:
    """Keep the scores of voxels whose flat index is a multiple of this.

    1 up to :data:`SCORE_SAMPLES` voxels; above, the smallest stride that keeps about that
    many and shares no factor with X or Y, so the kept voxels do not line up in columns
    or planes.
    """
    n = int(np.prod(shape))
    s = max(1, -(-n // SCORE_SAMPLES))
    while s > 1 and (math.gcd(s, shape[2]) != 1 or math.gcd(s, shape[1]) != 1):
        s += 1
    return s


def score_rows(voxels: np.ndarray, stride: int) -> np.ndarray:
    """The score rows of those flat *voxels* that keep one (a multiple of *stride*)."""
    return voxels[voxels % stride == 0] // stride


def n_score_slots(shape: tuple[int, int, int]) -> int:
    """Rows of the score buffer: one per voxel with ``flat index % stride == 0``."""
    return -(-int(np.prod(shape)) // score_stride(shape))


def softmax(scores: np.ndarray) -> np.ndarray:
    """Row-wise softmax of ``(m, L)`` log scores, float64."""
    e = np.exp(scores - scores.max(axis=1, keepdims=True))
    return e / e.sum(axis=1, keepdims=True)


def project_bias(scores: np.ndarray, target: np.ndarray, start: np.ndarray | None = None,
                 tol: float = 1e-3, max_iter: int = 15) -> np.ndarray:
    """The bias ``b`` with ``mean_v softmax(scores_v + b) == target``.

    Damped Newton on F (see the module docstring) with the labels' Hessian
    ``mean_v (diag p_v - p_v p_v^T)``, a backtracking line search and a warm *start*.
    A label whose target is 0 gets :data:`OFF_BIAS` and takes no part; the others' targets
    are floored at :data:`BALANCE_EPS` and renormalised. F does not change when every bias
    moves together, so the label with the largest target is held at 0, and the others are
    kept within ``+-(spread + MAX_BIAS)`` of it, spread the largest difference between two
    labels' scores at any voxel: a label that no voxel can take stops there, instead
    of running off to infinity, and the search goes on for the others (F's minimum on that
    box; the share the stopped label cannot take goes to the largest label). Stops when
    every free label's fraction is within *tol* (at least two voxels' share) of its
    target, or after *max_iter* steps.
    """
    s = np.asarray(scores, np.float64)
    tgt = np.asarray(target, np.float64)
    on = tgt > 0
    b = np.full(tgt.size, OFF_BIAS)
    b[on] = 0.0 if start is None else np.asarray(start, np.float64)[on]
    if s.shape[0] == 0 or not on.any():
        return b
    pi = np.maximum(tgt[on], BALANCE_EPS)
    pi /= pi.sum()
    s_on = s[:, on] - s[:, on].max(axis=1, keepdims=True)  # the off labels' mass is negligible
    ref = int(np.argmax(pi))
    finite = s_on[np.isfinite(s_on)]
    limit = MAX_BIAS - (float(finite.min()) if finite.size else 0.0)  # s_on <= 0: -min is the spread

    def objective(x: np.ndarray) -> tuple[float, np.ndarray]:
        """F at *x*, and the voxels' laws there (the next step's, if *x* is taken)."""
        z = s_on + x
        m = z.max(axis=1, keepdims=True)
        e = np.exp(z - m)
        total = e.sum(axis=1, keepdims=True)
        return float(np.mean(m + np.log(total)) - pi @ x), e / total

    # Near-one-hot laws move a fraction in steps of one voxel: aim no finer than two.
    tol = max(tol, 2.0 / s.shape[0])
    x = np.clip(b[on] - b[on][ref], -limit, limit)
    f, p = objective(x)
    for _ in range(max_iter):
        q = p.mean(axis=0)
        grad = q - pi
        stuck = ((x >= limit) & (grad < 0)) | ((x <= -limit) & (grad > 0))
        free = ~stuck
        free[ref] = False
        if not free.any() or np.max(np.abs(grad[free])) <= tol:
            break
        hess = np.diag(q) - p.T @ p / p.shape[0]
        step = np.zeros_like(x)
        step[free] = -np.linalg.solve(hess[np.ix_(free, free)] + 1e-9 * np.eye(free.sum()), grad[free])
        # Where the voxels' laws are nearly one-hot the Hessian nearly vanishes and the
        # Newton step is huge: a trust region of MAX_STEP nats keeps the search sane.
        step *= min(1.0, MAX_STEP / max(np.max(np.abs(step)), 1e-300))
        t = 1.0
        while t > 1e-6:
            cand = np.clip(x + t * step, -limit, limit)
            f_cand, p_cand = objective(cand)
            if f_cand <= f + 1e-4 * (grad @ (cand - x)):
                break
            t *= 0.5
        if t <= 1e-6:
            break  # no descent left: as close as it gets
        x, f, p = cand, f_cand, p_cand
    b[on] = x
    return b


def sweep_target(exemplar: np.ndarray, fixed: np.ndarray, n_visited: int, unbiased: np.ndarray,
                 beta: float) -> np.ndarray:
    """The label fractions the visited voxels of a sweep should take.

    ``exemplar`` are the exemplar's fractions ``pi``, ``fixed`` the label counts of the
    voxels the sweep leaves alone (inherited, ``+in``), ``unbiased`` the visited voxels'
    expected fractions without a bias. With ``beta = 1`` the whole volume ends up at
    ``pi``; ``beta`` in (0, 1) goes that fraction of the way from ``unbiased``. Labels
    absent from the exemplar get 0 (the balance then forbids them).
    """
    n_total = n_visited + fixed.sum()
    exact = (exemplar * n_total - fixed) / max(n_visited, 1)
    exact = np.where(exemplar > 0, np.maximum(exact, BALANCE_EPS), 0.0)  # labels the exemplar lacks stay out
    exact /= exact.sum()
    return np.where(exemplar > 0, (1.0 - beta) * unbiased + beta * exact, 0.0)
