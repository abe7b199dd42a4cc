"""The metric families evaluated per view: features of a stack of slices, distances between them.

Each family turns a stack of slices into features once, so the exemplar's features are
reused for the measured value, the floor and the ceiling. Everything a family must hold
fixed between the exemplar and the slices (histogram edges, fringe level, phases, the
standardisation of patches) lives in :class:`Setup`, derived from the exemplar.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from . import autocorr, fringes, orientation, patches, phases, references
from .firstorder import MAX_DEFAULT_BINS, histogram_counts, histogram_edges, histogram_kl, quantise


class Distance(NamedTuple):
    """A distance a family reports.

    ``ceiling`` is the structureless reference that scales it ("shuffle" or "noise").
    ``power`` is how its sampling noise scales with the numbers of pixels compared,
    ``(1/N_a + 1/N_b) ** power``: 1 for divergences (KL behaves like a chi-square), 1/2 for
    distances (RMS differences, Wasserstein, total variation).
    """

    key: str
    label: str
    units: str
    ceiling: str
    power: float = 0.5


@dataclass(frozen=True)
class Setup:
    """What is fixed by the exemplar for every comparison."""

    exemplar: np.ndarray
    periodic: bool
    levels: int | None
    ex_range: tuple[float, float]
    integer_valued: bool
    hist_edges: np.ndarray
    fringe_level: float
    fringe_cap: float
    max_lag: int
    phase_values: np.ndarray | None
    patch_scales: tuple[int, ...]
    rng: np.random.Generator

    def grey(self, stack: np.ndarray) -> np.ndarray:
        """Grey levels as histogram statistics see them (quantised when ``levels`` is set)."""
        if self.levels is None:
            return stack
        return quantise(stack, self.levels, *self.ex_range)


class Family:
    """Base class: subclasses define ``name``, ``distances`` and the three methods."""

    name = ""
    distances: tuple[Distance, ...] = ()

    def __init__(self, setup: Setup):
        self.setup = setup

    def features(self, stack: np.ndarray, periodic: bool) -> Any:
        """Features of an ``(n, rows, cols)`` stack."""
        raise NotImplementedError

    def compare(self, fa: Any, fb: Any) -> dict[str, float | None]:
        """Distances between exemplar-side features ``fa`` and slice-side features ``fb``."""
        raise NotImplementedError

    def details(self, fa: Any, fb: Any, view: str) -> dict[str, Any]:
        """JSON-able curves and summaries for the report and its plot."""
        raise NotImplementedError


class HistogramFamily(Family):
    """Grey-level histograms (quantised when ``levels`` is set); symmetric KL."""

    name = "histogram"
    distances = (Distance("histogram_kl", "grey-level histogram, symmetric KL", "nats", "noise", 1.0),)

    def features(self, stack, periodic):
        return histogram_counts(self.setup.grey(stack), self.setup.hist_edges)

    def compare(self, fa, fb):
        return {"histogram_kl": histogram_kl(fa, fb)}

    def details(self, fa, fb, view):
        edges = self.setup.hist_edges
        return {"bin_edges": edges, "bin_centres": 0.5 * (edges[1:] + edges[:-1]),
                "exemplar": fa / fa.sum(), "volume": fb / fb.sum(),
                "quantised_levels": self.setup.levels}


class AutocorrelationFamily(Family):
    """Mean normalised autocorrelation maps; RMS difference over the shared lag window."""

    name = "autocorrelation"
    distances = (Distance("autocorrelation_l2", "autocorrelation, RMS difference over lags",
                          "correlation", "shuffle"),)

    def features(self, stack, periodic):
        return autocorr.autocorrelation_stack(stack, self.setup.max_lag)

    def compare(self, fa, fb):
        return {"autocorrelation_l2": autocorr.map_distance(fa, fb)}

    def details(self, fa, fb, view):
        ly, lx = min(fa.shape[0], fb.shape[0]) // 2, min(fa.shape[1], fb.shape[1]) // 2
        return {"lags": [ly, lx], "exemplar": np.round(autocorr.crop_map(fa, ly, lx), 5),
                "volume": np.round(autocorr.crop_map(fb, ly, lx), 5)}


class OrientationFamily(Family):
    """Coherence-weighted structure-tensor orientation histograms; symmetric KL."""

    name = "orientation"
    distances = (Distance("orientation_kl", "coherence-weighted orientation histogram, symmetric KL",
                          "nats", "shuffle", 1.0),)

    def features(self, stack, periodic):
        field = orientation.structure_tensor_orientation(stack, periodic=periodic)
        return (orientation.orientation_histogram(field), float(field.coherence.mean()),
                orientation.dominant_orientation_deg(field))

    def compare(self, fa, fb):
        return {"orientation_kl": orientation.orientation_kl(fa[0], fb[0])}

    def details(self, fa, fb, view):
        def side(f):
            dom = f[2]
            return {"histogram": f[0] / max(f[0].sum(), 1e-300), "mean_coherence": f[1],
                    "dominant_gradient_deg": dom,
                    "dominant_fringe_deg": None if dom is None else (dom + 180.0) % 180.0 - 90.0}
        return {"bin_centres_deg": orientation.bin_centres_deg(), "exemplar": side(fa), "volume": side(fb),
                "convention": "degrees, angle of the dominant gradient counter-clockwise from the "
                              "column (x) axis as displayed (row 0 at the top); fringes run at +90"}


class FringeFamily(Family):
    """Level-curve fringes at the exemplar mean: length and straightness distributions."""

    name = "fringes"
    distances = (Distance("fringe_length_w1", "fringe length distribution, Wasserstein-1", "pixels",
                          "shuffle"),
                 Distance("fringe_straightness_w1",
                          "fringe tortuosity: Wasserstein-1 of straightness = 1/tortuosity", "ratio",
                          "shuffle"))

    def features(self, stack, periodic):
        return fringes.trace_stack(stack, level=self.setup.fringe_level, periodic=periodic,
                                   max_extent=self.setup.fringe_cap)

    def compare(self, fa, fb):
        return fringes.fringe_distances(fa, fb)

    def details(self, fa, fb, view):
        cap = self.setup.fringe_cap
        length_edges = np.linspace(0.0, 2.0 * cap, 25)  # centre lines of curved fringes exceed the cap
        tort_edges = np.linspace(1.0, 2.0, 21)

        def hist(values, weights, edges):
            if len(values) == 0:
                return None
            h = np.histogram(np.clip(values, edges[0], edges[-1]), edges, weights=weights)[0]
            return h / h.sum()

        return {"level": self.setup.fringe_level, "max_extent": cap,
                "length_edges": length_edges, "tortuosity_edges": tort_edges,
                "exemplar": {**fringes.fringe_summary(fa),
                             "length_hist": hist(fa.lengths, fa.weights, length_edges),
                             "tortuosity_hist": hist(fa.tortuosities, fa.weights, tort_edges)},
                "volume": {**fringes.fringe_summary(fb),
                           "length_hist": hist(fb.lengths, fb.weights, length_edges),
                           "tortuosity_hist": hist(fb.tortuosities, fb.weights, tort_edges)}}


class PatchFamily(Family):
    """Multi-scale 5x5 patch distributions; sliced Wasserstein-2."""

    name = "patches"
    distances = (Distance("patch_sw", "k x k patch distribution, sliced Wasserstein-2",
                          "exemplar std", "shuffle"),)

    def features(self, stack, periodic):
        s = self.setup
        return patches.patch_quantiles(stack, s.patch_scales, s.rng, float(s.exemplar.mean()),
                                       float(s.exemplar.std()))

    def compare(self, fa, fb):
        return {"patch_sw": float(np.mean(patches.quantile_distances(fa, fb)))}

    def details(self, fa, fb, view):
        return {"patch_size": patches.PATCH_SIZE, "scales": list(self.setup.patch_scales),
                "per_scale": patches.quantile_distances(fa, fb),
                "projections": patches.N_PROJECTIONS, "quantiles": patches.N_QUANTILES}


#: Rows and columns of each view's slices, as volume axes.
VIEW_AXES = {"front": ("y", "x"), "right": ("y", "z"), "top": ("z", "x")}


class PhaseFamily(Family):
    """Few-phase descriptors: volume fractions, S2, the cluster function C2, lineal path and chord lengths."""

    name = "phases"
    distances = (
        Distance("volume_fraction_tv", "volume fractions, total variation", "fraction", "noise"),
        Distance("s2_l2", "two-point correlation S2, RMS difference", "probability", "shuffle"),
        Distance("c2_l2", "connectedness C2(r)/C2(0), RMS difference", "probability", "shuffle"),
        Distance("lineal_path_l2", "lineal path, RMS difference", "probability", "shuffle"),
        Distance("chord_length_w1", "chord-length distributions, mean Wasserstein-1", "pixels", "shuffle"),
    )

    def features(self, stack, periodic):
        labels = phases.to_labels(self.setup.grey(stack), self.setup.phase_values)
        n = len(self.setup.phase_values)
        feats = {"fractions": phases.volume_fractions(labels, n), "s2": {}, "c2": {}, "lineal": {}, "chords": {}}
        for axis in (0, 1):
            lag = self.setup.max_lag
            for p in range(n):
                feats["s2"][p, axis] = phases.two_point_correlation(labels, p, axis, lag)
                c2 = phases.two_point_cluster(labels, p, axis, lag)
                # Conditional on the first point (C2(0) is the fraction): a fraction that differs
                # between the exemplar's halves would otherwise hide whether the phase is connected.
                feats["c2"][p, axis] = c2 / c2[0] if c2[0] > 0 else c2
                feats["lineal"][p, axis] = phases.lineal_path(labels, p, axis, lag)
                feats["chords"][p, axis] = phases.chord_lengths(labels, p, axis)
        return feats

    def compare(self, fa, fb):
        tv = 0.5 * float(np.abs(fa["fractions"] - fb["fractions"]).sum())
        return {"volume_fraction_tv": tv, "s2_l2": _curves_rms(fa["s2"], fb["s2"]),
                "c2_l2": _curves_rms(fa["c2"], fb["c2"]),
                "lineal_path_l2": _curves_rms(fa["lineal"], fb["lineal"]),
                "chord_length_w1": _chords_w1(fa["chords"], fb["chords"])}

    def details(self, fa, fb, view):
        names = VIEW_AXES[view]
        out: dict[str, Any] = {"phase_values": self.setup.phase_values,
                               "fractions": {"exemplar": fa["fractions"], "volume": fb["fractions"]},
                               "axes": {"0": f"along rows (volume axis {names[0]})",
                                        "1": f"along columns (volume axis {names[1]})"},
                               "curves": []}
        for (p, axis), s2a in fa["s2"].items():
            ca, cb = fa["chords"][p, axis], fb["chords"][p, axis]
            out["curves"].append({
                "phase": p, "axis": axis, "volume_axis": names[axis],
                "s2": {"exemplar": s2a, "volume": fb["s2"][p, axis]},
                "c2": {"exemplar": fa["c2"][p, axis], "volume": fb["c2"][p, axis]},
                "lineal_path": {"exemplar": fa["lineal"][p, axis], "volume": fb["lineal"][p, axis]},
                "mean_chord": {"exemplar": _weighted_mean(*ca), "volume": _weighted_mean(*cb)},
            })
        return out


def _curves_rms(a: dict, b: dict) -> float:
    """RMS difference over phases, axes and the lags both curves have."""
    sq = []
    for key, ca in a.items():
        cb = b[key]
        m = min(len(ca), len(cb))
        sq.append((ca[:m] - cb[:m]) ** 2)
    return float(np.sqrt(np.mean(np.concatenate(sq))))


def _chords_w1(a: dict, b: dict) -> float | None:
    """Mean over phases and axes of the chord-length Wasserstein-1 distance (defined pairs only)."""
    from ._common import wasserstein_1d

    d = [wasserstein_1d(a[k][0], b[k][0], a[k][1], b[k][1]) for k in a if len(a[k][0]) and len(b[k][0])]
    return float(np.mean(d)) if d else None


def _weighted_mean(values: np.ndarray, weights: np.ndarray) -> float | None:
    return float(np.average(values, weights=weights)) if len(values) else None


def make_setup(exemplar: np.ndarray, volume_range: tuple[float, float], slice_shapes: list[tuple[int, int]],
               *, periodic: bool, levels: int | None, rng: np.random.Generator) -> Setup:
    """Fix, from the exemplar, everything the comparisons share."""
    lo, hi = float(exemplar.min()), float(exemplar.max())
    integer = bool(np.all(exemplar == np.round(exemplar)))
    if levels is None:
        both = np.array([min(lo, volume_range[0]), max(hi, volume_range[1])])
        # Integer exemplars keep integer-aligned bins unless the volume has fractions.
        edges = histogram_edges(np.round(both)) if integer else histogram_edges(both, MAX_DEFAULT_BINS)
        grey_ex = exemplar
    else:
        edges = np.arange(levels + 1) - 0.5
        grey_ex = quantise(exemplar, levels, lo, hi)
    smallest = min(min(exemplar.shape) // 4, min(min(s) for s in slice_shapes) // 2)
    # The floor compares parts cut at 40-60 % of a side: value, floor and ceiling must all
    # cover the same lags, so the lag window is what the smallest part allows.
    half = int(min(exemplar.shape) * references.CUT_RANGE[0])
    max_lag = min(autocorr.DEFAULT_LAGS, half // 2, min(min(s) for s in slice_shapes) // 2)
    scales = tuple(s for s in patches.usable_scales((half, half))
                   if all(s in patches.usable_scales(shape) for shape in slice_shapes))
    return Setup(exemplar=exemplar, periodic=periodic, levels=levels, ex_range=(lo, hi),
                 integer_valued=integer, hist_edges=edges, fringe_level=float(exemplar.mean()),
                 fringe_cap=float(smallest), max_lag=max_lag,
                 phase_values=phases.phase_values(grey_ex), patch_scales=scales, rng=rng)


def make_families(setup: Setup) -> tuple[list[Family], dict[str, str]]:
    """The families that apply to this exemplar, and the reason each other one is skipped."""
    side = min(setup.exemplar.shape)
    out: list[Family] = [HistogramFamily(setup), AutocorrelationFamily(setup)]
    skipped = {}
    if side >= 40:
        out.append(OrientationFamily(setup))
    else:
        skipped["orientation"] = ("exemplar smaller than 40 pixels: its halves leave too few pixels "
                                  "away from the borders of the 7x7 windows")
    if setup.fringe_cap >= 2 * fringes.MIN_EXTENT:
        out.append(FringeFamily(setup))
    else:
        skipped["fringes"] = "exemplar or slices too small to hold whole fringes"
    if setup.patch_scales:
        out.append(PatchFamily(setup))
    else:
        skipped["patches"] = "exemplar halves too small for 5x5 patches"
    if setup.phase_values is not None:
        out.append(PhaseFamily(setup))
    else:
        n_levels = len(np.unique(setup.grey(setup.exemplar)))
        skipped["phases"] = (f"the exemplar has {n_levels} grey level(s); the few-phase analysis needs 2 to "
                             f"{phases.MAX_PHASES} (pass levels=2..{phases.MAX_PHASES} to quantise it)")
    return out, skipped
