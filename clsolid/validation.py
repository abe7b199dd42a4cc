"""Validation against a real 3D volume: hand a generator one section, grow volumes, and
compare their 3D properties with the real volume's along every axis.

This is how the field holds 2D-to-3D generators to account (SliceGAN, Kench & Cooper,
*Nature Machine Intelligence* 3, 2021): the section constrains some views, and the
properties along the axes it never saw tell whether the volume is the same material. The
properties and targets are :mod:`clsolid.metrics.truth`'s.
"""

from __future__ import annotations

import logging
from typing import Any, Callable

import numpy as np

from .api import synthesize
from .colour import float_top, lab, nearest, palette
from .core.views import DEPTH_AXIS
from .errors import InputError
from .groundtruth import sections as cut_sections
from .metrics import truth
from .metrics import correlation_lengths, two_point_correlation_axes
from .metrics._common import as_volume, check_int, jsonable
from .phases import is_categorical
from .preview import view_slice
from .report import _require_matplotlib

log = logging.getLogger(__name__)

AXES = ("z", "y", "x")


def segment(real: np.ndarray, classes: int) -> tuple[np.ndarray, list[float] | None]:
    """The real volume's labels, and the grey thresholds that made them (None when it is
    already segmented): multi-Otsu thresholds of the real volume, so that generated grey
    volumes are cut at the same levels."""
    if is_categorical(len(np.unique(real))):
        return real, None
    from skimage.filters import threshold_multiotsu

    thresholds = [float(t) for t in threshold_multiotsu(real, classes=classes)]
    return np.digitize(real, thresholds).astype(np.uint8), thresholds


class ColourCut:
    """How a colour volume ``(Z, Y, X, 3)`` becomes phases: *classes* colours of the real
    volume (its own colours when it has at most that many, else k-means in CIELAB,
    :func:`clsolid.colour.palette`), each voxel of the real volume and of every generated
    one the phase of the nearest of them in CIELAB."""

    def __init__(self, real: np.ndarray, classes: int) -> None:
        self.dtype, self.top = real.dtype, float_top(real)
        self.colours = palette(real, classes)[1]
        self._lab = lab(self.colours, self.dtype, self.top)

    def __call__(self, volume: np.ndarray) -> np.ndarray:
        points = lab(np.asarray(volume).reshape(-1, 3), self.dtype, self.top)
        return nearest(points, self._lab).reshape(np.shape(volume)[:-1]).astype(np.uint8)


#: What :func:`validate` hands the generator: the central front section, or every view's.
SECTIONS = ("front", "all")


def validate(real: Any, *, method: str = "ml", n: int = 3, shape: tuple[int, int, int] | None = None,
             seed: int = 0, device: Any = None, params: Any = None, classes: int = 2, tortuosity: bool = True,
             sections: str = "front", progress: Callable[[str], None] | None = None, **options: Any
             ) -> dict[str, Any]:
    """Grow ``n`` volumes from a real volume's central section (or sections) and compare them with it.

    Parameters
    ----------
    real : array_like, (Z, Y, X) or (Z, Y, X, 3)
        The real volume, segmented (at most 8 phase values), grey, or RGB (the generator
        then grows colour; the properties are those of the phases :class:`ColourCut` makes).
    method : str
        The generator (:func:`clsolid.synthesize`'s ``method``).
    n : int
        Volumes to grow, with seeds ``seed`` to ``seed + n - 1``.
    shape : tuple of 3 ints or None
        Their shape; None: half the real volume's on each axis, so that the real volume
        holds eight sub-volumes of that shape for its band.
    seed : int
        The first volume's seed.
    device, params, **options
        Passed to :func:`clsolid.synthesize`.
    classes : int
        For a grey real volume, the phases to cut it into (multi-Otsu thresholds, applied to
        the generated volumes too); for an RGB one, the colours it is cut by (:class:`ColourCut`).
    tortuosity : bool
        Solve for tortuosity factors (phases over a quarter of the volume).
    sections : {"front", "all"}
        ``"front"``: the central front section, for every view; ``"all"``: the three central
        sections, each its view's own exemplar (:func:`clsolid.groundtruth.sections`; an
        anisotropic material's).
    progress : callable or None
        Called with a line of text as each step starts.

    Returns
    -------
    dict
        JSON-ready: ``real`` (shape, section, thresholds, colours), ``generated`` (method, shape,
        seeds), ``band_count`` (the real volume's sub-volumes), ``phases`` (by phase and
        property: real, band, generated mean, error, in_band, met; see
        :func:`clsolid.metrics.truth.compare_properties`), ``section`` (by phase, the
        section's own fraction and S2 along its rows and columns, y and x: what the
        generator saw), ``volumes`` (each generated volume's own properties),
        ``correlation_length`` (along z, y and x: the real volume's, the generated volumes'
        mean and its relative error; :func:`clsolid.metrics.correlation_lengths`) and ``targets``.
    """
    arr = np.asarray(real)
    colour = arr.ndim == 4 and arr.shape[-1] == 3  # an RGB volume: cut into phases by colour
    as_volume(arr[..., 0] if colour else arr, "real volume", min_side=4)
    vol = arr
    n = check_int(n, "n", 1)
    classes = check_int(classes, "classes", 2)
    if shape is None:
        shape = tuple(max(2, s // 2) for s in vol.shape[:3])
    if len(tuple(shape)) != 3:
        raise InputError(f"shape={shape!r} must be three sides (Z, Y, X)")
    shape = tuple(check_int(s, "shape", 2) for s in shape)
    truth.subvolume_corners(vol.shape[:3], shape)  # the band needs sub-volumes of that shape
    say = progress or (lambda line: None)
    if colour:
        to_phases, thresholds = ColourCut(vol, classes), None
        labels = to_phases(vol)
    else:
        labels, thresholds = segment(vol, classes)
        to_phases = None if thresholds is None else (lambda v: np.digitize(v, thresholds).astype(np.uint8))
    phases = np.unique(labels)
    max_lag = min(shape) // 2
    if sections not in SECTIONS:
        raise InputError(f"sections={sections!r} must be one of {', '.join(map(repr, SECTIONS))}")
    z = vol.shape[0] // 2
    section = vol[z] if sections == "front" else (
        dict(cut_sections(vol)) if not colour else
        {view: view_slice(vol, view, vol.shape[axis] // 2) for view, axis in DEPTH_AXIS.items()})
    seen_as = f"front, z = {z}" if sections == "front" else (
        f"front z = {z}, right x = {vol.shape[2] // 2}, top y = {vol.shape[1] // 2}")

    grown = []  # grown first: a refused option costs no measuring
    for i in range(n):
        say(f"volume {i + 1} of {n}: {method}, seed {seed + i}, shape {shape}")
        volume = np.asarray(synthesize(section, shape, method=method, rng=seed + i, device=device, params=params,
                                       channel_axis=-1 if colour else None, **options))
        grown.append(volume if to_phases is None else to_phases(volume))
    say(f"real volume {vol.shape}: properties of the whole and of its sub-volumes of {shape}")
    real_props = truth.solid_properties(labels, phases=phases, max_lag=max_lag, tortuosity=tortuosity)
    # The phases the real volume's fractions select, solved in every sample alike.
    tortuosity = [float(key) for key, props in real_props.items() if props["tortuosity"] is not None]
    band, count = truth.property_band(labels, shape, phases=phases, max_lag=max_lag, tortuosity=tortuosity)
    say("the generated volumes' properties")
    samples = [truth.solid_properties(g, phases=phases, max_lag=max_lag, tortuosity=tortuosity) for g in grown]
    compared = truth.compare_properties(real_props, band, truth.mean_properties(samples))
    # The correlation length along each axis (every phase at once): an anisotropic material's signature.
    real_len = correlation_lengths(labels, phases)
    grown_len = np.mean([correlation_lengths(g, phases) for g in grown], axis=0)
    lengths = {"real": list(real_len), "generated": list(grown_len),
               "error": [float(g / r - 1.0) if np.isfinite(r) and r > 0 else None for g, r in zip(grown_len, real_len)]}
    # What the generator saw: a section's fraction and S2 can lie far from the whole volume's.
    cut = labels[z]
    seen = {key: {"fraction": float(np.mean(cut == phase)),
                  "s2": list(two_point_correlation_axes(cut, phase, max_lag=max_lag))}
            for key, phase in zip(real_props, phases)}
    return jsonable({
        "real": {"shape": vol.shape[:3], "section": seen_as, "thresholds": thresholds,
                 "colours": to_phases.colours.tolist() if colour else None},
        "generated": {"method": method, "shape": shape, "seeds": list(range(seed, seed + n))},
        "band_count": count, "phases": compared, "section": seen, "volumes": samples,
        "correlation_length": lengths,
        "targets": {**truth.TARGETS, "tortuosity_min_fraction": truth.TORTUOSITY_MIN_FRACTION},
    })


def _num(x: Any) -> str:
    if x is None:
        return "inf"
    return f"{x:.4g}" if isinstance(x, float) else str(x)


def _verdict(met: Any) -> str:
    return "" if met is None else ("met" if met else "MISSED")


def _rows(rows: dict) -> list[tuple[str, str, str, str, str, str]]:
    """(property, real, band, generated, error, verdict) for one phase, a row per axis."""
    out = []
    for prop, label in (("fraction", "fraction"), ("surface_area", "surface area")):
        r = rows[prop]
        out.append((label, _num(r["real"]), f"{_num(r['band'][0])} - {_num(r['band'][1])}", _num(r["generated"]),
                    _num(r["error"]), _verdict(r["met"])))
    s2 = rows["s2"]
    for a, axis in enumerate(AXES):
        out.append((f"S2 along {axis}", "", "in band" if s2["in_band"][a] else "", "", f"{s2['error'][a]:.3g} %",
                    _verdict(s2["met"][a])))
    for prop, label in (("connected", "connected"), ("tortuosity", "tortuosity")):
        r = rows.get(prop)
        if r is None:
            continue
        for a, axis in enumerate(AXES):
            band = f"{_num(r['band'][0][a])} - {_num(r['band'][1][a])}" if r["band"] else "-"
            out.append((f"{label} {axis}", _num(r["real"][a]), band, _num(r["generated"][a]), _num(r["error"][a]),
                        _verdict(r["met"][a] if r["met"] else None)))
    return out


def format_validation(report: dict) -> str:
    """The report as a plain-text table: a block per phase, a row per property and axis."""
    gen = report["generated"]
    lines = [f"real volume {tuple(report['real']['shape'])}, section {report['real']['section']}; "
             f"{len(gen['seeds'])} {gen['method']} volumes of {tuple(gen['shape'])}; band over "
             f"{report['band_count']} real sub-volumes of that shape"]
    if report["real"]["thresholds"]:
        lines.append("grey levels cut at " + ", ".join(f"{t:.4g}" for t in report["real"]["thresholds"]))
    if report["real"].get("colours"):
        lines.append("colours cut by the nearest (CIELAB) of " + ", ".join(
            "(" + ", ".join(f"{c:.4g}" for c in rgb) + ")" for rgb in report["real"]["colours"])
            + ": phase 0, 1, ...")
    widths = (16, 10, 20, 10, 10)
    head = ("property", "real", "band", "generated", "error")
    for key, rows in report["phases"].items():
        lines += ["", f"phase {key}: the section's fraction {report['section'][key]['fraction']:.4g}",
                  "  " + "".join(h.ljust(w) for h, w in zip(head, widths)) + "target"]
        for row in _rows(rows):
            lines.append("  " + "".join(c.ljust(w) for c, w in zip(row, widths)) + row[-1])
    lengths = report.get("correlation_length")
    if lengths:
        lines += ["", "correlation length z / y / x: real " + " / ".join(_num(v) for v in lengths["real"])
                  + ", generated " + " / ".join(_num(v) for v in lengths["generated"]) + " (error "
                  + " / ".join("-" if e is None else f"{100 * e:+.0f} %" for e in lengths["error"]) + ")"]
    lines += ["", "error: fraction in points (0.01 = 1 point); S2, the largest gap in percent of the phase's "
              "fraction; surface area and tortuosity, relative (0.05 = 5 %). inf: no cluster spans the block"]
    return "\n".join(lines)


def plot_validation(report: dict, path: Any) -> None:
    """S2 per axis and phase: the real volume's band and curve against each generated
    volume's and their mean (needs matplotlib)."""
    Figure, FigureCanvasAgg = _require_matplotlib()
    phases = list(report["phases"])
    fig = Figure(figsize=(10, 2.8 * len(phases)), layout="constrained")
    axes = fig.subplots(len(phases), 3, squeeze=False)
    for row, key in enumerate(phases):
        s2 = report["phases"][key]["s2"]
        for a, ax in enumerate(axes[row]):
            lags = np.arange(len(s2["real"][a]))
            low, high = (np.asarray(b) for b in s2["band"][a])
            ax.fill_between(lags[:low.size], low, high, color="0.85", label="real band")
            ax.plot(lags, s2["real"][a], color="k", lw=1.5, label="real")
            if a > 0:  # the section's rows and columns run along y and x
                seen = report["section"][key]["s2"][a - 1]
                ax.plot(np.arange(len(seen)), seen, color="tab:blue", lw=1, ls="--", label="section")
            for sample in report["volumes"]:
                ax.plot(np.arange(len(sample[key]["s2"][a])), sample[key]["s2"][a], color="tab:orange", lw=0.6,
                        alpha=0.6)
            ax.plot(np.arange(len(s2["generated"][a])), s2["generated"][a], color="tab:red", lw=1.5,
                    label="generated mean")
            ax.set_title(f"phase {key}, S2 along {AXES[a]}: error {s2['error'][a]:.3g} %")
            ax.set_xlabel("lag (voxels)")
            if a == 0:
                ax.legend(fontsize="small")
    FigureCanvasAgg(fig).print_png(str(path))
