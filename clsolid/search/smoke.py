"""The search methods' smoke test, which the device probe runs (:func:`clsolid.core.probe.register_smoke_test`)."""

from __future__ import annotations

import numpy as np

from ..core.device import Device
from ..errors import KernelBuildError
from .match import CLMatcher, ReferenceMatcher, exemplar_table


def smoke_test(device: Device, vector_width: int) -> None:
    """The nearest sites of a few queries in a 16x16 exemplar's 7 x 7 table, at *vector_width*,
    equal to the float64 reference's (integer grey levels: exact in float32)."""
    rng = np.random.default_rng(0)
    table, _ = exemplar_table(rng.integers(0, 32, (16, 16)).astype(np.float64), 7)
    queries = rng.integers(0, 32, (5, table.shape[1])).astype(np.float64)
    found = CLMatcher(device, table, vector_width=vector_width).nearest(queries, 4)[0]
    expected = ReferenceMatcher(table).nearest(queries, 4)[0]
    if not np.array_equal(found, expected):
        raise KernelBuildError(f"the search kernels ran at vector width {vector_width} but found other sites "
                               "than the reference")
