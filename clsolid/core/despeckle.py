"""Single-voxel specks out of a segmented volume: the last step of every method on phases.

A voxel is a speck when none of its 6 face neighbours shares its phase (the block wraps
around). A speck takes the phase most of its face neighbours have (the lowest on a tie), so
it joins them. The voxels are taken in three passes by a colouring in which face neighbours
never share a colour, wrap included (:func:`colours`), so that no change within a pass
touches another's neighbourhood, the result does not depend on the order, and no change
makes a new speck (a speck's neighbours did not share its phase, and the one it takes is
its neighbours'). Plane by plane, so that a block on disk is never read whole
(docs/design.md#despeckle).
"""

from __future__ import annotations

import numpy as np


def _neighbours(labels: np.ndarray, z: int) -> np.ndarray:
    """``(6, Y, X)``: the face neighbours of every voxel of plane *z*, wrapping."""
    plane, depth = labels[z], labels.shape[0]
    return np.stack([labels[(z - 1) % depth], labels[(z + 1) % depth],
                     np.roll(plane, 1, 0), np.roll(plane, -1, 0), np.roll(plane, 1, 1), np.roll(plane, -1, 1)])


def _majority(nb: np.ndarray) -> np.ndarray:
    """Per column of *nb* ``(6, n)``: the value most rows hold, the lowest on a tie."""
    counts = np.sum(nb[:, None, :] == nb[None, :, :], axis=1)  # (6, n): how many rows share row i's value
    order = np.lexsort((nb, -counts), axis=0)[0]  # most shared first, then the lowest value
    return nb[order, np.arange(nb.shape[1])]


def _cycle(n: int) -> np.ndarray:
    """A colouring of the cycle 0..n-1 in 0, 1, 2 that neighbours (n - 1 and 0 too) never share:
    alternate 0 and 1, and the last 2 where n is odd."""
    c = np.arange(n) % 2
    if n % 2:
        c[-1] = 2
    return c


def colours(shape: tuple[int, int, int]) -> tuple[np.ndarray, np.ndarray]:
    """The despeckling passes' colouring of a toroidal block: ``(c_z(z) + c_y(y) + c_x(x)) % 3``
    with each axis's :func:`_cycle`, as ``(c_z (Z,), plane (Y, X))``. Face neighbours differ
    along one axis, by 1 or 2 in its colours: never by 0 modulo 3."""
    return _cycle(shape[0]), _cycle(shape[1])[:, None] + _cycle(shape[2])[None, :]


def specks(labels: np.ndarray) -> int:
    """How many voxels of *labels* ``(Z, Y, X)`` no face neighbour shares the phase of."""
    return int(sum(np.count_nonzero(np.all(_neighbours(labels, z) != labels[z], axis=0))
                   for z in range(labels.shape[0])))


def despeckle(labels: np.ndarray) -> int:
    """Give every speck of *labels* (in place) the phase most of its face neighbours have.

    Parameters
    ----------
    labels : numpy.ndarray
        ``(Z, Y, X)`` phases (any integer or exact-valued dtype), toroidal; changed in place
        (a memory-mapped array is read and written a plane at a time).

    Returns
    -------
    int
        The voxels changed; afterwards :func:`specks` is 0.
    """
    changed = 0
    by_z, by_yx = colours(labels.shape)
    for colour in range(3):
        for z in range(labels.shape[0]):
            nb = _neighbours(labels, z)
            plane = labels[z]
            speck = np.all(nb != plane, axis=0) & ((by_yx + by_z[z]) % 3 == colour)
            if speck.any():
                plane[speck] = _majority(nb[:, speck])
                changed += int(np.count_nonzero(speck))
    return changed
