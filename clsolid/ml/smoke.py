"""The likelihood method's smoke test, which the device probe runs (:func:`clsolid.core.probe.register_smoke_test`)."""

from __future__ import annotations

import numpy as np

from ..core.device import Device
from ..core.slices import seam_ratio
from ..exemplar import level_map
from .driver import run_ml
from .opencl import CLBackend
from .params import MLParams


def smoke_test(device: Device, vector_width: int) -> None:
    """One sweep of a 4^3 block from a 16x16 exemplar of 32 grey levels, 11 x 11 windows:
    the exact sum's and the relaxation's kernels built and launched at *vector_width*."""
    image = np.random.default_rng(0).integers(0, 32, (16, 16)).astype(np.uint8)
    levels = level_map(image, 32)
    params = MLParams(scales=1, max_sweeps=1).for_exemplar(levels.values.size, levels.exact, seam_ratio(image),
                                                            image.shape)
    run_ml(levels.labels, (4, 4, 4), params, 0, CLBackend(device, vector_width=vector_width))
