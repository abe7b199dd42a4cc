"""Phase codes: how the search methods compare a categorical exemplar's phases
(``distance="weighted"``; a departure, docs/design.md#phase-distance).

A phase's grey value is a name, not a number: by squared differences phases 85 and 170 are
nearer than 0 and 255, and a three- or four-phase exemplar is matched by an order its phases
do not have. With phase codes the finest level compares phases as the likelihood method's
weighted mismatch does (:func:`clsolid.phases.phase_costs`): a mismatch between phases a and
b costs ``c_a + c_b``, with ``c_p = S / (2 f_p)`` (f_p the phase's fraction: a rare phase's
shapes weigh as much as the matrix's), an equal pair nothing. Each phase's value is replaced
by its code in the matched squares, exemplar and block alike, and the matcher adds
``[a != b] (a + b)`` for those terms (``NMIS`` in ``kernels/search/match.cl``); the parent
square, a blend of the coarser level, keeps squared differences. S makes the mean cost
between two random pixels the mean squared difference of two random grey levels (2 var), so
that the parent's terms keep their share: every phase has ``f_p c_p = S / 2``, so that mean
is ``(P - 1) S`` for P phases, and ``S = 2 var / (P - 1)``. The codes are rounded to distinct
integers, so that distances are exact in float32 while below 2^24.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..exemplar import nearest_level_index
from ..phases import make_distinct, phase_costs


@dataclass(frozen=True)
class PhaseCodes:
    """The sorted *phases* (grey values) of an exemplar and each one's *code* (float64, integers)."""

    phases: np.ndarray
    codes: np.ndarray

    def encode(self, values: np.ndarray) -> np.ndarray:
        """*values* with each replaced by the code of its nearest phase (a blend, as an
        up-sampled coarser level holds, counts for its nearest phase), float64, same shape."""
        return self.codes[nearest_level_index(values, self.phases)].reshape(np.shape(values))

    def encode_terms(self, rows: np.ndarray, n: int) -> np.ndarray:
        """A copy of feature *rows* ``(m, dim)`` with their first *n* terms encoded."""
        out = np.array(rows, np.float64)
        out[:, :n] = self.encode(out[:, :n])
        return out


def phase_codes(exemplar: np.ndarray) -> PhaseCodes:
    """The codes of a categorical *exemplar*'s phases (at least two values)."""
    phases = np.unique(exemplar)
    if phases.size < 2:
        raise ValueError("phase codes need at least two phases")
    labels = nearest_level_index(exemplar, phases).reshape(np.shape(exemplar))
    scale = 2.0 * float(np.var(exemplar)) / (phases.size - 1)
    codes = np.maximum(np.rint(scale * phase_costs(labels).astype(np.float64)), 1.0)
    return PhaseCodes(phases=phases.astype(np.float64), codes=make_distinct(codes, lambda c: c + 1.0))
