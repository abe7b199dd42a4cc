"""Quality of the ML engine over several seeds: calibrated scores of the constrained views.

Grows the thesis case (brick 64x64, 32 levels -> 64^3, 9x9, 3 scales, 1/8, re-synthesis,
h2-product, xi=-3, 95 %, 2 views) once per seed and prints, per view, the calibrated
scores of :func:`clsolid.metrics.evaluate` (0: as close as two halves of the exemplar,
1: no more structure than shuffled pixels or uniform noise). Scores vary a lot from
seed to seed, so judge a change by several seeds, not one.

    python tools/quality_ml.py                          # seeds 1 2 3, defaults
    python tools/quality_ml.py --seeds 1 2 3 4 --set bandwidth_factor=0.5
    python tools/quality_ml.py --shape 32 32 32 --set neighborhood=7 --save out/q
"""

from __future__ import annotations

import argparse
import ast
import time
from pathlib import Path

import numpy as np

import clsolid
from clsolid import metrics
from clsolid.exemplar import builtin_exemplar, quantise

METRICS = ("histogram_kl", "autocorrelation_l2", "orientation_kl", "patch_sw")
VIEWS = ("front", "right")


def parse_setting(text: str) -> tuple[str, object]:
    """``name=value`` with *value* a Python literal (numbers, strings, tuples)."""
    name, sep, value = text.partition("=")
    if not sep or not name:
        raise argparse.ArgumentTypeError(f"{text!r} is not name=value")
    try:
        return name, ast.literal_eval(value)
    except (ValueError, SyntaxError):
        return name, value


def scores(labels: np.ndarray, volume: np.ndarray) -> dict[tuple[str, str], float]:
    report = metrics.evaluate(labels, volume, views=VIEWS, reference_repeats=3)
    return {(r["view"], r["metric"]): r["score"] for r in report["summary"]}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", nargs="+", type=int, default=[1, 2, 3])
    ap.add_argument("--shape", nargs=3, type=int, default=(64, 64, 64))
    ap.add_argument("--exemplar", default="brick")
    ap.add_argument("--device", default=None)
    ap.add_argument("--set", dest="settings", action="append", type=parse_setting, default=[],
                    metavar="NAME=VALUE", help="a synthesize() keyword, repeatable")
    ap.add_argument("--save", type=Path, help="write each volume as SAVE_seed<N>.npy")
    args = ap.parse_args(argv)
    options = dict(args.settings)
    labels = quantise(builtin_exemplar(args.exemplar), options.get("levels", 32))
    device = clsolid.select_device(args.device)
    print(f"{args.exemplar} -> {tuple(args.shape)}, options {options or 'defaults'}, device {device.name}")
    print("seed  " + "  ".join(f"{m[:14]:>14s}" for m in METRICS) + "   (front/right)   seconds")
    table = []
    for seed in args.seeds:
        t = time.perf_counter()
        vol = clsolid.synthesize(labels.astype(np.uint16), tuple(args.shape), rng=seed, device=device, **options)
        seconds = time.perf_counter() - t
        if args.save:
            args.save.parent.mkdir(parents=True, exist_ok=True)
            np.save(f"{args.save}_seed{seed}.npy", vol)
        s = scores(labels, vol)
        table.append([[s.get((v, m)) for v in VIEWS] for m in METRICS])
        cells = "  ".join(f"{_fmt(s.get(('front', m)))}/{_fmt(s.get(('right', m)))}".rjust(14) for m in METRICS)
        print(f"{seed:4d}  {cells}   {seconds:8.1f}")
    arr = np.array(table, dtype=float)
    columns = [arr[:, i][np.isfinite(arr[:, i])] for i in range(len(METRICS))]  # a metric may be unmeasurable
    print("mean  " + "  ".join(_fmt(c.mean() if c.size else None).rjust(14) for c in columns))
    print("worst " + "  ".join(_fmt(c.max() if c.size else None).rjust(14) for c in columns))


def _fmt(x) -> str:
    return "  -" if x is None else f"{x:.2f}"


if __name__ == "__main__":
    main()
