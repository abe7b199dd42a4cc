"""The Gaussian pyramid of the search methods (Urs thesis, §3.2.3): a 5-tap binomial low-pass
filter, [1 4 6 4 1] / 16 on each axis, then 2:1 decimation."""

from __future__ import annotations

import numpy as np

#: The low-pass filter applied before each 2:1 decimation.
BINOMIAL5 = np.array([1.0, 4.0, 6.0, 4.0, 1.0]) / 16.0


def _blur(img: np.ndarray, mode: str) -> np.ndarray:
    out = np.asarray(img, np.float64)
    for axis in range(out.ndim):
        padded = np.pad(out, [(2, 2) if a == axis else (0, 0) for a in range(out.ndim)], mode=mode)
        n = out.shape[axis]
        out = sum(w * np.take(padded, np.arange(i, i + n), axis=axis) for i, w in enumerate(BINOMIAL5))
    return out


def upsampled(coarse: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """The coarser level *coarse* up-sampled 2:1 on each of the leading axes to *shape*
    (each value repeated, wrapping where a side is odd), float64; trailing axes of *coarse*
    (a tensor's components) are kept."""
    idx = np.ix_(*[(np.arange(n) // 2) % m for n, m in zip(shape, coarse.shape)])
    return coarse[idx].astype(np.float64)


def gaussian_pyramid(exemplar: np.ndarray, levels: int) -> list[np.ndarray]:
    """``levels`` images, finest first: level l+1 is level l filtered and decimated 2:1.

    The exemplar is not toroidal (Urs thesis, §3.2.4), so its edges are mirrored for the filter.
    """
    pyr = [np.asarray(exemplar, np.float64)]
    for _ in range(levels - 1):
        pyr.append(_blur(pyr[-1], "reflect")[::2, ::2])
    return pyr
