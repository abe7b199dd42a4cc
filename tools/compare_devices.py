"""Do two OpenCL runtimes grow the same volume? Same exemplar, settings and seed on every device.

Each device that compiles grows the block once (the default: the thesis case, brick 64^2
at 32 levels -> 64^3); the table gives, for every pair, the share of identical voxels and
the mean absolute level difference, plus each device's time and calibrated scores. Two
compilers (PoCL's LLVM and Intel's) agreeing is evidence that the kernels are portable.

    python tools/compare_devices.py                       # thesis case, seed 1
    python tools/compare_devices.py --shape 32 32 32 --seed 4 --set neighborhood=7
"""

from __future__ import annotations

import argparse
import itertools
import time

import numpy as np

import clsolid
from clsolid.exemplar import builtin_exemplar, level_map
from quality_ml import METRICS, parse_setting, scores  # beside this script (tools/ is on the path when it runs)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--shape", nargs=3, type=int, default=(64, 64, 64))
    ap.add_argument("--exemplar", default="brick")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--set", dest="settings", action="append", type=parse_setting, default=[],
                    metavar="NAME=VALUE", help="a synthesize() keyword, repeatable")
    args = ap.parse_args(argv)
    options = dict(args.settings)
    labels = level_map(builtin_exemplar(args.exemplar), options.get("levels", 32)).labels
    devices = [d for d in clsolid.list_devices() if d["compiles"]]
    print(f"{args.exemplar} -> {tuple(args.shape)}, seed {args.seed}, options {options or 'defaults'}")
    volumes = {}
    for d in devices:
        t = time.perf_counter()
        vol = clsolid.synthesize(labels, tuple(args.shape), rng=args.seed, device=d["index"], output="labels",
                                 **options)
        seconds = time.perf_counter() - t
        volumes[d["index"]] = vol
        s = scores(labels, vol)
        cells = "  ".join(f"{m}={s[('front', m)]:.2f}/{s[('right', m)]:.2f}" for m in METRICS
                          if s.get(("front", m)) is not None)
        print(f"{d['index']}  {d['platform']} / {d['name']} (vector width {d['vector_width']}): "
              f"{seconds:.1f} s; {cells}")
    for a, b in itertools.combinations(volumes, 2):
        va, vb = volumes[a].astype(int), volumes[b].astype(int)
        print(f"{a} vs {b}: {np.mean(va == vb):.2%} identical voxels, "
              f"mean |difference| {np.abs(va - vb).mean():.3f} levels")
    if len(volumes) < 2:
        print("only one device compiles here: nothing to compare")


if __name__ == "__main__":
    main()
