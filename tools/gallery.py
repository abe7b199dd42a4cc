"""Judge a synthesis method on the gallery of exemplars (clsolid.gallery).

Grows one cube per exemplar and seed, then measures, with clsolid.metrics: the largest
phase-fraction error (percentage points, categorical exemplars), the calibrated
histogram, patch, autocorrelation and (categorical) S2 and C2 (two-point cluster) scores in
the front, right and top views (0: as close as two halves of the exemplar, 1: no structure), the mirror
correlation (x <-> z with 2 views; every pair of axes with 3), the stretch (how much taller
than wide the features are in the constrained views, against the exemplar; the y axis the
two views share makes them tall), the largest fraction of any slice identical to a shifted
window of the exemplar, the share of isolated voxels (no face neighbour alike) over the
exemplar's share of isolated pixels, and the time. Writes, in OUTDIR:
gallery.md (a table and how many exemplars meet each target), gallery.json (every
number) and montage.png (each exemplar beside a front, right and top slice taken away
from the +in slices). With several seeds every cell shows the worst seed, and the targets
are counted both on those worst cells and seed by seed.

    python tools/gallery.py -o out/gallery                        # every exemplar, 64^2 -> 48^3
    python tools/gallery.py --names porous50 hrtem --size 128 --shape 64 -o out/g128
    python tools/gallery.py --names wood tabletop fur stained -o out/colour   # the colour gallery (ml)
    python tools/gallery.py --seeds 1 2 --set neighborhood=7 --set views=2 -o out/g7
    python tools/gallery.py --merge out/a/gallery.json out/b/gallery.json -o out/ab   # runs split by exemplar or seed
    python tools/gallery.py --compare out/a/gallery.json out/b/gallery.json -o out/ab  # before -> after, every view
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

import clsolid
from clsolid import metrics
from clsolid.exemplar import nearest_level_index
from clsolid.colour import luminance
from clsolid.gallery import MAX_SIZE, SIZES, colour_names, gallery_exemplar, gallery_info, gallery_names
from clsolid.metrics._common import jsonable
from clsolid.metrics.symmetry import AXIS_PAIRS
from clsolid.core.views import view_set
from clsolid.api import inserted_slices, slice_plan
from clsolid.preview import render_preview
from clsolid.core.slices import preview_depths
from quality_ml import parse_setting  # beside this script (tools/ is on the path when it runs)

VIEWS = metrics.VIEWS
#: The calibrated scores reported per view: (key in clsolid.metrics.evaluate, column title).
SCORES = (("histogram_kl", "hist"), ("patch_sw", "patch"), ("autocorrelation_l2", "autocorr"), ("s2_l2", "S2"),
          ("c2_l2", "C2"), ("colour_histogram_kl", "colour"))
#: The gallery's targets: (key, label, limit, whether the value must stay strictly below it).
TARGETS = (
    ("phase_error_pp", "every phase within 3 pp", 3.0, False),
    ("histogram_kl", "histogram <= 0.1", 0.1, False),
    ("patch_sw", "patch <= 0.3", 0.3, False),
    ("autocorrelation_l2", "autocorrelation <= 0.3", 0.3, False),
    ("mirror", "mirror <= 0.1", 0.1, False),
    ("copy", "no slice >= 90 % copied", 0.9, True),
    ("colour_histogram_kl", "joint colour histogram <= 0.1", 0.1, False),
)
#: A method's own stricter targets, counted beside :data:`TARGETS`: `kopf`'s histogram
#: re-weighting is to keep the phases within 2 points and the histogram within 0.05.
METHOD_TARGETS = {
    "kopf": (("phase_error_pp", "every phase within 2 pp (kopf's stricter target)", 2.0, False),
             ("histogram_kl", "histogram <= 0.05 (kopf's stricter target)", 0.05, False)),
}
#: Yardsticks of our own, counted the same way but not targets.
YARDSTICKS = (
    ("c2_l2", "connectedness C2 <= 0.3 (not an issue target)", 0.3, False),
    ("stretch", "stretch within 1.25x (not an issue target)", 1.25, False),
    ("traces", "no trace of the inserted slices (not an issue target)", 0, False),
)
REFERENCE_REPEATS = 3
#: Smallest long side, in pixels, of a montage panel.
PANEL_MIN = 128


# ----------------------------------------------------------------------------- one run


def level_indices(res: Any) -> tuple[np.ndarray, np.ndarray]:
    """The volume and the exemplar of a result, both in level indices (phases, for categorical ones).

    A method that blends values (``wl``) has no indices: each voxel counts for its nearest
    level value, so a blend of two phases counts for one of them (or for a phase between).
    """
    if res.labels is not None:
        return res.labels, res.exemplar_labels
    index = nearest_level_index(res.volume, res.level_values).reshape(res.volume.shape)
    return index.astype(res.exemplar_labels.dtype), res.exemplar_labels


def copy_chance(exemplar: np.ndarray, side: int) -> float:
    """What the copy measure gives without copying: a window of the exemplar's lower half
    against its upper half (two parts of the same material). Sparse and two-phase exemplars
    match by chance on most pixels (a slice of matrix equals a window of matrix)."""
    half = exemplar.shape[0] // 2
    h, w = min(side, exemplar.shape[0] - half), min(side, exemplar.shape[1])
    window = exemplar[half:half + h, :w][None]
    return float(metrics.match_counts(window, exemplar[:half]).max() / window[0].size)


def isolated(res: Any, categorical: bool) -> dict[str, float]:
    """The share of isolated voxels of a result's volume (labels none of the 6 face neighbours,
    across the block's faces too: it tiles, shares; grey: unlike every one by more than the exemplar's steps,
    :func:`clsolid.metrics.isolated_contrast_fraction`), the exemplar's share of isolated pixels
    (4 neighbours), and their ratio. The exemplar counts at least one pixel: a clean one has none,
    and a ratio to 0 would say nothing of how speckled the volume is."""
    if categorical:
        vol, ex = level_indices(res)
        in_volume, in_exemplar = metrics.isolated_fraction(vol, periodic=True), metrics.isolated_fraction(ex)
    else:  # the exemplar as the engine saw it (level means, palette colours), like the volume
        vol, ex = _grey(res.volume), _grey(res.exemplar)
        in_volume = metrics.isolated_contrast_fraction(vol, ex, periodic=True)
        in_exemplar = metrics.isolated_contrast_fraction(ex, ex)
    return {"volume": in_volume, "exemplar": in_exemplar,
            "ratio": in_volume / max(in_exemplar, 1.0 / np.size(res.exemplar))}


def _grey(values: np.ndarray) -> np.ndarray:
    """A colour image or volume's luminance; a grey one as it is."""
    return luminance(values) if values.shape[-1:] == (3,) and values.ndim in (3, 4) else values


def measure(res: Any, seconds: float, categorical: bool) -> dict[str, Any]:
    """Every number of the gallery for one synthesis result (phase fractions if ``categorical``).
    A colour result is evaluated in its colours (structure on luminance, and the joint colour
    histogram); its mirror, stretch and traces on luminance, its copies on palette indices."""
    params = res.params
    vol, ex = level_indices(res)
    constrained = view_set(params["views"])
    slices = inserted_slices(res.params, res.volume.shape[:3])  # the +in (or anchor) slices of every view
    colour = res.volume.ndim == 4
    report = metrics.evaluate(res.exemplar if colour else ex, res.volume if colour else vol, views=VIEWS,
                              constrained=constrained,  # +in copies would flatter
                              reference_repeats=REFERENCE_REPEATS, rng=0, exclude=slices)
    if colour:  # the structure's measures on luminance
        vol, ex = _grey(res.volume), _grey(res.exemplar)
    scores = {v: {key: None for key, _ in SCORES} for v in VIEWS}
    for row in report["summary"]:
        if row["metric"] in scores[row["view"]]:
            scores[row["view"]][row["metric"]] = row["score"]
    pairs = [(0, 2)] if params["views"] == 2 else AXIS_PAIRS
    mirror = metrics.mirror_correlations(vol, pairs)
    copy = metrics.max_copy_fraction(*(level_indices(res) if colour else (vol, ex)), VIEWS)
    stretch = metrics.stretch(ex, vol, constrained)
    out: dict[str, Any] = {
        "seconds": seconds, "constrained": list(constrained), "scores": scores,
        "mirror": mirror, "mirror_max": max((r for r in mirror.values() if np.isfinite(r)), default=None),
        "mirror_chance": metrics.mirror_chance(ex, min(vol.shape)),
        "stretch": stretch, "stretch_max": _farthest_from_one(stretch.values()),
        "copy": {"fraction": copy.fraction, "view": copy.view, "index": copy.index, "shift": list(copy.shift),
                 "inserted": bool(copy.index in slices[copy.view]),
                 "chance": copy_chance(res.exemplar_labels if colour else ex, min(vol.shape))},
        "inserted_depths": {v: d.tolist() for v, d in slices.items()},
        "isolated": isolated(res, categorical),
        "traces": metrics.slice_traces(vol, slices, exemplar=ex, categorical=categorical)["outside"],
        "phase_error_pp": None, "fractions": None,
    }
    if categorical:
        both = np.union1d(np.unique(ex), np.unique(vol))
        f_ex = np.array([np.mean(ex == v) for v in both])
        f_vol = np.array([np.mean(vol == v) for v in both])
        out["phase_error_pp"] = float(100.0 * np.abs(f_ex - f_vol).max())
        out["fractions"] = {"levels": both.tolist(), "exemplar": f_ex.tolist(), "volume": f_vol.tolist()}
    return out


def run_one(name: str, size: int, shape: int, seed: int, method: str, options: dict,
            device: Any) -> tuple[dict[str, Any], Any]:
    """Synthesise one exemplar with one seed and measure it."""
    image = gallery_exemplar(name, size)
    t = time.perf_counter()
    res = clsolid.synthesize(image, (shape,) * 3, method=method, rng=seed, device=device, full_output=True,
                             channel_axis=-1 if image.ndim == 3 else None, **options)
    seconds = time.perf_counter() - t
    categorical = gallery_info(name).kind == "categorical"
    return {"name": name, "seed": seed, **measure(res, seconds, categorical)}, res


# ----------------------------------------------------------------------------- summary


def _worst(values: list) -> float | None:
    defined = [v for v in values if v is not None]
    return max(defined) if defined else None


def _factor(ratio: float) -> float:
    """How far a ratio is from 1, as a factor either way: 0.5 and 2 both give 2, 0 and inf give inf."""
    return float("inf") if ratio in (0.0, float("inf")) else max(ratio, 1.0 / ratio)


def _farthest_from_one(ratios: Any) -> float | None:
    """The ratio farthest from 1 by its factor (0.5 and 2 are as far), None if none is known."""
    known = [r for r in ratios if r is not None and not np.isnan(r)]
    return max(known, key=_factor) if known else None


def summarise(runs: list[dict]) -> dict[str, Any]:
    """One exemplar's runs (seeds) reduced to their worst value for every number."""
    first = runs[0]
    return {
        "phase_error_pp": _worst([r["phase_error_pp"] for r in runs]),
        "scores": {v: {k: _worst([r["scores"][v][k] for r in runs]) for k, _ in SCORES} for v in VIEWS},
        "mirror": _worst([r["mirror_max"] for r in runs]),
        "mirror_chance": first["mirror_chance"],
        "stretch": _farthest_from_one([r.get("stretch_max") for r in runs]),  # gallery.json before it: None
        "copy": max((r["copy"] for r in runs), key=lambda c: c["fraction"]),
        "isolated": _worst([r.get("isolated", {}).get("ratio") for r in runs]),  # gallery.json before it: None
        "traces": max((r.get("traces") for r in runs), key=lambda t: -1 if t is None else len(t)),
        "seconds": float(np.mean([r["seconds"] for r in runs])),
        "constrained": first["constrained"],
    }


def meets(row: dict, key: str, limit: float, strict: bool) -> bool | None:
    """Whether one exemplar meets one target (None: not measurable or not applicable)."""
    if key in dict(SCORES):  # a per-view score: the worst constrained view
        values = [row["scores"][v][key] for v in row["constrained"]]
        if any(v is None for v in values):
            return None
        value = max(values)
    elif key == "copy":
        value = row["copy"]["fraction"]
    elif key == "stretch":  # a factor either way
        value = None if row["stretch"] is None else _factor(row["stretch"])
    elif key == "traces":  # how many statistics show one
        value = None if row.get("traces") is None else len(row["traces"])
    else:
        value = row[key]
    if value is None:
        return None
    return value < limit if strict else value <= limit


def _traces(outside: list[str] | None) -> str:
    """The traces cell: how many statistics show one, and the first of them."""
    if outside is None:
        return "–"
    return f"{len(outside)} ({outside[0]})" if outside else "0"


def _fmt(x: float | None, digits: int = 2) -> str:
    return "–" if x is None else "∞" if x == float("inf") else f"{x:.{digits}f}"


def target_counts(rows: dict[str, dict], method: str = "ml") -> list[tuple[str, str, str]]:
    """For every target (the gallery's, then *method*'s own) and yardstick: its label, how many of
    *rows* meet it of those judged ("k/n"), and how many could not be judged and why ("" if none)."""
    out = []
    for key, label, limit, strict in TARGETS + METHOD_TARGETS.get(method, ()) + YARDSTICKS:
        verdicts = [meets(row, key, limit, strict) for row in rows.values()]
        judged = [v for v in verdicts if v is not None]
        if key == "colour_histogram_kl" and not judged:  # a gallery without colour exemplars
            continue
        left = len(verdicts) - len(judged)
        why = "not segmented, not applicable" if key == "phase_error_pp" else "not measurable"
        out.append((label, f"{sum(judged)}/{len(judged)}", f" ({left} {why})" if left else ""))
    return out


def markdown(rows: dict[str, dict], settings: dict, runs: dict[str, list[dict]] | None = None) -> str:
    """The table of the gallery, and how many exemplars meet each target; with several seeds'
    *runs* (each exemplar's, in seed order), the same count seed by seed as well."""
    lines = [
        f"Gallery: method `{settings['method']}`, exemplars {settings['size']}², volumes "
        f"{settings['shape']}³, seeds {settings['seeds']}, settings {settings['options'] or 'defaults'}, "
        f"device {settings['device']}.",
        "",
        "Scores (F/R/T = front/right/top view): 0 = as close as two halves of the exemplar, 1 = no "
        "structure; – = not measurable for this exemplar (colour: the joint colour histogram of a colour "
        "exemplar, whose other scores are its luminance's); each on 16 slices of its view away from "
        "the view's +in (or anchor) slices, which start as exemplar copies. Phase err: largest phase-fraction error, "
        "percentage points. Mirror: correlation with the x↔z mirror after removing each y-plane's "
        "mean (the largest over axis pairs with 3 views), and in brackets the level an isotropic "
        "material with the exemplar's autocorrelation would give (a voxel near the plane z = x is "
        "close to its mirror voxel). Stretch: in the constrained view where it is farthest from 1, "
        "the features' height-to-width ratio (correlation lengths along y and across) over the "
        "exemplar's: above 1, taller than the exemplar's; ∞: longer along y than half the volume's "
        "side. Isolated: the volume's share of voxels no face neighbour is like (the same phase; grey: "
        "within the exemplar's 99th-percentile step) over the exemplar's share of such pixels, counted as at "
        "least one pixel. Traces: the per-slice statistics (phase fractions or mean and spread, isolated share, "
        "step to the next slice, patch distance) whose mean over the inserted slices, or over their "
        "neighbours, lies more than one standard deviation of the other slices from theirs "
        "(`clsolid.metrics.slice_traces`), counted over views; the worst seed's, with the first named. Copy: largest fraction of a slice equal to a shifted exemplar window, with the slice "
        "(view and depth; +in: an inserted slice) and, in "
        "brackets, its chance level: a window of the exemplar's lower half against its upper half."
        + (" Each cell is the worst seed; time is the mean." if len(settings["seeds"]) > 1 else ""),
        "",
        "| exemplar | kind | phase err | " + " | ".join(f"{title} F/R/T" for _, title in SCORES)
        + " | mirror | stretch | isolated | traces | copy | time (s) |",
        "|---" * (9 + len(SCORES)) + "|",
    ]
    for name, row in rows.items():
        info = gallery_info(name)
        kind = f"{len(info.phases)} phases" if info.kind == "categorical" else info.kind
        cells = ["/".join(_fmt(row["scores"][v][key]) for v in VIEWS) for key, _ in SCORES]
        c = row["copy"]
        copy = (f"{c['fraction']:.2f} {c['view'][0].upper()}{c['index']}{' +in' if c['inserted'] else ''} "
                f"({c['chance']:.2f})")
        lines.append(f"| {name} | {kind} | {_fmt(row['phase_error_pp'], 1)} | " + " | ".join(cells)
                     + f" | {_fmt(row['mirror'])} ({_fmt(row['mirror_chance'])}) | {_fmt(row['stretch'])} | "
                     f"{_fmt(row.get('isolated'), 1)} | {_traces(row.get('traces'))} | {copy} "
                     f"| {row['seconds']:.1f} |")
    lines += ["", "Targets met (scores in the constrained views"
              + ("; every exemplar's worst seed):" if len(settings["seeds"]) > 1 else "):"), ""]
    lines += [f"- {label}: {count}{unjudged}" for label, count, unjudged in target_counts(rows, settings["method"])]
    if runs and len(settings["seeds"]) > 1:  # the worst seed of each exemplar is not one seed's block
        per_seed = [target_counts({name: summarise(mine) for name, r in runs.items()
                                   if (mine := [x for x in r if x["seed"] == seed])}, settings["method"])
                    for seed in settings["seeds"]]
        lines += ["", "Seed by seed (" + ", ".join(str(s) for s in settings["seeds"]) + "):", ""]
        lines += [f"- {label}: " + " · ".join(counts[j][1] for counts in per_seed)
                  for j, (label, _, _) in enumerate(per_seed[0])]
    return "\n".join(lines) + "\n"


def montage(path: Path, rows: list[np.ndarray]) -> None:
    """Stack the previews of the exemplars (one row each), left-aligned on white (in colour
    where any is)."""
    if any(r.ndim == 3 for r in rows):
        rows = [r if r.ndim == 3 else np.repeat(r[..., None], 3, axis=2) for r in rows]
    width = max(r.shape[1] for r in rows)
    padded = [np.pad(r, ((0, 0), (0, width - r.shape[1])) + ((0, 0),) * (r.ndim - 2), constant_values=255)
              for r in rows]
    Image.fromarray(np.vstack(padded)).save(path, format="PNG")


def montage_row(name: str, res: Any) -> np.ndarray:
    """The exemplar beside a front, right and top slice, each away from the ``+in`` (or
    anchor) slices."""
    params = slice_plan(res.params)
    ml = res.params["method"] == "ml"  # a search method's volume holds values, not level indices
    colour = res.volume.ndim == 4  # shown in its colours
    exemplar, volume = (res.exemplar_labels, res.labels) if ml and not colour else (res.exemplar, res.volume)
    return render_preview(exemplar, volume, depths=preview_depths(volume.shape, params),
                          constrained=params.view_names, name=name, min_side=PANEL_MIN).image


# ----------------------------------------------------------------------------- merge


def write_report(outdir: Path, settings: dict, runs: dict[str, list[dict]]) -> None:
    """gallery.md and gallery.json in *outdir* from every exemplar's *runs*."""
    rows = {name: summarise(r) for name, r in runs.items()}
    outdir.mkdir(parents=True, exist_ok=True)
    (outdir / "gallery.md").write_text(markdown(rows, settings, runs), encoding="utf-8")
    (outdir / "gallery.json").write_text(
        json.dumps(jsonable({"settings": settings, "exemplars": rows, "runs": runs}), indent=1), encoding="utf-8")


#: Settings that two runs must share to be counted as one gallery (the device and seeds may differ).
MERGE_KEYS = ("method", "size", "shape", "options")


def merge_reports(reports: list[dict]) -> tuple[dict, dict[str, list[dict]]]:
    """One gallery from the ``gallery.json`` of several runs with the same settings over
    different exemplars or different seeds (e.g. two processes, one per core; seeds 3 and 4
    after 1 and 2): the settings, with every seed, and the runs, exemplars in the order
    first given, each exemplar's seeds in order. Refuses runs whose settings differ or that
    measure an exemplar with the same seed twice."""
    first = reports[0]["settings"]
    runs: dict[str, list[dict]] = {}
    devices, seeds = [], set()
    for report in reports:
        settings = report["settings"]
        differ = [k for k in MERGE_KEYS if settings.get(k) != first.get(k)]
        if differ:
            raise ValueError(f"cannot merge runs whose {', '.join(differ)} differ")
        for name, more in report["runs"].items():
            had = {r["seed"] for r in runs.get(name, [])}
            twice = sorted(had & {r["seed"] for r in more})
            if twice:
                raise ValueError(f"{name} with seed {twice[0]} measured in more than one of the runs")
            runs[name] = sorted(runs.get(name, []) + list(more), key=lambda r: r["seed"])
        devices.append(settings["device"])
        seeds.update(settings["seeds"])
    device = " + ".join(dict.fromkeys(devices))
    return {**first, "device": device, "seeds": sorted(seeds)}, runs


# ----------------------------------------------------------------------------- compare


def _all_views(run: dict, key: str) -> float | None:
    """The worst of a run's three views for a per-view score (None if any is unmeasurable)."""
    values = [run["scores"][v][key] for v in VIEWS]
    return None if any(v is None for v in values) else max(values)


#: The columns of a comparison: (title, the value of one run, the limit it must not exceed).
COMPARED = (
    ("patch, worst view", lambda r: _all_views(r, "patch_sw"), 0.3),
    ("autocorr, worst view", lambda r: _all_views(r, "autocorrelation_l2"), 0.3),
    ("top patch", lambda r: r["scores"]["top"]["patch_sw"], 0.3),
    ("top autocorr", lambda r: r["scores"]["top"]["autocorrelation_l2"], 0.3),
    ("mirror", lambda r: r["mirror_max"], 0.1),
    ("stretch (factor)", lambda r: None if r.get("stretch_max") is None else _factor(r["stretch_max"]), 1.15),
    ("isolated", lambda r: r.get("isolated", {}).get("ratio"), 1.5),
)


def compare_markdown(before: dict, after: dict) -> str:
    """One table, exemplar by exemplar, of two galleries' worst seeds, every view judged
    (the constrained ones and the free one alike): each cell "before → after"."""
    names = [n for n in after["runs"] if n in before["runs"]]
    lines = [f"Before: {before['settings']['method']}, settings {before['settings']['options'] or 'defaults'}, "
             f"seeds {before['settings']['seeds']}. After: {after['settings']['method']}, settings "
             f"{after['settings']['options'] or 'defaults'}, seeds {after['settings']['seeds']}. Each cell: the worst "
             "seed, before → after; the scores' worst view is taken over front, right and top, constrained or not.",
             "", "| exemplar | " + " | ".join(t for t, _, _ in COMPARED) + " |", "|---" * (1 + len(COMPARED)) + "|"]
    met = {t: [0, 0, 0, 0] for t, _, _ in COMPARED}  # met before, judged before, met after, judged after
    for name in names:
        cells = []
        for title, value, limit in COMPARED:
            pair = []
            for k, runs in enumerate((before["runs"][name], after["runs"][name])):
                worst = _worst([value(r) for r in runs])
                if worst is not None:
                    met[title][2 * k] += worst <= limit
                    met[title][2 * k + 1] += 1
                pair.append(_fmt(worst, 1 if title == "isolated" else 2))
            cells.append(" → ".join(pair))
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    lines += ["", "Exemplars within each limit (" + ", ".join(f"{t} <= {lim}" for t, _, lim in COMPARED)
              + "), before → after:", ""]
    lines += [f"- {t}: {m[0]}/{m[1]} → {m[2]}/{m[3]}" for t, m in met.items()]
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------- main


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--names", nargs="+", choices=gallery_names() + colour_names(), default=list(gallery_names()),
                    metavar="NAME", help=f"exemplars (default: all of {', '.join(gallery_names())})")
    ap.add_argument("--size", type=int, choices=(*SIZES, MAX_SIZE), default=64,
                    help=f"exemplar side (default 64; the gallery is meant at {SIZES})")
    ap.add_argument("--shape", type=int, default=48, metavar="N", help="cube side of the volumes (default 48)")
    ap.add_argument("--seeds", nargs="+", type=int, default=[1], help="seeds (default 1)")
    ap.add_argument("--method", default="ml", help="synthesis method (default ml)")
    ap.add_argument("--set", dest="settings", action="append", type=parse_setting, default=[],
                    metavar="NAME=VALUE", help="a synthesize() keyword, repeatable")
    ap.add_argument("--device", default=None, help="OpenCL device (default: clsolid's choice)")
    ap.add_argument("--merge", nargs="+", type=Path, metavar="JSON",
                    help="instead of running: one table and gallery.json from the gallery.json of runs over "
                         "different exemplars or seeds with the same settings (no montage: it needs the volumes)")
    ap.add_argument("--compare", nargs=2, type=Path, metavar=("BEFORE", "AFTER"),
                    help="instead of running: compare.md, a before/after table of two gallery.json files, every "
                         "view judged")
    ap.add_argument("-o", "--outdir", type=Path, required=True, help="folder for gallery.md/.json and montage.png")
    args = ap.parse_args(argv)
    if args.compare:
        try:
            before, after = (json.loads(p.read_text(encoding="utf-8")) for p in args.compare)
            text = compare_markdown(before, after)
        except (OSError, ValueError, KeyError) as err:
            print(f"gallery: --compare: {err}", file=sys.stderr)
            return 2
        args.outdir.mkdir(parents=True, exist_ok=True)
        (args.outdir / "compare.md").write_text(text, encoding="utf-8")
        print(f"wrote {args.outdir / 'compare.md'}", file=sys.stderr)
        return 0
    if args.merge:
        try:
            settings, runs = merge_reports([json.loads(p.read_text(encoding="utf-8")) for p in args.merge])
        except (OSError, ValueError, KeyError) as err:
            print(f"gallery: --merge: {err}", file=sys.stderr)
            return 2
        write_report(args.outdir, settings, runs)
        print(f"wrote {args.outdir / 'gallery.md'} and gallery.json", file=sys.stderr)
        return 0
    options = dict(args.settings)
    try:
        device = args.device if str(args.device).lower() == "reference" else clsolid.select_device(args.device)
    except clsolid.ClsolidError as err:
        print(f"gallery: {err}", file=sys.stderr)
        return 2
    device_name = device if isinstance(device, str) else device.name
    settings = {"method": args.method, "size": args.size, "shape": args.shape, "seeds": args.seeds,
                "options": options, "device": device_name, "version": clsolid.__version__}
    runs: dict[str, list[dict]] = {}
    rows_for_montage = []
    for name in args.names:
        for seed in args.seeds:
            t = time.perf_counter()
            try:
                run, res = run_one(name, args.size, args.shape, seed, args.method, options, device)
            except clsolid.ClsolidError as err:
                print(f"gallery: {name} seed {seed}: {err}", file=sys.stderr)
                return 2
            runs.setdefault(name, []).append(run)
            if seed == args.seeds[0]:
                rows_for_montage.append(montage_row(name, res))
            c = run["copy"]
            print(f"{name} seed {seed}: {run['seconds']:.1f} s synthesis, {time.perf_counter() - t:.1f} s in all; "
                  f"phase err {_fmt(run['phase_error_pp'], 1)} pp, mirror {_fmt(run['mirror_max'])}, "
                  f"stretch {_fmt(run['stretch_max'])}, isolated {_fmt(run['isolated']['ratio'], 1)}x, "
                  f"copy {c['fraction']:.2f} ({c['view']} {c['index']})", file=sys.stderr, flush=True)
    write_report(args.outdir, settings, runs)
    montage(args.outdir / "montage.png", rows_for_montage)
    print(f"wrote {args.outdir / 'gallery.md'}, gallery.json and montage.png", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
