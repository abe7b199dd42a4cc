"""What a synthesis run of any method takes and gives: the seed, the block shape, the
progress report after every sweep or pass, and the full result."""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..errors import InputError


@dataclass
class SweepInfo:
    """What a ``progress`` callback receives after every sweep.

    ``scale`` counts from 1 (coarsest) to ``n_scales`` (full resolution); ``temperature``
    is the global temperature after the sweep (the sum of voxel temperatures, or under
    ``relaxation="annealing"`` the t_in of the next sweep) and ``target`` the value that
    ends the scale (0 when a fixed number of ``sweeps`` does). ``eta`` is an estimate in seconds of
    the time left for the whole synthesis. ``volume()`` returns a copy of the block
    at the current scale, and ``exemplar`` is the quantised exemplar decimated to that
    scale (with an exemplar per view, a dict of them by view), so the two can be compared
    during the run.
    """

    scale: int
    n_scales: int
    shape: tuple[int, int, int]
    sweep: int
    max_sweeps: int
    temperature: float
    initial_temperature: float
    target: float
    visited: int
    elapsed: float
    eta: float
    exemplar: np.ndarray | dict[str, np.ndarray] = field(repr=False)
    volume: Callable[[], np.ndarray] = field(repr=False)


@dataclass
class SynthesisResult:
    """A synthesised volume with everything needed to reproduce and judge it.

    Attributes
    ----------
    volume : ndarray
        ``(Z, Y, X)`` in the exemplar's own units and dtype: the exemplar's own values
        when it holds at most ``levels`` of them, else each level's mean value
        (see :func:`clsolid.exemplar.level_map`); for the search methods, float64: means
        of those values (``wl``, ``kopf`` on grey exemplars) or the values themselves
        (``chen-wang``; ``kopf`` on categorical ones). A colour volume is ``(Z, Y, X, 3)``,
        every voxel a palette colour, whatever the method.
    labels : ndarray or None
        The same volume as level indices in ``[0, level_values.size)`` (uint8, or uint16
        above 256 levels): what the engine works on. None for the search methods on grey
        exemplars, whose voxels are exemplar values or their means, not levels (on a colour
        exemplar they work on the palette's labels, and give them).
    exemplar : ndarray or dict
        The exemplar as the engine saw it, in its own units (each pixel replaced by its
        level's value; identical to the input when ``values_exact``); with an exemplar
        per view, a dict of them by view.
    exemplar_labels : ndarray or dict
        The same exemplar (or exemplars) as level indices.
    level_values : ndarray
        Value of each level index: ``level_values[labels] == volume``.
    values_exact : bool
        Whether ``level_values`` are exactly values of the exemplar (False: level means).
    seed : int
        The seed actually used; passing it as ``rng`` reproduces the volume on the same device.
    params : dict
        Every effective parameter, including the per-scale bandwidths.
    device : str
        The back end that ran the synthesis.
    timings : dict
        ``total_s`` and, per scale (coarsest first), the shape, sweeps, global
        temperatures and seconds per sweep.
    site_use : ndarray or None
        Search methods, when asked (``site_map=True``): the position histogram, ``(H, W)``
        int64, how many voxel neighbourhoods (every voxel, every constrained view) of the
        finished block are nearest to each exemplar pixel's; -1 where the pixel has no
        complete neighbourhood (``chen-wang``: how many voxels copy each pixel, its own
        position histogram). :func:`clsolid.preview.save_site_map` draws it.
    source : ndarray or None
        ``method="chen-wang"``: ``(Z, Y, X, 2)`` int64, the exemplar ``(row, column)`` each
        voxel's value was copied from (``exemplar[source[..., 0], source[..., 1]] ==
        volume``).
    """

    volume: np.ndarray
    labels: np.ndarray | None
    exemplar: np.ndarray
    exemplar_labels: np.ndarray
    level_values: np.ndarray
    values_exact: bool
    seed: int
    params: dict
    device: str
    timings: dict
    site_use: np.ndarray | None = None
    source: np.ndarray | None = None


def resolve_seed(rng) -> int:
    """SPEC 7: an int seed, a ``numpy.random.Generator``, or None (fresh entropy)."""
    if rng is None:
        return int(np.random.SeedSequence().generate_state(1, np.uint64)[0] >> np.uint64(1))
    if isinstance(rng, np.random.Generator):
        return int(rng.integers(0, 2**63 - 1))
    if isinstance(rng, numbers.Integral) and not isinstance(rng, bool) and 0 <= rng < 2**64:
        return int(rng)
    raise InputError(f"rng={rng!r} must be a non-negative int seed, a numpy Generator or None")


def check_shape(shape) -> tuple[int, int, int]:
    """*shape* as three ints ``(Z, Y, X)``, each at least 1: integers (not bools), or whole floats
    (not strings, which int() would read too: ``"444"`` is no shape)."""
    try:
        out = tuple(int(s) for s in shape)
        ok = (len(out) == 3 and all(float(s) == o for s, o in zip(shape, out))
              and not any(isinstance(s, (bool, np.bool_, str, bytes)) for s in shape))
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise InputError(f"shape={shape!r} must be three integers (Z, Y, X)")
    if min(out) < 1:
        raise InputError(f"shape={out} must have every size >= 1")
    return out
