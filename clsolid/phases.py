"""Phases: when an exemplar is a segmented image, whose values are names rather than numbers.

One rule decides it for every method and for the evaluation: an exemplar is *categorical*
when its own values are kept (it holds at most ``levels`` distinct values, so none is a
quantisation of grey levels) and there are at most :data:`MAX_PHASES` of them. Its voxels
then take a phase, never a blend, and the methods compare phases as names
(docs/design.md#categorical-exemplars).
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

#: The most values a categorical exemplar holds.
MAX_PHASES = 8


def is_categorical(n_values: int, kept: bool = True) -> bool:
    """Whether an exemplar of *n_values* distinct values is categorical.

    Parameters
    ----------
    n_values : int
        Its distinct values (after the level map, :func:`clsolid.exemplar.level_map`).
    kept : bool
        Whether those are the exemplar's own values (``LevelMap.exact``); False where they
        are the means of quantised grey levels. An image read back from a file (a volume
        to evaluate) keeps its values.

    Returns
    -------
    bool
    """
    return bool(kept) and n_values <= MAX_PHASES


def phase_costs(labels_img: np.ndarray) -> np.ndarray:
    """float32 ``(L,)``: each label's half of a weighted mismatch, ``1 / (2 f_l)`` (f_l: its
    fraction in *labels_img*, labels 0..L-1), so that a mismatch between phases a and b costs
    ``1/(2 f_a) + 1/(2 f_b)``: the chi-square distance of correspondence analysis, under which a
    rare phase's pixel weighs as much as the matrix's do together. Two phases with the same
    fraction are moved one float apart: the kernels tell phases apart by their costs."""
    f = np.bincount(labels_img.ravel().astype(np.intp)) / labels_img.size
    return make_distinct((0.5 / f).astype(np.float32), lambda c: np.nextafter(c, np.float32(np.inf)))


def make_distinct(codes: np.ndarray, step: Callable[[Any], Any]) -> np.ndarray:
    """*codes* (in place) with each code equal to an earlier one moved up by *step* until it
    is not: the kernels tell phases apart by their codes."""
    for i in range(1, codes.size):
        while np.any(codes[:i] == codes[i]):
            codes[i] = step(codes[i])
    return codes
