"""``evaluate``: every metric, per view, on a readable scale (floor and ceiling)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import InputError
from . import autocorr, fringes, orientation, patches, phases, references
from ._common import (DEFAULT_CONSTRAINED, PSEUDO_COUNT, VIEWS, as_image, as_volume, check_int,
                      check_views, jsonable, slice_indices, view_slices)
from .families import Family, Setup, make_families, make_setup
from .firstorder import first_order_stats

FORMAT_VERSION = 1
#: Most slices per ceiling repeat. The ceiling uses as many slices as the view (up to this),
#: so that its sampling noise matches the measured value's.
CEILING_SLICES = 16
#: Smallest exemplar side evaluate accepts (its halves must still hold some texture).
MIN_EXEMPLAR_SIDE = 16
MIN_VOLUME_SIDE = 8


def evaluate(exemplar: Any, volume: Any, *, views: Any = VIEWS, constrained: Any = DEFAULT_CONSTRAINED,
             levels: int | None = None, max_slices: int | None = 16, rng: Any = 0,
             reference_repeats: int = 5, periodic: bool = True,
             exclude: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Compare a volume's slices with the exemplar, view by view, with reference scales.

    Parameters
    ----------
    exemplar : array_like, 2D, or dict
        The exemplar (at least 16 x 16; treated as non-periodic); or one per view, a dict
        ``{view: exemplar}`` as :func:`clsolid.synthesize` takes them: each view is then
        compared with its own, and a view without one is left out. An RGB exemplar
        ``(H, W, 3)`` goes with an RGB volume: every distance is then measured on
        luminance, and each view adds the joint colour histogram's
        (:mod:`clsolid.metrics.colour`) and each channel's (``colour_channels``).
    volume : array_like, (Z, Y, X)
        The synthesised volume (every side at least 8); ``(Z, Y, X, 3)`` with an RGB exemplar.
    views : sequence of {"front", "right", "top"}
        Views to report (see :func:`view_slices` for their orientation).
    constrained : sequence of view names
        Views the synthesis constrained; only used to label the report.
    levels : int or None
        Quantise exemplar and volume into this many equal-width classes over the
        exemplar's range before the histogram statistics (and the few-phase analysis);
        None: use the grey levels as they are.
    max_slices : int or None
        Slices per view, evenly spaced (see :func:`view_slices`); None: all of them.
    rng : int, numpy.random.Generator or None
        Seeds the random halves, shuffles, noise and patch subsampling.
    reference_repeats : int
        Number of random halves and of shuffles/noise draws per reference (0 skips the
        references, then no distance is judged informative and no score is given).
    periodic : bool
        Whether the volume wraps around (the engine's volumes do); used by the
        orientation and fringe analyses at the slices' borders.
    exclude : mapping of view name to slice indices, optional
        Slices each view leaves out before choosing its ``max_slices``: a synthesis's
        ``+in`` (or anchor) slices, which start as exemplar copies and would flatter
        their view's scores (``clsolid evaluate`` reads them from the sidecar).

    Returns
    -------
    dict
        JSON-able report (Python types only; NaN never appears, undefined values are None):
        ``settings`` (every choice made, and the families skipped and why), ``exemplar``,
        ``volume``, ``views`` and ``summary`` (one row per view and distance); with an
        exemplar per view, ``exemplars`` too (each view's shape and statistics). Each view
        holds its ``constrained`` flag and ``label``, the slice indices used, first-order
        ``stats``, the curves behind each distance (histograms, autocorrelation maps,
        orientation histograms, fringe and phase statistics) and ``distances``; each
        distance has ``value``; ``floor``: mean, std, min, max, n of the distances between
        random halves of the exemplar rescaled to this comparison's sample sizes, with the
        raw halves values under ``halves``; ``ceiling``: the same between the exemplar and
        shuffled pixels or uniform noise (``kind``); ``informative``: whether the ceiling
        exceeds the floor by 3 combined standard deviations; ``score``:
        ``(value - floor) / (ceiling - floor)`` when informative, else None; ``note``.

    Notes
    -----
    Cost grows with the slices measured, most of it tracing fringes (timings:
    docs/benchmarks.md).
    """
    if isinstance(exemplar, Mapping):
        return _evaluate_per_view(exemplar, volume, views=views, constrained=constrained, levels=levels,
                                  max_slices=max_slices, rng=rng, reference_repeats=reference_repeats,
                                  periodic=periodic, exclude=exclude)
    if _rgb(exemplar) or _rgb(volume):
        return _evaluate_colour(exemplar, volume, views=views, constrained=constrained, levels=levels,
                                max_slices=max_slices, rng=rng, reference_repeats=reference_repeats,
                                periodic=periodic, exclude=exclude)
    ex = as_image(exemplar, "exemplar", min_side=MIN_EXEMPLAR_SIDE)
    vol = as_volume(volume, "volume", min_side=MIN_VOLUME_SIDE)
    views = check_views(views, "views")
    constrained = check_views(constrained, "constrained", allow_empty=True)
    levels = check_int(levels, "levels", 2, allow_none=True)
    max_slices = check_int(max_slices, "max_slices", 1, allow_none=True)
    repeats = check_int(reference_repeats, "reference_repeats", 0)
    if repeats == 1:
        raise InputError("reference_repeats=1 cannot measure a spread; use 0 (no references) or >= 2")
    excluded = _check_exclude(exclude)
    gen = np.random.default_rng(rng)
    stacks = {v: view_slices(vol, v, max_slices, excluded.get(v, ())).astype(np.float64) for v in views}
    setup = make_setup(ex, (float(vol.min()), float(vol.max())), [s.shape[1:] for s in stacks.values()],
                       periodic=bool(periodic), levels=levels, rng=gen)
    families, skipped = make_families(setup)
    ex_features = {f.name: f.features(ex[None], False) for f in families}
    floors = _floors(families, setup, gen, repeats)
    ceilings: dict[tuple, dict] = {}
    report_views = {}
    for view, stack in stacks.items():
        key = (stack.shape[1:], min(len(stack), CEILING_SLICES))
        if key not in ceilings:
            ceilings[key] = _ceilings(families, setup, ex_features, key, gen, repeats)
        report_views[view] = _view_report(view, vol.shape, stack, max_slices, excluded.get(view, ()),
                                          view in constrained, families, setup, ex_features, floors,
                                          ceilings[key])
    report = {
        "format": "clsolid-metrics", "version": FORMAT_VERSION,
        "settings": {**_settings(setup, views, constrained, max_slices, rng, repeats, skipped),
                     "excluded_slices": {v: sorted(int(i) for i in d) for v, d in excluded.items()}},
        "exemplar": {"shape": list(ex.shape), "stats": first_order_stats(setup.grey(ex))},
        "volume": {"shape": list(vol.shape), "dtype": str(vol.dtype)},
        "views": report_views,
        "summary": _summary(report_views),
    }
    return jsonable(report)


def _rgb(data: Any) -> bool:
    """Whether *data* is an RGB image or volume (a last axis of 3 after a 2D or 3D grid)."""
    shape = np.shape(data) if not isinstance(data, Mapping) else ()
    return len(shape) in (3, 4) and shape[-1] == 3 and (len(shape) == 4 or min(shape[:2]) > 3)


def _evaluate_colour(exemplar: Any, volume: Any, **kw: Any) -> dict[str, Any]:
    """:func:`evaluate` of an RGB volume against an RGB exemplar: every distance on
    luminance, and each view's colour distances (:func:`clsolid.metrics.colour.colour_distances`)."""
    from ..colour import luminance
    from .colour import KEY, colour_distances

    ex, vol = np.asarray(exemplar), np.asarray(volume)
    if not (ex.ndim == 3 and ex.shape[-1] == 3 and vol.ndim == 4 and vol.shape[-1] == 3):
        raise InputError(f"an RGB exemplar goes with an RGB volume, and a grey one with a grey one; got exemplar "
                         f"{ex.shape} and volume {vol.shape}")
    report = evaluate(luminance(ex), luminance(vol), **kw)
    stacks = {}
    for view, rep in report["views"].items():
        axis = {"front": 0, "right": 2, "top": 1}[view]
        stacks[view] = np.stack([view_slices(vol[..., c], view, None)[_positions(vol.shape[axis], rep)]
                                 for c in range(3)], axis=-1)
    repeats = int(report["settings"]["reference_repeats"])
    joint, channels = colour_distances(ex, stacks, np.random.default_rng(kw.get("rng")), repeats)
    for view, rep in report["views"].items():
        rep["distances"][KEY] = jsonable(joint[view])
        rep["colour_channels"] = jsonable(channels[view])
    report["summary"] = _summary(report["views"])
    report["settings"]["colour"] = {
        "structure": "every other distance on luminance, 0.2126 R + 0.7152 G + 0.0722 B",
        "joint_histogram": "each pixel as the nearest (CIELAB) of the exemplar's palette of at most 32 colours "
                           "(k-means in CIELAB); symmetric KL, nats; ceiling: uniform noise in the RGB cube",
        "channel_histograms": "32 bins over each channel's full range; symmetric KL, nats"}
    report["exemplar"]["channels"] = 3
    report["volume"] = {"shape": list(vol.shape), "dtype": str(vol.dtype)}
    return report


def _positions(n: int, rep: dict) -> np.ndarray:
    """The slice indices a view's report used, as positions along its axis of *n*."""
    idx = np.asarray(rep["slice_indices"], dtype=np.intp)
    return idx if idx.size else np.arange(n)


def _evaluate_per_view(exemplars: Mapping[str, Any], volume: Any, *, views: Any, **kw: Any) -> dict[str, Any]:
    """:func:`evaluate` with an exemplar per view: each view's report against its own
    exemplar (its own floor and ceiling), in one report whose ``exemplar`` is the first's and
    ``exemplars`` every view's (shape and statistics)."""
    views = check_views(views, "views")
    unknown = [v for v in exemplars if v not in VIEWS]
    if unknown:
        raise InputError(f"exemplars are given for {unknown!r}; views are {', '.join(VIEWS)}")
    measured = [v for v in views if v in exemplars]
    if not measured:
        raise InputError(f"views={list(views)!r}: none has an exemplar (given for {', '.join(exemplars)})")
    reports = {v: evaluate(exemplars[v], volume, views=(v,), **kw) for v in measured}
    first = reports[measured[0]]
    left_out = [v for v in views if v not in exemplars]
    return {**first,
            "settings": {**first["settings"], "views": measured,
                         "skipped": {**first["settings"]["skipped"],
                                     **({"views " + ", ".join(left_out): "no exemplar of their own"}
                                        if left_out else {})}},
            "exemplars": {v: r["exemplar"] for v, r in reports.items()},
            "views": {v: r["views"][v] for v, r in reports.items()},
            "summary": [row for r in reports.values() for row in r["summary"]]}


def _floors(families: list[Family], setup: Setup, gen: np.random.Generator,
            repeats: int) -> dict[str, list[tuple[float | None, int, int]]]:
    """Each distance between the two parts of ``repeats`` random halves, with their sizes."""
    out: dict[str, list] = {d.key: [] for f in families for d in f.distances}
    for a, b in references.exemplar_halves(setup.exemplar, gen, repeats):
        for fam in families:
            for k, v in fam.compare(fam.features(a[None], False), fam.features(b[None], False)).items():
                out[k].append((v, a.size, b.size))
    return out


def _ceilings(families: list[Family], setup: Setup, ex_features: dict, key: tuple,
              gen: np.random.Generator, repeats: int) -> dict[str, list[float | None]]:
    """Each distance between the exemplar and structureless slices of the views' shape."""
    shape, n = key
    out: dict[str, list[float | None]] = {d.key: [] for f in families for d in f.distances}
    lo, hi = setup.ex_range
    for _ in range(repeats):
        draws = {"shuffle": references.shuffled_stack(setup.exemplar, shape, n, gen),
                 "noise": references.noise_stack(lo, hi, setup.integer_valued, shape, n, gen)}
        for fam in families:
            kinds = {d.ceiling for d in fam.distances}
            got = {kind: fam.compare(ex_features[fam.name], fam.features(draws[kind], setup.periodic))
                   for kind in kinds}
            for d in fam.distances:
                out[d.key].append(got[d.ceiling][d.key])
    return out


def _check_exclude(exclude: Mapping[str, Any] | None) -> dict[str, Any]:
    """*exclude* as a dict of view name to indices (checked against the volume in view_slices)."""
    if exclude is None:
        return {}
    if not isinstance(exclude, Mapping):
        raise InputError(f"exclude must map view names to slice indices, got {type(exclude).__name__}")
    unknown = [v for v in exclude if v not in VIEWS]
    if unknown:
        raise InputError(f"exclude names unknown views {unknown}; views are {', '.join(VIEWS)}")
    return {v: np.asarray(d, dtype=np.intp).ravel() for v, d in exclude.items()}


def _view_report(view: str, shape: tuple, stack: np.ndarray, max_slices: int | None, exclude: Any,
                 is_constrained: bool, families: list[Family], setup: Setup, ex_features: dict,
                 floors: dict, ceilings: dict) -> dict:
    """Everything measured on one view's slices, each distance with its floor and ceiling."""
    axis = {"front": 0, "right": 2, "top": 1}[view]
    out: dict[str, Any] = {
        "constrained": is_constrained,
        "label": f"{view} ({'constrained' if is_constrained else 'unconstrained'})",
        "slice_axis": "zyx"[axis],
        "slice_indices": slice_indices(shape[axis], max_slices, exclude),
        "slice_shape": list(stack.shape[1:]),
        "stats": first_order_stats(setup.grey(stack)),
        "distances": {},
    }
    for fam in families:
        fb = fam.features(stack, setup.periodic)
        values = fam.compare(ex_features[fam.name], fb)
        for d in fam.distances:
            floor = references.floor_reference(floors[d.key], setup.exemplar.size, stack.size, d.power)
            ceiling = references.spread(ceilings[d.key])
            out["distances"][d.key] = {
                "label": d.label, "units": d.units, "value": values[d.key],
                "floor": floor, "ceiling": None if ceiling is None else {**ceiling, "kind": d.ceiling},
                **references.readable(values[d.key], floor, ceiling),
            }
        out[fam.name] = fam.details(ex_features[fam.name], fb, view)
    return out


def _summary(report_views: dict) -> list[dict]:
    rows = []
    for view, rep in report_views.items():
        for key, d in rep["distances"].items():
            rows.append({"view": view, "constrained": rep["constrained"], "metric": key, "units": d["units"],
                         "value": d["value"],
                         "floor": None if d["floor"] is None else d["floor"]["mean"],
                         "floor_std": None if d["floor"] is None else d["floor"]["std"],
                         "ceiling": None if d["ceiling"] is None else d["ceiling"]["mean"],
                         "ceiling_std": None if d["ceiling"] is None else d["ceiling"]["std"],
                         "informative": d["informative"], "score": d["score"]})
    return rows


def _settings(setup: Setup, views: tuple, constrained: tuple, max_slices: int | None, rng: Any,
              repeats: int, skipped: dict) -> dict:
    """Every choice the numbers depend on, so that a report explains itself."""
    return {
        "views": list(views), "constrained": list(constrained), "levels": setup.levels,
        "max_slices": max_slices, "seed": rng if isinstance(rng, (int, np.integer)) else None,
        "reference_repeats": repeats, "periodic_volume": setup.periodic, "skipped": skipped,
        "statistics": "population moments (ddof=0); mad = mean absolute deviation about the mean; "
                      "skewness = m3/m2^1.5; kurtosis = excess kurtosis m4/m2^2 - 3",
        "histogram": {"bins": len(setup.hist_edges) - 1, "range": [setup.hist_edges[0], setup.hist_edges[-1]],
                      "pseudo_count": PSEUDO_COUNT,
                      "divergence": "sum (P-Q) ln(P/Q) = KL(P||Q) + KL(Q||P), nats"},
        "autocorrelation": {"lags": setup.max_lag,
                            "clip": f"{autocorr.DEFAULT_LAGS}, clipped to half the side of the smallest "
                                    "exemplar part used by the floor and to half the slices' side",
                            "distance": "RMS difference over lags of the exemplar's map and the mean "
                                        "of the slices' maps"},
        "orientation": {"gradient": "Sobel", "window": "Gaussian sigma 1, 7x7",
                        "bins": orientation.ORIENTATION_BINS, "weights": "coherence",
                        "pseudo_count": PSEUDO_COUNT, "border_dropped": orientation.BORDER},
        "fringes": {"level": setup.fringe_level, "smoothing_sigma": fringes.SMOOTH_SIGMA,
                    "min_tip_distance": fringes.MIN_EXTENT, "max_extent": setup.fringe_cap,
                    "edge_correction": "Miles-Lantuejoul weights (non-periodic); periodic slices wrap",
                    "distance": "Wasserstein-1 between weighted number distributions"},
        "patches": {"size": patches.PATCH_SIZE, "scales": list(setup.patch_scales),
                    "projections": patches.N_PROJECTIONS, "quantiles": patches.N_QUANTILES,
                    "max_patches": patches.MAX_PATCHES, "standardised_by": "exemplar mean and std"},
        "phases": {"values": setup.phase_values, "max_phases": phases.MAX_PHASES,
                   "max_lag": setup.max_lag},
        "references": {"floor": "distance between two random near-halves of the exemplar (cut at 40-60%), "
                                "times (1/N_exemplar + 1/N_slices)^p / (1/N_half1 + 1/N_half2)^p with p = 1 "
                                "for KL divergences and 1/2 for the other distances (raw values in "
                                "floor.halves)",
                       "ceiling_shuffle": f"exemplar vs {CEILING_SLICES} slices of its shuffled pixels",
                       "ceiling_noise": "exemplar vs uniform noise over its range (distances shuffling "
                                        "cannot change)",
                       "informative": f"ceiling mean - floor mean > {references.SEPARATION} x "
                                      "sqrt(floor std^2 + ceiling std^2)",
                       "score": "(value - floor mean) / (ceiling mean - floor mean)"},
    }
