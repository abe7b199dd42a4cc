"""Philox4x32-10 counter-based generator (Salmon et al., SC'11) in NumPy.

The kernels use Random123's ``philox4x32`` (shipped with pyopencl); this is the
bit-exact NumPy twin used by the float64 reference and by the tests. A stream is
keyed by the seed, and counted by voxel coordinates and a tag (sweep or purpose),
so the numbers do not depend on the device, the work-group size or the order in
which voxels are processed.
"""

from __future__ import annotations

import numpy as np

_M0, _M1 = np.uint64(0xD2511F53), np.uint64(0xCD9E8D57)
_W0, _W1 = np.uint64(0x9E3779B9), np.uint64(0xBB67AE85)
_LO = np.uint64(0xFFFFFFFF)

#: Tags that separate the streams drawn for different purposes. The random start uses
#: TAG_INIT; the stochastic relaxations use :func:`relax_tag`, which never equals it.
TAG_INIT = 0
#: Purpose field (bits 28-31) of the relaxation tags, and of the pruned likelihood's sample.
PURPOSE_RELAX = 1
PURPOSE_SAMPLE = 2


def relax_tag(level: int, sweep: int) -> int:
    """Tag of the relaxation draws of one sweep: ``purpose << 28 | level << 20 | sweep``.

    *level* is the scale (0 = full resolution, < 256) and *sweep* counts from 1 within
    the scale (< 2^20). Each voxel is visited at most once per sweep, so the counter
    (x, y, z, tag) is used once; its four words serve the draws of that one visit.
    """
    if not (0 <= level < 256 and 0 <= sweep < 1 << 20):
        raise ValueError(f"level={level} or sweep={sweep} out of the tag's range")
    return (PURPOSE_RELAX << 28) | (level << 20) | sweep


def tag_sweep(tag: int) -> int:
    """The sweep (from 1 within its scale) of relaxation tag *tag* (:func:`relax_tag`)."""
    return tag & ((1 << 20) - 1)


def sample_tag(tag: int) -> int:
    """The tag of the pruned likelihood's site sample in the sweep of relaxation tag *tag*:
    the same level and sweep, purpose :data:`PURPOSE_SAMPLE`."""
    return (PURPOSE_SAMPLE << 28) | (tag & 0x0FFFFFFF)


def philox4x32(counter: np.ndarray, key: np.ndarray, rounds: int = 10) -> np.ndarray:
    """Apply Philox4x32 to ``counter`` (``(..., 4)`` uint32) with ``key`` (``(..., 2)`` uint32).

    Returns the ``(..., 4)`` uint32 output block.
    """
    c = np.asarray(counter, dtype=np.uint32)
    k = np.asarray(key, dtype=np.uint32)
    c0, c1, c2, c3 = (c[..., i].astype(np.uint64) for i in range(4))
    k0, k1 = k[..., 0].astype(np.uint64), k[..., 1].astype(np.uint64)
    for r in range(rounds):
        if r:  # key schedule in 64-bit arithmetic, wrapped to 32 bits
            k0 = (k0 + _W0) & _LO
            k1 = (k1 + _W1) & _LO
        p0, p1 = _M0 * c0, _M1 * c2
        hi0, lo0 = p0 >> np.uint64(32), p0 & _LO
        hi1, lo1 = p1 >> np.uint64(32), p1 & _LO
        c0, c1, c2, c3 = hi1 ^ c1 ^ k0, lo1, hi0 ^ c3 ^ k1, lo0
    return np.stack([c0, c1, c2, c3], axis=-1).astype(np.uint32)


def seed_key(seed: int) -> np.ndarray:
    """The Philox key of a 64-bit seed."""
    seed = int(seed) & 0xFFFFFFFFFFFFFFFF
    return np.array([seed & 0xFFFFFFFF, seed >> 32], dtype=np.uint32)


def voxel_words(seed: int, z: np.ndarray, y: np.ndarray, x: np.ndarray, tag: int) -> np.ndarray:
    """The four Philox words ``(..., 4)`` of voxels at ``(z, y, x)``, counter ``(x, y, z, tag)``."""
    x = np.asarray(x, dtype=np.uint32)
    ctr = np.stack([x, np.asarray(y, np.uint32), np.asarray(z, np.uint32), np.full_like(x, tag)], axis=-1)
    return philox4x32(ctr, seed_key(seed))


def voxel_uint32(seed: int, shape: tuple[int, int, int], tag: int) -> np.ndarray:
    """First Philox word for every voxel of a ``(Z, Y, X)`` block, counter ``(x, y, z, tag)``."""
    z, y, x = np.meshgrid(*(np.arange(n, dtype=np.uint32) for n in shape), indexing="ij")
    return voxel_words(seed, z, y, x, tag)[..., 0]


def unit_float(u: np.ndarray) -> np.ndarray:
    """Uniform words to floats in [0, 1): ``(u >> 8) * 2^-24``, exact in float32 and float64."""
    return (np.asarray(u, np.uint32) >> np.uint32(8)).astype(np.float64) * 2.0**-24


def bounded(u: np.ndarray, n: int) -> np.ndarray:
    """Map uniform uint32 words to ``[0, n)`` by multiply-high (as ``mul_hi`` in the kernels)."""
    return ((u.astype(np.uint64) * np.uint64(n)) >> np.uint64(32)).astype(np.int64)
