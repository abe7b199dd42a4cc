"""Generated 3D ground truths: volumes whose 3D statistics are known, to validate a synthesis.

A synthesis sees only 2D sections of a material; these volumes are the material itself.
Slice one (:func:`sections`), grow a volume from the slice, and compare the two volumes'
3D statistics (correlation lengths along each axis, phase fractions, particle shapes).

Conventions
-----------
* **Values.** Every volume is ``uint8`` phase labels ``0 .. n - 1`` (``(Z, Y, X)``, as
  everywhere in clsolid); map them to grey values as the exemplars need.
* **Units.** Lengths are in voxels: a larger side shows more of the same material at the
  same voxel size, so a 256 side is sliced at 256 x 256 with the features as specified.
* **Determinism.** Each function draws from ``numpy.random.default_rng(seed)`` only: the
  same arguments give the same bits.
* **Periodicity.** The volumes are periodic (they tile), as the gallery's exemplars are:
  no face of the cube differs from its inside.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from statistics import NormalDist
from typing import Any, Callable, Sequence

import numpy as np

from .core.views import DEPTH_AXIS
from .errors import InputError
from .preview import view_slice
from .volumeio import _check_volume

#: Largest volume generated, in voxels (512^3): the fields are float64 in host memory.
MAX_VOXELS = 512**3
#: Smallest side along any axis.
MIN_SIDE = 8
#: The level the phases' autocorrelation falls to at a correlation length (as in
#: :func:`clsolid.metrics.correlation_length`).
_HALF = 0.5
#: Gauss-Legendre nodes for the bivariate normal integral (smooth after r = sin t).
_NODES = np.polynomial.legendre.leggauss(64)


# --------------------------------------------------------------------------- checks


def _check_shape(shape: Any, name: str = "shape") -> tuple[int, int, int]:
    """An int side (a cube) or a (Z, Y, X) triple of ints, each >= MIN_SIDE."""
    sides = (shape,) * 3 if isinstance(shape, numbers.Integral) and not isinstance(shape, bool) else shape
    try:
        sides = tuple(sides)
    except TypeError:
        raise InputError(f"{name}={shape!r} must be a side (int) or a (Z, Y, X) triple of ints") from None
    if len(sides) != 3 or any(isinstance(s, bool) or not isinstance(s, numbers.Integral) or s < MIN_SIDE
                              for s in sides):
        raise InputError(f"{name}={shape!r} must be a side or a (Z, Y, X) triple of integers >= {MIN_SIDE}")
    sides = tuple(int(s) for s in sides)
    if math.prod(sides) > MAX_VOXELS:  # Python ints: a huge shape must not wrap
        raise InputError(f"{name}={shape!r} has {math.prod(sides)} voxels, more than "
                         f"{MAX_VOXELS} (512^3); generate a smaller volume")
    return sides


def _check_seed(seed: Any) -> int:
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise InputError(f"seed={seed!r} must be an integer >= 0")
    return int(seed)


def _check_positive(value: Any, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not np.isfinite(value) or value <= 0:
        raise InputError(f"{name}={value!r} must be a positive finite number")
    return float(value)


def _check_fractions(fractions: Any, size: int) -> np.ndarray:
    """At least two positive fractions summing to 1, each at least one voxel of *size*."""
    try:
        f = np.asarray(fractions, dtype=np.float64)
    except (TypeError, ValueError):
        f = np.array([np.nan])
    if f.ndim != 1 or not 2 <= f.size <= 255 or not np.all(np.isfinite(f)) or abs(f.sum() - 1.0) > 1e-6:
        raise InputError(f"fractions={fractions!r} must be 2 to 255 phase fractions summing to 1")
    if np.any(f * size < 1.0):
        raise InputError(f"fractions={fractions!r}: every phase needs at least one voxel of the {size}")
    return f / f.sum()


# --------------------------------------------------------------------------- Gaussian fields


def _phase_correlation(c: float, thresholds: np.ndarray, base: float) -> float:
    """Expected phase autocorrelation (:func:`clsolid.metrics.lag_correlations`' definition)
    of a standard Gaussian field cut at *thresholds*, between two voxels whose field
    values correlate by *c*; *base* is the sum of the squared phase fractions.

    ``d/dr P(X<=a, Y<=b) = phi2(a, b; r)`` (Plackett), so the chance that both voxels fall
    in one phase rises from ``base`` at r = 0 by the integral over r of a sum of bivariate
    normal densities; r = sin(t) removes the density's singularity at r = 1.
    """
    x, w = _NODES
    top = np.arcsin(c)
    t = 0.5 * top * (x + 1.0)
    r, cos2 = np.sin(t), np.cos(t) ** 2

    def dens(a: float, b: float) -> np.ndarray:  # phi2(a, b; r) dr / dt
        return np.exp(-(a * a - 2.0 * r * a * b + b * b) / (2.0 * cos2)) / (2.0 * np.pi)

    g = sum(2.0 * dens(a, a) for a in thresholds)
    g = g - sum(2.0 * dens(a, b) for a, b in zip(thresholds[:-1], thresholds[1:]))
    return float(0.5 * top * np.dot(w, g) / (1.0 - base))


def _field_sigma(length: float, fractions: np.ndarray) -> float:
    """Standard deviation (voxels) of the Gaussian covariance ``exp(-r^2 / (2 s^2))`` whose
    field, cut into *fractions*, has phases correlated by one half at lag *length*."""
    thresholds = np.array([NormalDist().inv_cdf(q) for q in np.cumsum(fractions)[:-1]])
    base = float(np.sum(fractions**2))
    lo, hi = 0.0, 1.0 - 1e-12
    for _ in range(60):  # bisection: the correlation rises with c
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _phase_correlation(mid, thresholds, base) < _HALF else (lo, mid)
    c = 0.5 * (lo + hi)
    return length / np.sqrt(2.0 * np.log(1.0 / c))


def _gaussian_field(shape: tuple[int, int, int], sigmas: Sequence[float], rng: np.random.Generator) -> np.ndarray:
    """Periodic white noise low-passed to the Gaussian covariance ``exp(-sum r_i^2 / (2 s_i^2))``.

    The covariance's spectrum is ``exp(-2 pi^2 sum s_i^2 k_i^2)`` (k in cycles per voxel), so
    the noise's Fourier coefficients are multiplied by its square root, one factor per axis.
    """
    spec = np.fft.rfftn(rng.standard_normal(shape))
    freqs = [np.fft.fftfreq(shape[0]), np.fft.fftfreq(shape[1]), np.fft.rfftfreq(shape[2])]
    for axis, (k, s) in enumerate(zip(freqs, sigmas)):
        spec *= np.exp(-(np.pi * s * k) ** 2).reshape([-1 if a == axis else 1 for a in range(3)])
    return np.fft.irfftn(spec, s=shape, axes=(0, 1, 2))


def _cut(values: np.ndarray, fractions: np.ndarray) -> np.ndarray:
    """Labels 0 .. n-1 by rank: the lowest ``round(f_0 N)`` values phase 0, and so on
    (exact counts up to ties)."""
    flat = values.ravel()
    stops = np.round(np.cumsum(fractions) * flat.size).astype(np.int64)[:-1]
    thresholds = np.partition(flat, stops - 1)[stops - 1]
    labels = np.zeros(values.shape, np.uint8)
    for t in thresholds:
        labels += values > t
    return labels


def _thresholded(shape: Any, seed: Any, lengths: Sequence[Any], names: Sequence[str],
                 fractions: Any) -> np.ndarray:
    sides = _check_shape(shape)
    rng = np.random.default_rng(_check_seed(seed))
    f = _check_fractions(fractions, int(np.prod(sides)))
    sigmas = []
    for value, name, n in zip(lengths, names, sides):
        length = _check_positive(value, name)
        # Shorter ones alias on the grid; longer ones the metrics cannot measure (lags to half a side).
        if not 1.0 <= length <= n / 2:
            raise InputError(f"{name}={value!r} must be 1 to {n / 2:g} voxels (half the side along that axis)")
        sigmas.append(_field_sigma(length, f))
    return _cut(_gaussian_field(sides, sigmas, rng), f)


def isotropic_field(shape: int | Sequence[int], *, seed: int, correlation_length: float = 8.0,
                    fractions: Sequence[float] = (0.5, 0.5)) -> np.ndarray:
    """An isotropic thresholded Gaussian random field: a bicontinuous 2- or n-phase medium.

    White noise is low-passed in Fourier space to a Gaussian covariance and cut at its
    quantiles into phases 0 .. n-1 (lowest field values phase 0).

    Parameters
    ----------
    shape : int or (int, int, int)
        The cube's side, or ``(Z, Y, X)``; every side at least 8 and at most 512^3 voxels.
    seed : int
        Seed of ``numpy.random.default_rng``; the same seed gives the same volume.
    correlation_length : float, default 8.0
        Voxels at which the phases' autocorrelation falls to one half, along every axis, as
        :func:`clsolid.metrics.correlation_length` measures it on ``lag_correlations`` with
        the phases given: the field's covariance is scaled so that its cut has this length
        in expectation. 1 to half the shortest side.
    fractions : sequence of float, default (0.5, 0.5)
        Phase fractions, summing to 1; their number is the number of phases. Exact up to
        rounding to whole voxels.

    Returns
    -------
    numpy.ndarray
        ``(Z, Y, X)`` uint8 labels ``0 .. len(fractions) - 1``.

    Raises
    ------
    InputError
        A shape, seed, length or fraction out of range.
    """
    return _thresholded(shape, seed, (correlation_length,) * 3, ("correlation_length",) * 3, fractions)


def anisotropic_field(shape: int | Sequence[int], *, seed: int,
                      correlation_lengths: Sequence[float] = (4.0, 8.0, 16.0),
                      fractions: Sequence[float] = (0.5, 0.5)) -> np.ndarray:
    """A thresholded Gaussian random field with its own correlation length along each axis.

    As :func:`isotropic_field`, with the Gaussian covariance stretched along z, y and x by
    different factors: features are ellipsoids elongated along the longest length, as in
    a rolled or directionally grown material.

    Parameters
    ----------
    shape : int or (int, int, int)
        The cube's side, or ``(Z, Y, X)``; every side at least 8 and at most 512^3 voxels.
    seed : int
        Seed of ``numpy.random.default_rng``; the same seed gives the same volume.
    correlation_lengths : (float, float, float), default (4.0, 8.0, 16.0)
        Phase correlation lengths (voxels; see :func:`isotropic_field`) along z, y and x,
        each 1 to half the side along its axis.
    fractions : sequence of float, default (0.5, 0.5)
        Phase fractions, summing to 1, as for :func:`isotropic_field`.

    Returns
    -------
    numpy.ndarray
        ``(Z, Y, X)`` uint8 labels ``0 .. len(fractions) - 1``.

    Raises
    ------
    InputError
        A shape, seed, length or fraction out of range.
    """
    try:
        lengths = tuple(correlation_lengths)
    except TypeError:
        lengths = ()
    if len(lengths) != 3:
        raise InputError(f"correlation_lengths={correlation_lengths!r} must be three lengths (z, y, x)")
    names = tuple(f"correlation_lengths[{i}]" for i in range(3))
    return _thresholded(shape, seed, lengths, names, fractions)


# --------------------------------------------------------------------------- particles


#: Candidate centres drawn at once, and rounds of them, before a particle is given up.
_BATCH, _ROUNDS = 32, 16


def _place_spheres(rng: np.random.Generator, side: int, diameters: np.ndarray,
                   gap: float) -> tuple[np.ndarray, np.ndarray]:
    """Random sequential addition of non-overlapping spheres in the periodic cube.

    Each sphere, largest first (as a sieve fills), takes the first of up to
    ``_BATCH * _ROUNDS`` uniform centres whose surface is at least *gap* from every sphere
    already placed; it is dropped if none is. Returns the centres ``(n, 3)`` and radii.
    """
    centres = np.empty((0, 3))
    radii = np.empty(0)
    for d in np.sort(diameters)[::-1]:
        r = d / 2.0
        for _ in range(_ROUNDS):
            cand = rng.random((_BATCH, 3)) * side
            delta = cand[:, None, :] - centres[None, :, :]
            delta -= side * np.round(delta / side)  # nearest periodic image
            fits = np.all(np.sqrt(np.sum(delta**2, axis=2)) >= r + radii[None, :] + gap, axis=1)
            if fits.any():
                centres = np.vstack([centres, cand[np.argmax(fits)]])
                radii = np.append(radii, r)
                break
    return centres, radii


def particulate_composite(side: int, *, seed: int, diameters: tuple[float, float] = (20.0, 40.0),
                          particle_fraction: float = 0.35, gap: float = 2.0, binder: float = 1.0,
                          neck: float = 5.0) -> np.ndarray:
    """Round particles packed without overlap in a matrix, coated and joined by a thin binder.

    A 3-phase particulate composite, such as a battery electrode (active particles, carbon
    binder, pores) or a cermet: spheres of uniformly distributed diameters are placed by
    random sequential addition, largest first; a binder shell coats each, and binder necks
    fill the narrow gaps between neighbours.

    Parameters
    ----------
    side : int
        The cube's side, at most 512 and at least ``2 * (diameters[1] + gap)`` and
        ``diameters[1] + 2 * max(binder, neck) + 5``, so that no sphere, nor the voxels
        within reach of its shell, meets its own periodic image.
    seed : int
        Seed of ``numpy.random.default_rng``; the same seed gives the same volume.
    diameters : (float, float), default (20.0, 40.0)
        Smallest and largest particle diameter, voxels; at least 2.
    particle_fraction : float, default 0.35
        Volume fraction of particles asked, in (0, 0.5]. Spheres are drawn until their
        volume reaches it; those that find no place are dropped, so a dense packing comes
        out below it (random sequential addition jams near 0.38 for one size).
    gap : float, default 2.0
        Smallest distance between two particles' surfaces, voxels. At least 2 keeps them
        apart on the grid: no two voxels of different particles are neighbours, diagonals
        included.
    binder : float, default 1.0
        Thickness of the binder shell on every particle, voxels (0 to 4).
    neck : float, default 5.0
        Gaps up to this wide (voxels, 0 to 8) are bridged by a binder neck: the voxels whose
        distances to the two nearest particle surfaces add up to at most ``neck``.

    Returns
    -------
    numpy.ndarray
        ``(side, side, side)`` uint8 labels: 0 matrix, 1 particle (voxel centres inside a
        sphere), 2 binder.

    Raises
    ------
    InputError
        A side, seed, diameter, fraction or thickness out of range.
    """
    seed = _check_seed(seed)
    try:
        dmin, dmax = (float(d) for d in diameters)
    except (TypeError, ValueError):
        raise InputError(f"diameters={diameters!r} must be two numbers (smallest, largest)") from None
    if not 2.0 <= dmin <= dmax or not np.isfinite(dmax):
        raise InputError(f"diameters={diameters!r} must be finite with 2 <= smallest <= largest")
    gap = _check_positive(gap, "gap")
    fraction = _check_positive(particle_fraction, "particle_fraction")
    if fraction > 0.5:
        raise InputError(f"particle_fraction={particle_fraction!r} must be at most 0.5; "
                         "random sequential addition cannot pack spheres denser")
    for value, name, top in ((binder, "binder", 4.0), (neck, "neck", 8.0)):
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0.0 <= value <= top:
            raise InputError(f"{name}={value!r} must be a number from 0 to {top:g} voxels")
    reach = max(float(binder), float(neck)) + 1.0
    # No sphere may meet its own periodic image, nor its box of voxels wrap onto itself.
    least = int(np.ceil(max(2.0 * (dmax + gap), dmax + 2.0 * reach + 3.0)))
    if isinstance(side, bool) or not isinstance(side, numbers.Integral) or not least <= side <= 512:
        raise InputError(f"side={side!r} must be an integer from {least} (for diameters up to {dmax:g}, "
                         "so that no particle meets its periodic image) to 512")
    side = int(side)
    rng = np.random.default_rng(seed)

    # One draw of diameters, half as many again as the mean sphere volume asks, so that their
    # volume passes the target; the first that reach it are placed.
    target = fraction * side**3
    mean_cube = (dmax**4 - dmin**4) / (4.0 * (dmax - dmin)) if dmax > dmin else dmin**3
    drawn = rng.uniform(dmin, dmax, size=int(np.ceil(1.5 * target / (np.pi / 6.0 * mean_cube))) + 8)
    keep = np.searchsorted(np.cumsum(np.pi / 6.0 * drawn**3), target) + 1
    centres, radii = _place_spheres(rng, side, drawn[:keep], gap)

    # Distances to the nearest and second-nearest particle surface, within reach of a shell or neck.
    near = np.full((side,) * 3, np.inf, np.float32)
    second = np.full((side,) * 3, np.inf, np.float32)
    for c, r in zip(centres, radii):
        axes = [np.arange(int(np.floor(ci - r - reach)), int(np.ceil(ci + r + reach)) + 1) for ci in c]
        dz, dy, dx = ((a - ci).astype(np.float32) ** 2 for a, ci in zip(axes, c))
        d = np.sqrt(dz[:, None, None] + dy[None, :, None] + dx[None, None, :]) - np.float32(r)
        box = np.ix_(*(a % side for a in axes))
        n1, n2 = near[box], second[box]
        second[box] = np.minimum(n2, np.maximum(n1, d))
        near[box] = np.minimum(n1, d)
    labels = np.zeros((side,) * 3, np.uint8)
    labels[(near < binder) | (near + second <= neck)] = 2
    labels[near < 0] = 1
    return labels


# --------------------------------------------------------------------------- registry and sections


@dataclass(frozen=True)
class GroundTruthEntry:
    """What one registered ground truth is.

    Attributes
    ----------
    name : str
        Its name in the registry.
    description : str
        One line: the material it stands for.
    phases : tuple of str
        What each label ``0 .. n - 1`` is.
    min_side : int
        Smallest side :func:`ground_truth` makes it at.
    source : str
        How it is made (the function and its arguments).
    """

    name: str
    description: str
    phases: tuple[str, ...]
    min_side: int
    source: str
    _make: Callable[[int, int], np.ndarray] | None = field(default=None, repr=False, compare=False)


#: Largest side :func:`ground_truth` accepts.
MAX_SIDE = 512
_ISO = dict(correlation_length=8.0)
_ANISO = dict(correlation_lengths=(3.0, 6.0, 12.0))
_THREE = dict(fractions=(0.4, 0.35, 0.25))
_ENTRIES = (
    GroundTruthEntry("iso2", "isotropic bicontinuous 2-phase medium, 50 % each (sandstone, spinodal)",
                     ("phase A", "phase B"), 32, "isotropic_field, correlation_length=8",
                     lambda side, seed: isotropic_field(side, seed=seed, **_ISO)),
    GroundTruthEntry("iso3", "isotropic 3-phase medium, 40/35/25 % (a thresholded field cut twice)",
                     ("phase A", "phase B", "phase C"), 32,
                     "isotropic_field, correlation_length=8, fractions=(0.4, 0.35, 0.25)",
                     lambda side, seed: isotropic_field(side, seed=seed, **_ISO, **_THREE)),
    GroundTruthEntry("aniso2", "anisotropic 2-phase medium, features 2x longer along y than z and x than y",
                     ("phase A", "phase B"), 32, "anisotropic_field, correlation_lengths=(3, 6, 12)",
                     lambda side, seed: anisotropic_field(side, seed=seed, **_ANISO)),
    GroundTruthEntry("aniso3", "anisotropic 3-phase medium, 40/35/25 %, lengths 3, 6, 12 along z, y, x",
                     ("phase A", "phase B", "phase C"), 32,
                     "anisotropic_field, correlation_lengths=(3, 6, 12), fractions=(0.4, 0.35, 0.25)",
                     lambda side, seed: anisotropic_field(side, seed=seed, **_ANISO, **_THREE)),
    GroundTruthEntry("particles", "round particles 20-40 voxels across in a matrix, with a thin binder "
                     "(battery electrode, cermet)", ("matrix", "particle", "binder"), 84,
                     "particulate_composite, diameters=(20, 40), particle_fraction=0.35",
                     lambda side, seed: particulate_composite(side, seed=seed)),
)
_REGISTRY = {e.name: e for e in _ENTRIES}


def ground_truth_names() -> tuple[str, ...]:
    """Names of the registered ground truths, in the order they are listed."""
    return tuple(_REGISTRY)


def ground_truth_info(name: str) -> GroundTruthEntry:
    """What the ground truth ``name`` is: description, phases, smallest side and source.

    Raises
    ------
    InputError
        ``name`` is not registered.
    """
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise InputError(f"name={name!r} is not a ground truth; use one of {', '.join(_REGISTRY)}") from None


def ground_truth(name: str, side: int, *, seed: int = 0) -> np.ndarray:
    """One registered ground truth, as a ``(side, side, side)`` uint8 label volume.

    Parameters
    ----------
    name : str
        One of :func:`ground_truth_names`.
    side : int
        The cube's side, from the entry's ``min_side`` to 512. Lengths are in voxels: a
        larger side shows more of the same material.
    seed : int, default 0
        Seed of the generator; the same name, side and seed give the same volume.

    Returns
    -------
    numpy.ndarray
        ``(side, side, side)`` uint8 labels ``0 .. n - 1`` (see ``ground_truth_info(name).phases``).

    Raises
    ------
    InputError
        Unknown ``name``, ``side`` out of range or a bad ``seed``.
    """
    entry = ground_truth_info(name)
    if isinstance(side, bool) or not isinstance(side, numbers.Integral) or not entry.min_side <= side <= MAX_SIDE:
        raise InputError(f"side={side!r} must be an integer from {entry.min_side} to {MAX_SIDE} for {name!r}")
    return entry._make(int(side), _check_seed(seed))


def sections(volume: np.ndarray) -> dict[str, np.ndarray]:
    """The three central orthogonal sections of a volume, oriented as the views.

    Parameters
    ----------
    volume : numpy.ndarray
        ``(Z, Y, X)`` volume.

    Returns
    -------
    dict
        ``{"front": volume[Z // 2], "right": volume[:, :, X // 2].T, "top": volume[:, Y // 2, :]}``:
        rows y and columns x, rows y and columns z, rows z and columns x
        (:func:`clsolid.preview.view_slice`). Views of ``volume``, not copies.

    Raises
    ------
    InputError
        ``volume`` is not a non-empty 3D real array.
    """
    vol = _check_volume(volume)
    return {view: view_slice(vol, view, vol.shape[axis] // 2) for view, axis in DEPTH_AXIS.items()}
