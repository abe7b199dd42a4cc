"""An exemplar per view against one exemplar, on anisotropic ground truths.

Each ground truth (clsolid.groundtruth: ``aniso2``, ``aniso3``, correlation lengths 3, 6 and
12 voxels along z, y and x) is cut into its three central sections. Volumes are grown from
all three, each its view's own exemplar, and, for comparison, from the front section alone
in every view. Each view of each volume is scored against that view's own section (patch
and autocorrelation scores, 0 = as close as two halves of the section, 1 = as far as
shuffled pixels; the +in slices left out), and the volume's correlation length along each
axis against the real volume's. Writes OUTDIR/per_view.md, OUTDIR/per_view.json and a
montage (OUTDIR/per_view.png: per row, the sections and the volume's three slices).

    python tools/per_view.py -o results/per_view                      # ml and kopf, seeds 1 2
    python tools/per_view.py --methods ml --seeds 1 --side 64 --shape 48 -o results/pv
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
from clsolid.api import inserted_slices
from clsolid.core.views import VIEW_ORDER, view_set
from clsolid.exemplar import nearest_level_index
from clsolid.groundtruth import ground_truth, sections
from clsolid.metrics._common import jsonable
from clsolid.preview import render_preview

MODES = ("per view", "front only")
SCORES = (("patch_sw", "patch"), ("autocorrelation_l2", "autocorr"))


def _labels(res: Any) -> np.ndarray:
    """The volume in level indices (a blend of ``wl`` counts for its nearest level)."""
    if res.labels is not None:
        return res.labels
    return nearest_level_index(res.volume, res.level_values).reshape(res.volume.shape)


def measure(res: Any, cuts: dict[str, np.ndarray], real_lengths: tuple[float, ...]) -> dict[str, Any]:
    """Each view's scores against its own section, and the correlation lengths along z, y, x."""
    vol = _labels(res)
    levels = np.asarray(res.level_values, np.float64)
    slices = inserted_slices(res.params, vol.shape)
    scores = {}
    for view in VIEW_ORDER:
        own = nearest_level_index(cuts[view].astype(np.float64), levels).reshape(cuts[view].shape)
        report = metrics.evaluate(own, vol, views=[view], reference_repeats=3, rng=0, exclude=slices)
        row = {r["metric"]: r["score"] for r in report["summary"]}
        scores[view] = {key: row.get(key) for key, _ in SCORES}
    lengths = metrics.correlation_lengths(vol, np.arange(levels.size))
    errors = [float(g / r - 1.0) for g, r in zip(lengths, real_lengths)]
    return {"scores": scores, "lengths": list(lengths), "length_error": errors}


def _fmt(x: float | None) -> str:
    return "-" if x is None else f"{x:.2f}"


def _worst(runs: list[dict], view: str, key: str) -> float | None:
    values = [r["scores"][view][key] for r in runs if r["scores"][view][key] is not None]
    return max(values) if values else None


def markdown(rows: list[dict]) -> str:
    """One row per ground truth, method and mode: the worst seed's scores per view, the mean
    correlation-length errors; * marks a miss (score above 0.3, length off by more than 10 %)."""
    head = ["| truth | method | exemplars | " + " | ".join(f"{v} patch / autocorr" for v in VIEW_ORDER)
            + " | length error z / y / x (%) | s per volume |", "|---" * 8 + "|"]
    lines = []
    for row in rows:
        cells = []
        for view in VIEW_ORDER:
            pair = [_worst(row["runs"], view, key) for key, _ in SCORES]
            cells.append(" / ".join(_fmt(v) + ("*" if v is not None and v > 0.3 else "") for v in pair))
        err = np.mean([r["length_error"] for r in row["runs"]], axis=0)
        lengths = " / ".join(f"{100 * e:+.0f}{'*' if abs(e) > 0.1 else ''}" for e in err)
        seconds = np.mean([r["seconds"] for r in row["runs"]])
        lines.append(f"| {row['truth']} | {row['method']} | {row['mode']} | " + " | ".join(cells)
                     + f" | {lengths} | {seconds:.0f} |")
    return "\n".join(head + lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--names", nargs="+", default=["aniso2", "aniso3"])
    p.add_argument("--methods", nargs="+", default=["ml", "kopf"])
    p.add_argument("--seeds", nargs="+", type=int, default=[1, 2])
    p.add_argument("--side", type=int, default=64, help="the real volumes' side, so the sections' (default 64)")
    p.add_argument("--shape", type=int, default=48, help="the grown blocks' side (default 48)")
    p.add_argument("--truth-seed", type=int, default=0, help="the ground truths' seed (default 0)")
    p.add_argument("--device", default=None)
    p.add_argument("-o", "--outdir", required=True)
    args = p.parse_args(argv)
    out = Path(args.outdir)
    out.mkdir(parents=True, exist_ok=True)
    rows, montage = [], []
    for name in args.names:
        real = ground_truth(name, args.side, seed=args.truth_seed)
        cuts = {v: np.ascontiguousarray(c) for v, c in sections(real).items()}
        real_lengths = metrics.correlation_lengths(real, np.unique(real))
        for method in args.methods:
            for mode in MODES:
                exemplar = cuts if mode == "per view" else cuts["front"]
                runs = []
                for seed in args.seeds:
                    t = time.perf_counter()
                    res = clsolid.synthesize(exemplar, (args.shape,) * 3, method=method, rng=seed,
                                             device=args.device, full_output=True)
                    seconds = time.perf_counter() - t
                    runs.append({"seed": seed, "seconds": seconds, **measure(res, cuts, real_lengths)})
                    print(f"{name} {method} {mode} seed {seed}: {seconds:.0f} s, lengths "
                          f"{np.round(runs[-1]['lengths'], 2)} against {np.round(real_lengths, 2)}", file=sys.stderr)
                    if seed == args.seeds[0]:
                        shown = res.exemplar if isinstance(res.exemplar, dict) else {"front": res.exemplar}
                        montage.append(render_preview(shown, res.volume, name=f"{name} {method} {mode}",
                                                      constrained=view_set(res.params["views"]),
                                                      cube=False, min_side=96).image)
                rows.append({"truth": name, "method": method, "mode": mode, "real_lengths": list(real_lengths),
                             "runs": runs})
    table = markdown(rows)
    (out / "per_view.md").write_text(table + "\n")
    (out / "per_view.json").write_text(json.dumps(jsonable({"settings": vars(args), "rows": rows}), indent=1))
    width = max(m.shape[1] for m in montage)
    stacked = np.vstack([np.pad(m, ((0, 0), (0, width - m.shape[1])), constant_values=255) for m in montage])
    Image.fromarray(stacked).save(out / "per_view.png")
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
