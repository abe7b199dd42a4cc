"""How often each exemplar site is used: the live histograms over sites that spread a
block's matches over the exemplar (Chen & Wang 2010; Urs thesis, §3.4.2-3.4.3).

``chen-wang`` keeps two (its index and position histograms, ``clsolid.search.chenwang``);
the coherence search of ``wl`` and ``kopf`` keeps one, over its views' matches, to choose
among the candidates (``clsolid.search.coherence``, ``index_histogram``). Both weigh a
site by :func:`excess_factor` and rank candidates by :func:`spread_rank`.
"""

from __future__ import annotations

import numpy as np


def excess_factor(counts: np.ndarray, level: float) -> np.ndarray:
    """``1 + max(0, counts / level - 1)``: 1 up to the uniform *level*, then growing with the
    excess in units of that level."""
    return 1.0 + np.maximum(0.0, counts / level - 1.0)


def spread_rank(ssd: np.ndarray, eps: float, excess: np.ndarray) -> np.ndarray:
    """``(sqrt(ssd) + eps) * excess``: candidates' L2 distances (Kopf's norm, kept off 0 by
    *eps*), each weighed by its site's :func:`excess_factor`. ``chen-wang`` and the coherence
    search (on the host and in the ``coherence_best`` kernel) keep the least."""
    return (np.sqrt(np.maximum(ssd, 0.0)) + eps) * excess


def recount(hist: np.ndarray, old: np.ndarray, new: np.ndarray) -> None:
    """Move counts of *hist* from the *old* sites (-1: none) to the *new* ones (-1: none)."""
    np.subtract.at(hist, old[old >= 0], 1)
    np.add.at(hist, new[new >= 0], 1)
