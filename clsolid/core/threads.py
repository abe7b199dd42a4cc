"""The host's BLAS threads while an OpenCL CPU device computes."""

from __future__ import annotations

import contextlib
import functools
from typing import Iterator


@functools.lru_cache(maxsize=1)
def _controller():
    from threadpoolctl import ThreadpoolController  # scans the loaded libraries once (~1 ms)

    return ThreadpoolController()


@contextlib.contextmanager
def serial_blas() -> Iterator[None]:
    """Run the block with NumPy's BLAS (and LAPACK) on one thread, restoring it after.

    The drivers' host work between kernel launches is small linear algebra (the label
    balance's Hessian, sampled voxels x labels, after every conflict-free set). A BLAS pool
    of several threads spins for cores that the OpenCL CPU runtime's threads hold, and
    gains nothing on matrices this small: it slows the sweeps with the balance several-fold
    (docs/design.md#blas-threads). OpenBLAS splits a product by rows and
    columns, not along the sum, so one thread gives the same results bit for bit.
    """
    with _controller().limit(limits=1, user_api="blas"):
        yield
