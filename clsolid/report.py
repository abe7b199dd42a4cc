"""The evaluation report: reading a volume and its sidecar, the table, the figures.

The numbers come from :func:`clsolid.metrics.evaluate`; this module reads the files, formats
the table, and draws the report and convergence-track figures (``clsolid evaluate``,
:mod:`clsolid.cli.evaluate`). Plotting needs matplotlib, an optional extra
(``pip install "clsolid[report]"``); everything else works without it.
"""

from __future__ import annotations

import json
import math
import pathlib
from typing import Any

import numpy as np

from .errors import ClsolidError, InputError, MissingDependencyError

INSTALL_HINT = 'install it with pip install "clsolid[report]" or pip install matplotlib'


class PlottingUnavailable(MissingDependencyError):
    """matplotlib, needed to draw a figure, is not installed."""


# ----------------------------------------------------------------------------- reading


def load_exemplar(path: Any) -> np.ndarray:
    """Read a 2D grey or RGB exemplar (.npy, .tif/.tiff, .png, or a built-in name).

    The same reader as :func:`clsolid.synthesize` uses: see :func:`clsolid.exemplar.load_exemplar`.
    """
    from .exemplar import load_exemplar as _load

    return _load(str(path) if isinstance(path, pathlib.PurePath) else path)


def load_volume(path: Any) -> np.ndarray:
    """Read a 3D ``(Z, Y, X)`` volume, or an RGB one ``(Z, Y, X, 3)``, from .npy or .tif/.tiff
    (leading singleton axes dropped).

    Uses :func:`clsolid.volumeio.load_volume`.
    """
    from .volumeio import load_volume as _load

    arr = _load(path)[0]
    rgb = arr.ndim == 4 and arr.shape[-1] == 3
    arr = arr if rgb else _squeeze(arr)
    if arr.ndim != 3 and not rgb:
        raise InputError(f"VOLUME={str(path)!r} holds an array of shape {arr.shape}; expected (Z, Y, X) or RGB "
                         "(Z, Y, X, 3)")
    return arr


def read_sidecar(volume_path: Any) -> tuple[pathlib.Path, dict | None]:
    """The path of a ``clsolid synth`` volume's JSON sidecar and what it holds (None when
    there is none or it cannot be read as JSON)."""
    sidecar = pathlib.Path(volume_path).with_suffix(".json")
    try:
        return sidecar, json.loads(sidecar.read_text())
    except (OSError, ValueError):
        return sidecar, None


def like_with_like(exemplar: np.ndarray | dict[str, np.ndarray], sidecar: pathlib.Path, meta: dict | None
                   ) -> tuple[np.ndarray | dict[str, np.ndarray], int | None, str]:
    """Put the exemplar in the units of a ``clsolid synth`` volume, from its sidecar
    (:func:`read_sidecar`).

    A volume of level means is compared after quantising both into the synthesis's
    levels; a volume of level indices against the exemplar's indices (an exemplar per view,
    a dict, on their shared levels); a volume of the exemplar's exact values as it is. A
    colour volume of palette colours is compared with the exemplar in that palette's colours.
    Without a sidecar nothing changes.

    Returns
    -------
    (exemplar, levels, note)
        The exemplar to compare with, the ``levels`` to pass to :func:`evaluate`, and a
        line saying what was done ("" when nothing was).
    """
    from .exemplar import each, level_map

    try:
        written, exact, levels = meta["written"], bool(meta["values_exact"]), meta["params"]["levels"]
    except (KeyError, TypeError):
        return exemplar, None, ""
    if written == "indices":
        return (level_map(exemplar, levels).labels, None,
                f"{sidecar}: the volume holds level indices; the exemplar is compared as indices too")
    if exact or levels is None:
        return exemplar, None, ""
    if any(np.ndim(im) == 3 for im in each(exemplar)):
        palette = level_map(exemplar, levels)
        return (palette.to_values(palette.labels), None,
                f"{sidecar}: a palette of {levels} colours; the exemplar is compared in those colours")
    return exemplar, int(levels), f"{sidecar}: level means of {levels} levels; both quantised to {levels} levels"


def inserted_from_sidecar(sidecar: pathlib.Path, meta: dict | None, shape: tuple) -> tuple[dict, str]:
    """The ``+in`` (or anchor) slices of a ``clsolid synth`` volume, from its sidecar
    (:func:`read_sidecar`).

    Returns
    -------
    (exclude, note)
        Slice indices per view to pass to :func:`evaluate` as ``exclude``, and a line saying
        what is left out ("" and no slices without a sidecar, or for a volume whose shape is
        not the one the sidecar records, or for a synthesis without such slices).
    """
    from .api import inserted_slices

    try:
        params = dict(meta["params"])
        recorded = tuple(params.get("shape") or ())
        depths = inserted_slices(params, shape) if recorded in ((), tuple(shape)) else {}
    except (ValueError, KeyError, TypeError, ClsolidError):
        return {}, ""
    depths = {v: d for v, d in depths.items() if d.size}
    if not depths:
        return {}, ""
    counts = ", ".join(f"{len(d)} {v}" for v, d in depths.items())
    return depths, f"{sidecar}: leaving out the +in slices ({counts}; --keep-inserted measures them)"


def _squeeze(arr: np.ndarray) -> np.ndarray:
    """Drop singleton axes, but keep a volume or image with a side of one as it is."""
    return arr.squeeze() if arr.ndim > 3 or (arr.ndim == 3 and 1 in arr.shape[:1]) else arr


# ----------------------------------------------------------------------------- table


def _fmt(x: Any, width: int = 0) -> str:
    if x is None:
        return "-"
    if isinstance(x, float) and (x == 0 or 1e-3 <= abs(x) < 1e4):
        return f"{x:.3g}" if abs(x) < 10 else f"{x:.1f}"
    return f"{x:.2e}" if isinstance(x, float) else str(x)


def _ref(ref: dict | None) -> str:
    if ref is None:
        return "-"
    return f"{_fmt(ref['mean'])}±{_fmt(ref['std'])}"


def _cell(d: dict) -> str:
    if d["value"] is None:
        return "n/m"
    tag = "n/i" if d["informative"] is False else ("?" if d["score"] is None else f"{d['score']:+.2f}")
    return f"{_fmt(d['value'])} [{tag}]"


def format_table(report: dict) -> str:
    """The short text table of a report: one row per distance, one column per view.

    Parameters
    ----------
    report : dict
        As returned by :func:`clsolid.metrics.evaluate`.

    Returns
    -------
    str
        Table, legend included.
    """
    views = report["views"]
    names = list(views)
    first = views[names[0]]
    header = ["metric", "units", "floor", "ceiling"] + [
        f"{v}{'*' if views[v]['constrained'] else ''}" for v in names]
    rows = [header]
    differ = False
    for key, d in first["distances"].items():
        for v in names[1:]:
            other = views[v]["distances"][key]
            differ |= (_ref(other["floor"]), _ref(other["ceiling"])) != (_ref(d["floor"]), _ref(d["ceiling"]))
        rows.append([key, d["units"], _ref(d["floor"]), _ref(d["ceiling"])]
                    + [_cell(views[v]["distances"][key]) for v in names])
    widths = [max(len(r[i]) for r in rows) for i in range(len(header))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    s = report["settings"]
    vol = report["volume"]["shape"]
    exemplars = report.get("exemplars") or {"": report["exemplar"]}  # one, or each view's
    shapes = ", ".join(f"{v + ' ' if v else ''}{e['shape'][0]}x{e['shape'][1]}" for v, e in exemplars.items())
    head = (f"exemplar{'s' if len(exemplars) > 1 else ''} {shapes}, volume {vol[0]}x{vol[1]}x{vol[2]} (Z,Y,X); "
            f"{s['max_slices'] or 'all'} slices per view; {s['reference_repeats']} reference repeats")
    legend = ["cells: value [score]; score = (value - floor) / (ceiling - floor): ~0 as good as the "
              "exemplar itself, ~1 no more structure than shuffled pixels (noise for histograms)",
              "floor/ceiling: mean±std over random exemplar halves / shuffles; * constrained view; "
              "n/i: uninformative for this exemplar; n/m: not measurable; ?: no floor or ceiling"]
    if differ:
        legend.append(f"floor and ceiling shown for the {names[0]} view; the other views' are in the JSON")
    for name, why in s.get("skipped", {}).items():
        legend.append(f"skipped {name}: {why}")
    return "\n".join([head, *lines, *legend, "", _stats_table(report)])


def _stats_table(report: dict) -> str:
    """First-order statistics of the exemplar and of each view's slices, side by side."""
    views = report["views"]
    exemplars = report.get("exemplars") or {"": report["exemplar"]}
    cols = [(f"{v + ' ' if v else ''}exemplar", e["stats"]) for v, e in exemplars.items()] + [
        (f"{v}{'*' if rep['constrained'] else ''}", rep["stats"]) for v, rep in views.items()]
    rows = [["statistic"] + [c for c, _ in cols]]
    for key in ("mean", "mad", "std", "variance", "skewness", "kurtosis"):
        rows.append([key if key != "kurtosis" else "kurtosis (excess)"] + [_fmt(st[key]) for _, st in cols])
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows)


# ----------------------------------------------------------------------------- track


def load_track(path: Any) -> dict:
    """Read and validate a convergence track JSON file (see :func:`validate_track`)."""
    try:
        with open(path, encoding="utf-8") as fh:
            track = json.load(fh)
    except json.JSONDecodeError as err:
        raise InputError(f"--track={str(path)!r} is not valid JSON: {err}") from None
    validate_track(track)
    return track


def validate_track(track: Any) -> list[dict]:
    """Check ``{"records": [{"scale": int, "sweep": int, "indicators": {name: number}}, ...]}``.

    Parameters
    ----------
    track : dict
        The parsed JSON. Indicator values may be numbers or None (null).

    Returns
    -------
    list of dict
        The records.
    """
    if not isinstance(track, dict) or not isinstance(track.get("records"), list):
        raise InputError("track must be a JSON object with a 'records' list")
    for i, rec in enumerate(track["records"]):
        if not isinstance(rec, dict):
            raise InputError(f"track records[{i}] must be an object, got {rec!r}")
        for key in ("scale", "sweep"):
            if isinstance(rec.get(key), bool) or not isinstance(rec.get(key), int):
                raise InputError(f"track records[{i}].{key} must be an integer, got {rec.get(key)!r}")
        ind = rec.get("indicators")
        if not isinstance(ind, dict):
            raise InputError(f"track records[{i}].indicators must be an object, got {ind!r}")
        for name, value in ind.items():
            if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))):
                raise InputError(f"track records[{i}].indicators[{name!r}] must be a number, got {value!r}")
    return track["records"]


def _track_series(records: list[dict]) -> dict[str, dict[int, tuple[list[int], list[float]]]]:
    """indicator -> scale -> (sweeps, values), finite values only, in record order."""
    out: dict[str, dict[int, tuple[list[int], list[float]]]] = {}
    for rec in records:
        for name, value in rec["indicators"].items():
            if value is None or not math.isfinite(value):
                continue
            sweeps, values = out.setdefault(name, {}).setdefault(rec["scale"], ([], []))
            sweeps.append(rec["sweep"])
            values.append(float(value))
    return out


def format_track(track: dict) -> str:
    """One line per indicator and scale: first and last value and the number of sweeps."""
    series = _track_series(validate_track(track))
    lines = [f"track: {len(track['records'])} records"]
    for name, scales in series.items():
        for scale, (sweeps, values) in sorted(scales.items()):
            lines.append(f"  {name} scale {scale}: {_fmt(values[0])} -> {_fmt(values[-1])} "
                         f"over {len(sweeps)} sweeps")
    return "\n".join(lines)


# ----------------------------------------------------------------------------- plotting


def _require_matplotlib() -> tuple[Any, Any]:
    """The Figure class and Agg canvas; no pyplot, so no global state or GUI backend."""
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError:
        raise PlottingUnavailable(
            f"plotting needs matplotlib, which is not installed; {INSTALL_HINT}") from None
    return Figure, FigureCanvasAgg


def plot_track(track: dict, path: Any) -> None:
    """Plot convergence indicators: one panel per indicator, one curve per scale against sweeps.

    Parameters
    ----------
    track : dict
        ``{"records": [{"scale": int, "sweep": int, "indicators": {name: float, ...}}, ...]}``.
    path : str or path-like
        The PNG to write.
    """
    series = _track_series(validate_track(track))
    Figure, Canvas = _require_matplotlib()
    n = max(len(series), 1)
    cols = min(n, 3)
    rows = -(-n // cols)
    fig = Figure(figsize=(4.2 * cols, 3.2 * rows), layout="constrained")
    Canvas(fig)
    if not series:
        fig.text(0.5, 0.5, "no indicator values in this track", ha="center")
    for k, (name, scales) in enumerate(series.items()):
        ax = fig.add_subplot(rows, cols, k + 1)
        for scale, (sweeps, values) in sorted(scales.items()):
            ax.plot(sweeps, values, marker="o", ms=3, label=f"scale {scale}")
        ax.set_title(name)
        ax.set_xlabel("sweep")
        ax.xaxis.get_major_locator().set_params(integer=True)
        ax.legend(fontsize="small")
    fig.savefig(path, dpi=100)


def plot_report(report: dict, path: Any) -> None:
    """Draw a report: per view, histograms, orientation histograms, autocorrelation maps, fringes.

    Parameters
    ----------
    report : dict
        As returned by :func:`clsolid.metrics.evaluate`.
    path : str or path-like
        The PNG to write.
    """
    Figure, Canvas = _require_matplotlib()
    panels = [_hist_panel, _orientation_panel, _acf_panel("exemplar"), _acf_panel("volume"), _fringe_panel]
    if any(v.get("phases") for v in report["views"].values()):
        panels.append(_s2_panel)
    views = report["views"]
    fig = Figure(figsize=(3.3 * len(panels), 2.9 * len(views)), layout="constrained")
    Canvas(fig)
    for r, (name, view) in enumerate(views.items()):
        for c, panel in enumerate(panels):
            ax = fig.add_subplot(len(views), len(panels), r * len(panels) + c + 1)
            panel(ax, view)
            if c == 0:
                ax.set_ylabel(view["label"], fontweight="bold")
    fig.suptitle("clsolid evaluate: exemplar (black) vs volume slices (red)")
    fig.savefig(path, dpi=90)


def _score_title(view: dict, key: str, what: str) -> str:
    d = view["distances"].get(key)
    if d is None:
        return what
    return f"{what}\n{key}: {_cell(d)}"


def _hist_panel(ax: Any, view: dict) -> None:
    h = view["histogram"]
    ax.step(h["bin_centres"], h["exemplar"], where="mid", color="k", label="exemplar")
    ax.step(h["bin_centres"], h["volume"], where="mid", color="r", label="volume")
    ax.set_title(_score_title(view, "histogram_kl", "grey levels"), fontsize="small")
    ax.legend(fontsize="x-small")


def _orientation_panel(ax: Any, view: dict) -> None:
    o = view.get("orientation")
    if o is None:
        ax.text(0.5, 0.5, "orientation skipped", ha="center", transform=ax.transAxes)
        ax.set_axis_off()
        return
    ax.plot(o["bin_centres_deg"], o["exemplar"]["histogram"], color="k")
    ax.plot(o["bin_centres_deg"], o["volume"]["histogram"], color="r")
    ax.set_xlabel("gradient angle (deg)")
    ax.set_title(_score_title(view, "orientation_kl", "orientation"), fontsize="small")


def _acf_panel(side: str):
    def panel(ax: Any, view: dict) -> None:
        a = view["autocorrelation"]
        ly, lx = a["lags"]
        ax.imshow(np.array(a[side]), extent=(-lx - 0.5, lx + 0.5, ly + 0.5, -ly - 0.5), vmin=-1, vmax=1,
                  cmap="RdBu_r")
        title = f"autocorrelation, {side}"
        ax.set_title(_score_title(view, "autocorrelation_l2", title) if side == "volume" else title,
                     fontsize="small")
    return panel


def _fringe_panel(ax: Any, view: dict) -> None:
    f = view.get("fringes")
    if f is None or f["exemplar"]["length_hist"] is None or f["volume"]["length_hist"] is None:
        ax.text(0.5, 0.5, "no fringe distribution", ha="center", transform=ax.transAxes)
        ax.set_axis_off()
        return
    edges = np.array(f["length_edges"])
    centres = 0.5 * (edges[1:] + edges[:-1])
    ax.step(centres, f["exemplar"]["length_hist"], where="mid", color="k")
    ax.step(centres, f["volume"]["length_hist"], where="mid", color="r")
    ax.set_xlabel("fringe length (px)")
    ax.set_title(_score_title(view, "fringe_length_w1", "fringe lengths"), fontsize="small")


def _s2_panel(ax: Any, view: dict) -> None:
    p = view.get("phases")
    if not p:
        ax.set_axis_off()
        return
    for curve in p["curves"]:
        if curve["phase"] != len(p["phase_values"]) - 1:
            continue
        style = "-" if curve["axis"] == 1 else "--"
        ax.plot(curve["s2"]["exemplar"], style, color="k", label=f"along {curve['volume_axis']}")
        ax.plot(curve["s2"]["volume"], style, color="r")
    ax.set_xlabel("lag (px)")
    ax.legend(fontsize="x-small")
    ax.set_title(_score_title(view, "s2_l2", f"S2 of phase {p['phase_values'][-1]}"), fontsize="small")
