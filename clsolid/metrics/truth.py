"""A generated volume's 3D properties against a real volume's: the field's validation.

One slice of a real 3D volume goes to a generator; the volumes it grows are compared with
the real one on properties that no slice shows, along every axis, the unconstrained ones
included (SliceGAN, Kench & Cooper, *Nature Machine Intelligence* 3, 2021, section
"Results"): per phase, the volume fraction, the specific surface area, S2 along each axis,
the connected fraction and the tortuosity factor along each axis. The real volume's own
spread (its sub-volumes of the generated size) says how far apart two honest samples of
the material lie: its *band* (docs/design.md#validation-band).
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from ..errors import InputError
from ._common import as_volume, check_int
from .solid import connected_fraction, specific_surface_area, tortuosity_factor, two_point_correlation_axes

#: Per-axis properties (one value per axis z, y, x) and whole-block ones.
AXIS_PROPERTIES = ("connected", "tortuosity")
SCALAR_PROPERTIES = ("fraction", "surface_area")

#: The targets a generated volume is held to, per phase (generated mean against the real
#: volume): fraction within 1 point; S2 within 5 % of the phase's fraction at every lag of
#: every axis, or inside the real band where the band is wider; surface area within 5 %;
#: tortuosity factor within 10 % on every axis, for phases over 25 % of the volume.
TARGETS = {"fraction": 0.01, "s2": 0.05, "surface_area": 0.05, "tortuosity": 0.10}
TORTUOSITY_MIN_FRACTION = 0.25


def solid_properties(labels: Any, *, phases: Any = None, max_lag: int | None = None,
                     tortuosity: bool | Sequence[Any] = True) -> dict[str, dict[str, Any]]:
    """Every 3D property of each phase of a label volume.

    Parameters
    ----------
    labels : array_like, (Z, Y, X)
        A segmented volume.
    phases : sequence or None
        The phase values to measure; None: those present in ``labels``.
    max_lag : int or None
        The longest S2 lag (see :func:`~clsolid.metrics.two_point_correlation_axes`); None:
        half the shortest side.
    tortuosity : bool or sequence
        The phases whose tortuosity factor (the costliest property) is solved for: True,
        those over :data:`TORTUOSITY_MIN_FRACTION` of the volume; False, none; or their
        values. The others get None.

    Returns
    -------
    dict
        By phase value (as a string): ``fraction`` and ``surface_area`` (floats), ``s2``
        (three curves, z, y, x), ``connected`` and ``tortuosity`` (three values each, z, y,
        x; a tortuosity of ``inf`` where nothing spans the block, None where not solved).
    """
    vol = as_volume(labels, "labels")
    values = np.unique(vol) if phases is None else np.asarray(phases, dtype=np.float64).ravel()
    max_lag = min(vol.shape) // 2 if max_lag is None else check_int(max_lag, "max_lag", 1)
    out = {}
    for phase in values:
        fraction = float(np.mean(vol == phase))
        if isinstance(tortuosity, bool):
            solve = tortuosity and fraction > TORTUOSITY_MIN_FRACTION
        else:
            solve = any(float(phase) == float(t) for t in tortuosity)
        out[_key(phase)] = {
            "fraction": fraction,
            "surface_area": specific_surface_area(vol, phase),
            "s2": list(two_point_correlation_axes(vol, phase, max_lag=max_lag)),
            "connected": list(connected_fraction(vol, phase)),
            "tortuosity": [tortuosity_factor(vol, phase, a) for a in range(3)] if solve else None,
        }
    return out


def _key(phase: Any) -> str:
    """A phase value as a report key: ``'1'`` for 1.0, as a JSON object needs."""
    value = float(phase)
    return str(int(value)) if value.is_integer() else repr(value)


def subvolume_corners(shape: tuple[int, ...], size: tuple[int, ...]) -> list[tuple[int, int, int]]:
    """Corners of the sub-volumes of ``size`` that tile a block of ``shape``, spread evenly
    where ``size`` does not divide it (as many as fit without overlap, per axis)."""
    if len(size) != 3 or any(s < 2 or s > n for s, n in zip(size, shape)):
        raise InputError(f"a sub-volume of shape {tuple(size)} does not fit a block of shape {tuple(shape)}: each "
                         "side must be 2 to the block's")
    starts = [np.linspace(0, n - s, n // s).round().astype(int) if n // s > 1 else np.array([(n - s) // 2])
              for n, s in zip(shape, size)]
    return [(int(z), int(y), int(x)) for z in starts[0] for y in starts[1] for x in starts[2]]


def property_band(labels: Any, size: tuple[int, int, int], *, phases: Any = None, max_lag: int | None = None,
                  tortuosity: bool | Sequence[Any] = True) -> tuple[dict, int]:
    """The spread of each property over a real volume's sub-volumes of ``size``.

    Parameters
    ----------
    labels : array_like, (Z, Y, X)
        The real segmented volume.
    size : tuple of 3 ints
        The sub-volumes' shape: that of the generated volumes.
    phases, max_lag, tortuosity
        As :func:`solid_properties`.

    Returns
    -------
    band : dict
        By phase and property, the ``[low, high]`` over the sub-volumes (elementwise for
        curves and per-axis values).
    count : int
        The number of sub-volumes.
    """
    vol = as_volume(labels, "labels")
    corners = subvolume_corners(vol.shape, tuple(size))
    samples = [solid_properties(vol[z:z + size[0], y:y + size[1], x:x + size[2]], phases=phases if phases is not None
                                else np.unique(vol), max_lag=max_lag, tortuosity=tortuosity)
               for z, y, x in corners]
    band: dict[str, dict[str, Any]] = {}
    for key in samples[0]:
        band[key] = {}
        for prop in samples[0][key]:
            values = [s[key][prop] for s in samples]
            if any(v is None for v in values):
                band[key][prop] = None
                continue
            if prop == "s2":
                band[key][prop] = [[np.min([v[a] for v in values], axis=0), np.max([v[a] for v in values], axis=0)]
                                   for a in range(3)]
            else:
                stack = np.array(values, dtype=np.float64)
                band[key][prop] = [np.min(stack, axis=0), np.max(stack, axis=0)]
    return band, len(corners)


def mean_properties(samples: list[dict]) -> dict:
    """The mean of each property over generated volumes (S2 curve by curve; None stays None)."""
    if not samples:
        raise InputError("no generated volumes to average")
    mean: dict[str, dict[str, Any]] = {}
    for key in samples[0]:
        mean[key] = {}
        for prop in samples[0][key]:
            values = [s.get(key, {}).get(prop) for s in samples]
            if any(v is None for v in values):
                mean[key][prop] = None
            elif prop == "s2":
                mean[key][prop] = [np.mean([v[a] for v in values], axis=0) for a in range(3)]
            else:
                mean[key][prop] = np.mean(np.array(values, dtype=np.float64), axis=0)
    return mean


def _relative(generated: float, real: float) -> float:
    if math.isinf(real) or math.isinf(generated):
        return 0.0 if generated == real else math.inf
    return abs(generated - real) / real if real else math.inf


def _inside(value: Any, band: Any) -> bool:
    if band is None:
        return False
    low, high = (np.asarray(b, dtype=np.float64) for b in band)
    return bool(np.all((low <= value) & (value <= high)))


def compare_properties(real: dict, band: dict, generated: dict) -> dict:
    """Each phase's generated mean against the real volume, with the targets' verdicts.

    Parameters
    ----------
    real : dict
        :func:`solid_properties` of the real volume.
    band : dict
        :func:`property_band` of the real volume.
    generated : dict
        :func:`mean_properties` of the generated volumes.

    Returns
    -------
    dict
        By phase and property: ``real``, ``band``, ``generated``, ``error`` (fraction:
        absolute; S2: per axis, the largest gap in percent of the phase's fraction; surface
        area and tortuosity: relative, per axis for the latter), ``in_band`` and ``met``
        (the target of :data:`TARGETS`; None where a property has no target for that
        phase).
    """
    out: dict[str, dict[str, Any]] = {}
    for key, props in real.items():
        g, b = generated.get(key), band.get(key)
        if g is None or b is None:
            raise InputError(f"phase {key} of the real volume is missing from the generated volumes' properties")
        f = props["fraction"]
        rows: dict[str, Any] = {}
        err = abs(g["fraction"] - f)
        rows["fraction"] = dict(real=f, band=b["fraction"], generated=g["fraction"], error=err,
                                in_band=_inside(g["fraction"], b["fraction"]), met=err <= TARGETS["fraction"])
        err = _relative(g["surface_area"], props["surface_area"])
        rows["surface_area"] = dict(real=props["surface_area"], band=b["surface_area"], generated=g["surface_area"],
                                    error=err, in_band=_inside(g["surface_area"], b["surface_area"]),
                                    met=err <= TARGETS["surface_area"])
        s2_err, s2_met, s2_in = [], [], []
        for a in range(3):
            r, gen = np.asarray(props["s2"][a]), np.asarray(g["s2"][a])
            n = min(r.size, gen.size)
            gap = np.abs(gen[:n] - r[:n])
            low, high = (np.asarray(x)[:n] for x in b["s2"][a])
            inside = (low <= gen[:n]) & (gen[:n] <= high)
            s2_err.append(100.0 * float(gap.max()) / f if f else math.inf)
            s2_met.append(bool(np.all((gap <= TARGETS["s2"] * f) | inside)))
            s2_in.append(bool(np.all(inside)))
        rows["s2"] = dict(real=props["s2"], band=b["s2"], generated=g["s2"], error=s2_err, in_band=s2_in, met=s2_met)
        rows["connected"] = dict(real=props["connected"], band=b["connected"], generated=g["connected"],
                                 error=[abs(x - y) for x, y in zip(g["connected"], props["connected"])],
                                 in_band=[_inside(x, [lo, hi]) for x, lo, hi in zip(g["connected"], *b["connected"])],
                                 met=None)
        if props["tortuosity"] is not None and g["tortuosity"] is not None:
            err = [_relative(x, y) for x, y in zip(g["tortuosity"], props["tortuosity"])]
            in_band = ([_inside(x, [lo, hi]) for x, lo, hi in zip(g["tortuosity"], *b["tortuosity"])]
                       if b["tortuosity"] is not None else [False] * 3)
            rows["tortuosity"] = dict(real=props["tortuosity"], band=b["tortuosity"], generated=g["tortuosity"],
                                      error=err, in_band=in_band, met=[e <= TARGETS["tortuosity"] for e in err])
        out[key] = rows
    return out


__all__ = ["solid_properties", "property_band", "mean_properties", "compare_properties", "subvolume_corners",
           "TARGETS", "TORTUOSITY_MIN_FRACTION"]
