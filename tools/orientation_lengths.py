"""How far the orientation stays alike: the exemplar's against the volume's constrained views.

The thesis found synthetic fringes longer and straighter than the exemplar's (Urs thesis,
§6.3.3). This measures that gap: each gallery exemplar's orientation correlation lengths
along y and x (:func:`clsolid.metrics.orientation_correlation_lengths`: how far the local
orientation, coherence weighted, stays alike) against the same lengths over the slices of
each constrained view of a grown volume (the +in slices left out), as ratios: 1 the
exemplar's, above 1 orientation that wanders less than the material's. A view's rows are
y (front, right) or z (top); its columns x (front, top) or z (right).

    python tools/orientation_lengths.py                                   # hrtem lamellae channels, ml and wl
    python tools/orientation_lengths.py --names hrtem --methods ml kopf --seeds 1 2 3 --size 128 --shape 96
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

import numpy as np

import clsolid
from clsolid import metrics
from clsolid.api import inserted_slices
from clsolid.core.views import view_set
from clsolid.gallery import gallery_exemplar


def measure(exemplar: np.ndarray, volume: np.ndarray, views: tuple[str, ...], skip: dict) -> dict[str, Any]:
    """The exemplar's lengths, and each view's lengths and ratios to them."""
    ex = metrics.orientation_correlation_lengths(exemplar.astype(np.float64))
    out: dict[str, Any] = {"exemplar": ex}
    for view in views:
        got = metrics.orientation_correlation_lengths(metrics.view_slices(volume, view, exclude=skip.get(view, ())),
                                                      periodic=True)
        out[view] = {"lengths": got, "ratios": tuple(g / e for g, e in zip(got, ex))}
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--names", nargs="+", default=["hrtem", "lamellae", "channels"], help="gallery exemplars")
    parser.add_argument("--methods", nargs="+", default=["ml", "wl"], help="methods to compare")
    parser.add_argument("--seeds", nargs="+", type=int, default=[1], help="seeds")
    parser.add_argument("--size", type=int, default=64, help="exemplar side (default 64)")
    parser.add_argument("--shape", type=int, default=48, help="cube side (default 48)")
    parser.add_argument("--device", default=None, help="OpenCL device")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="a method option (a number, or a string)")
    args = parser.parse_args(argv)
    options = {}
    for item in args.set:
        key, _, value = item.partition("=")
        try:
            options[key] = int(value) if value.lstrip("-").isdigit() else float(value)
        except ValueError:
            options[key] = value
    print("orientation correlation length (pixels, y/x) of each exemplar, and per view of each volume the ratio "
          "to it (rows/columns; 1: the exemplar's, >1: longer, straighter)")
    print(f"{'exemplar':10} {'method':10} {'seed':>4}  {'exemplar y/x':>13}  views (rows/cols ratio)  time")
    for name in args.names:
        exemplar = gallery_exemplar(name, args.size)
        for method in args.methods:
            for seed in args.seeds:
                t0 = time.perf_counter()
                res = clsolid.synthesize(exemplar, (args.shape,) * 3, method=method, rng=seed, device=args.device,
                                         full_output=True, **options)
                seconds = time.perf_counter() - t0
                views = view_set(res.params["views"])
                skip = inserted_slices(res.params, res.volume.shape)
                m = measure(exemplar, np.asarray(res.volume, np.float64), views, skip)
                ex = "/".join(f"{v:.1f}" for v in m["exemplar"])
                cells = "  ".join(f"{view} {m[view]['ratios'][0]:.2f}/{m[view]['ratios'][1]:.2f}" for view in views)
                print(f"{name:10} {method:10} {seed:>4}  {ex:>13}  {cells}  {seconds:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
