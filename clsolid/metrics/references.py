"""Reference scales for distances: exemplar halves (the floor) and structureless images (the ceiling).

The floor is the distance between two halves of the exemplar: what a volume "as good as the
exemplar itself" scores, once rescaled from the halves' sample sizes to those of the real
comparison (see :func:`size_factor`; the raw halves distances are kept too). The ceiling is
the distance between the exemplar and as many slices as the view, of the same shape, filled
with its shuffled pixels ("shuffle"), or, for distances that shuffling cannot change
(histograms, volume fractions), with uniform noise over its range ("noise").
Each is repeated to measure its spread; a distance is *informative* for an exemplar only
when its ceiling exceeds its floor by more than :data:`SEPARATION` times their combined
standard deviation.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: Ceiling - floor must exceed this many combined standard deviations to be informative.
SEPARATION = 3.0
#: Cut positions of the random halves, as fractions of the exemplar's side.
CUT_RANGE = (0.4, 0.6)


def exemplar_halves(exemplar: np.ndarray, rng: np.random.Generator,
                    repeats: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """``repeats`` random splits of the exemplar into two near-halves.

    Splits alternate between a horizontal and a vertical cut (starting at random), each at
    a random position in 40-60 % of the side; which part plays the exemplar is random.
    """
    first = int(rng.integers(2))
    out = []
    for k in range(repeats):
        axis = (first + k) % 2
        side = exemplar.shape[axis]
        cut = int(round(rng.uniform(*CUT_RANGE) * side))
        cut = min(max(cut, 1), side - 1)
        a, b = np.split(exemplar, [cut], axis=axis)
        out.append((a, b) if rng.integers(2) else (b, a))
    return out


def shuffled_stack(exemplar: np.ndarray, shape: tuple[int, int], n: int,
                   rng: np.random.Generator) -> np.ndarray:
    """``n`` slices of ``shape`` filled with the exemplar's pixels in random order.

    When more pixels are needed than the exemplar has, its pixels are repeated (each copy
    used equally often) before shuffling, so the histogram is kept exactly.
    """
    flat = exemplar.ravel()
    need = n * shape[0] * shape[1]
    pool = np.tile(flat, -(-need // flat.size))
    return rng.permutation(pool)[:need].reshape(n, *shape)


def noise_stack(lo: float, hi: float, integer: bool, shape: tuple[int, int], n: int,
                rng: np.random.Generator) -> np.ndarray:
    """``n`` slices of uniform noise over ``[lo, hi]`` (whole numbers if ``integer``)."""
    if integer:
        return rng.integers(int(round(lo)), int(round(hi)) + 1, size=(n, *shape)).astype(np.float64)
    return rng.uniform(lo, hi, size=(n, *shape))


def size_factor(n_a: int, n_b: int, n_exemplar: int, n_slices: int, power: float) -> float:
    """Factor taking a halves distance to the sample sizes of the real comparison.

    Sampling noise makes a distance between two samples of one texture grow like
    ``(1/N_a + 1/N_b) ** power``. Two halves hold half the pixels each, the exemplar and
    the slices many more, so the halves overstate what a volume as good as the exemplar
    scores (about 2x for distances, 4x for divergences when the slices are numerous).
    """
    return float(((1.0 / n_exemplar + 1.0 / n_slices) / (1.0 / n_a + 1.0 / n_b)) ** power)


def floor_reference(samples: list[tuple[float | None, int, int]], n_exemplar: int, n_slices: int,
                    power: float) -> dict[str, Any] | None:
    """The floor: raw distances between halves, and the same matched to the comparison's sizes.

    ``mean``/``std``/``min``/``max`` describe the matched values, which the score uses;
    ``halves`` holds the raw halves distances and ``size_factor`` their mean rescaling.
    """
    raw = spread([v for v, _, _ in samples])
    factors = [size_factor(a, b, n_exemplar, n_slices, power) for v, a, b in samples if v is not None]
    matched = spread([v * f for (v, _, _), f in zip([s for s in samples if s[0] is not None], factors)])
    if raw is None or matched is None:
        return None
    return {**matched, "halves": raw, "size_factor": float(np.mean(factors))}


def spread(samples: list[float | None]) -> dict[str, Any] | None:
    """Mean, standard deviation (ddof=1), min, max and count of the defined samples."""
    x = np.array([s for s in samples if s is not None], dtype=np.float64)
    if x.size == 0:
        return None
    return {
        "mean": float(x.mean()),
        "std": float(x.std(ddof=1)) if x.size > 1 else None,
        "min": float(x.min()),
        "max": float(x.max()),
        "n": int(x.size),
    }


def readable(value: float | None, floor: dict | None, ceiling: dict | None) -> dict[str, Any]:
    """Informative flag, normalised score and a note for a distance and its references.

    The score is ``(value - floor) / (ceiling - floor)``: about 0 means as close as two
    halves of the exemplar, about 1 means no more structure than shuffled pixels.
    """
    if value is None:
        return {"informative": False, "score": None,
                "note": "not measurable here (e.g. too few fringes or chords)"}
    if floor is None or ceiling is None:
        missing = "floor" if floor is None else "ceiling"
        return {"informative": None, "score": None,
                "note": f"no {missing}: references skipped, or too little in the exemplar's halves "
                        "(e.g. too few fringes) to measure it"}
    if floor["std"] is None or ceiling["std"] is None:
        return {"informative": None, "score": None, "note": "too few references to judge noise"}
    gap = ceiling["mean"] - floor["mean"]
    noise = math.hypot(floor["std"], ceiling["std"])
    if not (gap > 1e-9 * max(abs(ceiling["mean"]), 1e-12) and gap > SEPARATION * noise):
        return {"informative": False, "score": None,
                "note": "uninformative for this exemplar: its halves and structureless "
                        "images are not told apart"}
    return {"informative": True, "score": float((value - floor["mean"]) / gap), "note": None}
