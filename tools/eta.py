"""How right the progress ETA is (its aim: within 20 % after the first sweep of the finest
scale).

Grows each exemplar with the defaults (or --set NAME=VALUE), records the ETA reported after
every sweep, and compares it with the time the run then actually took. Prints, per
exemplar, the error after the first finest-scale sweep and the largest error over the
finest scale's sweeps (positive: the ETA said more time than was left).

    python tools/eta.py                                  # brick, porous50, gravel at 64^3
    python tools/eta.py --names hrtem --shape 48 --set relaxation='"icm"'
    python tools/eta.py --replay-terms 0     # as on blocks too large to replay (512^3 and up)
    python tools/eta.py --names gravel --size 128 --shape 128   # a grey exemplar whose first sweeps search
"""

from __future__ import annotations

import argparse
import json
import time

import clsolid
from clsolid.gallery import gallery_exemplar
from clsolid.ml import forecast


def measure(name: str, shape: int, seed: int, device, options: dict, size: int | None = None) -> dict:
    """One run's (scale, sweep, elapsed, eta) reports and the ETA's relative errors on the finest
    scale; the gallery's exemplar at *size* if given (else brick, grass and gravel whole, the rest at 64)."""
    image = name if size is None and name in ("brick", "grass", "gravel") else gallery_exemplar(name, size or 64)
    reports = []
    t0 = time.perf_counter()
    clsolid.synthesize(image, (shape,) * 3, rng=seed, device=device,
                       progress=lambda i: reports.append((i.scale, i.n_scales, i.sweep, time.perf_counter() - t0, i.eta)),
                       **options)
    end = time.perf_counter() - t0
    finest = [r for r in reports if r[0] == r[1]]
    errors = [(eta - (end - at)) / (end - at) for _, _, _, at, eta in finest[:-1]]  # the last: nothing left
    return {"name": name, "seconds": end, "sweeps": len(finest), "first": errors[0] if errors else None,
            "worst": max(errors, key=abs) if errors else None}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--names", nargs="+", default=["brick", "porous50", "gravel"])
    ap.add_argument("--shape", type=int, default=64, help="cube side (default 64)")
    ap.add_argument("--size", type=int, default=None,
                    help="the gallery's exemplars at this side (default: brick, grass, gravel whole, the rest 64)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--device", default=None)
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                    help="a synthesize option, the value as JSON (repeatable)")
    ap.add_argument("--replay-terms", type=float, default=None,
                    help="replay a scale's temperatures only up to this many neighbour terms a sweep "
                         f"(default the library's, {forecast.REPLAY_TERMS:.3g}; 0: never, the fallback ETA)")
    args = ap.parse_args(argv)
    options = {k: json.loads(v) for k, v in (s.split("=", 1) for s in args.set)}
    device = clsolid.select_device(args.device)
    library = forecast.REPLAY_TERMS
    if args.replay_terms is not None:
        forecast.REPLAY_TERMS = args.replay_terms
    try:
        print(f"device: {device.name}; {args.shape}^3, seed {args.seed}, settings {options or 'defaults'}, "
              f"replayed up to {forecast.REPLAY_TERMS:.3g} terms a sweep")
        for name in args.names:
            r = measure(name, args.shape, args.seed, device, options, args.size)
            first = "–" if r["first"] is None else f"{100 * r['first']:+.0f} %"
            worst = "–" if r["worst"] is None else f"{100 * r['worst']:+.0f} %"
            print(f"{name}: {r['seconds']:.1f} s, {r['sweeps']} finest sweeps; ETA error after the first: {first}, "
                  f"worst on the finest scale: {worst}", flush=True)
    finally:
        forecast.REPLAY_TERMS = library

if __name__ == "__main__":
    main()
