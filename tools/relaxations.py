"""Compare relaxations (and the balance term) on one exemplar: label fractions, calibrated
scores, sweeps and seconds, one line per setting and seed.

The exemplar is a built-in name or ``3phase``: a 64x64 smoothed Gaussian field cut into
three phases of 50, 30 and 20 % (a segmented micrograph's stand-in, made with NumPy).
Each ``--run`` is a set of synthesize() keywords; the default runs compare ICM, Gibbs and
annealing, without and with ``balance``.

    python tools/relaxations.py                               # 3phase, 32^3, 5x5, 2 scales
    python tools/relaxations.py --exemplar brick --seeds 1 2 --run relaxation=gibbs,balance=1
"""

from __future__ import annotations

import argparse
import ast
import json
import time

import numpy as np

import clsolid
from clsolid import metrics
from clsolid.exemplar import builtin_exemplar, quantise

METRICS = ("histogram_kl", "autocorrelation_l2", "patch_sw")
DEFAULT_RUNS = ("", "relaxation=gibbs", "relaxation=annealing", "balance=1", "relaxation=gibbs,balance=1",
                "relaxation=annealing,balance=1")


def three_phase(n: int = 64, seed: int = 0) -> np.ndarray:
    """Phases 0, 1, 2 covering 50, 30 and 20 % of a smoothed (sigma 3 px, periodic) Gaussian field."""
    from scipy import ndimage

    field = ndimage.gaussian_filter(np.random.default_rng(seed).standard_normal((n, n)), 3, mode="wrap")
    return np.digitize(field, np.quantile(field, [0.5, 0.8])).astype(np.uint8)


def parse_run(text: str) -> dict:
    """``name=value,name=value`` (Python literals, else strings) -> synthesize() keywords."""
    out = {}
    for item in filter(None, text.split(",")):
        name, sep, value = item.partition("=")
        if not sep:
            raise argparse.ArgumentTypeError(f"{item!r} is not name=value")
        try:
            out[name] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            out[name] = value
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--exemplar", default="3phase", help="3phase, or a built-in name (32 levels)")
    ap.add_argument("--shape", nargs=3, type=int, default=(32, 32, 32))
    ap.add_argument("--neighborhood", type=int, default=5)
    ap.add_argument("--scales", type=int, default=2)
    ap.add_argument("--seeds", nargs="+", type=int, default=[1, 2, 3])
    ap.add_argument("--run", dest="runs", action="append", type=parse_run, default=None,
                    metavar="NAME=VALUE,...", help="one setting to compare, repeatable")
    ap.add_argument("--device", default=None)
    args = ap.parse_args(argv)
    runs = args.runs or [parse_run(r) for r in DEFAULT_RUNS]
    if args.exemplar == "3phase":
        labels, levels = three_phase(), 3
    else:
        labels, levels = quantise(builtin_exemplar(args.exemplar), 32), 32
    wanted = np.bincount(labels.ravel(), minlength=levels) / labels.size
    device = clsolid.select_device(args.device)
    print(f"{args.exemplar} -> {tuple(args.shape)}, {args.neighborhood}x{args.neighborhood}, {args.scales} scales, "
          f"device {device.name}")
    print(f"exemplar fractions {np.round(wanted, 3).tolist()}" if levels <= 4 else
          "fractions: total variation distance to the exemplar's histogram")
    print("setting  seed  fractions  " + "  ".join(METRICS) + "  (front/right mean)  sweeps  seconds")
    for options in runs:
        for seed in args.seeds:
            t = time.perf_counter()
            r = clsolid.synthesize(labels, tuple(args.shape), neighborhood=args.neighborhood, scales=args.scales,
                                   levels=levels, rng=seed, device=device, full_output=True, **options)
            seconds = time.perf_counter() - t
            got = np.bincount(r.volume.ravel(), minlength=levels) / r.volume.size
            fractions = np.round(got, 3).tolist() if levels <= 4 else f"TV {0.5 * np.abs(got - wanted).sum():.3f}"
            report = metrics.evaluate(labels, r.volume, views=("front", "right"), reference_repeats=3)
            score = {m: [s["score"] for s in report["summary"] if s["metric"] == m and s["score"] is not None]
                     for m in METRICS}
            cells = "  ".join(f"{np.mean(v):.2f}" if v else "-" for v in score.values())
            print(f"{json.dumps(options)}  {seed}  {fractions}  {cells}  "
                  f"{[s['sweeps'] for s in r.timings['scales']]}  {seconds:.1f}", flush=True)


if __name__ == "__main__":
    main()
