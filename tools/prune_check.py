"""Can the likelihood be pruned, and at what candidate count?

The Parzen LCPDF of a voxel sums over every exemplar site. This measures, in float64, how
far the LCPDF moves when the sum keeps only the K sites whose neighbourhoods are nearest to
the voxel's: the best any candidate set of that size can do (a k-coherence or PCA-bounded
set can only approach it), found here by brute force.

A volume is grown with the defaults; then, on sampled voxels of the finished block (or of
noise drawn from the exemplar's pixels, ``--block noise``: what a first sweep sees) and in
each constrained view, the normalised LCPDFs are compared: the total-variation distance
between exact and pruned (0: the same, 1: disjoint), and how often their most probable
level is the same. Nothing here is a pruned synthesis: it says whether one can match the
exact likelihood, and at what candidate count.

    python tools/prune_check.py                        # porous50, brick, gravel: 48^3, 2000 voxels
    python tools/prune_check.py --names hrtem --counts 16 64 256 1024
    python tools/prune_check.py --names gravel hrtem grass --counts 16 64 --pca 16 24   # found by PCA

``--pca D`` finds each K sites by a cheaper distance instead: between the windows' projections
on the exemplar windows' first D principal axes (D multiply-adds a site instead of one per
window term), then sums their exact terms, as a pruned likelihood with such candidates would.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

import clsolid
from clsolid.gallery import gallery_exemplar
from clsolid.ml.model import build_scale
from clsolid.ml.params import MLParams
from clsolid.ml.pruned import ProjectedWindows, smallest
from clsolid.ml.reference import normalise, parzen, site_distances


def site_terms(model, vol: np.ndarray, voxels: np.ndarray, view: int, temperature: float) -> np.ndarray:
    """``(m, n)``: each voxel's neighbourhood distance to every site, as the engine's reference
    computes it (fall-off and phase costs included), every neighbour at *temperature*."""
    return site_distances(model, vol, np.full(vol.shape, temperature), voxels, view)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--names", nargs="+", default=["porous50", "brick", "gravel"])
    ap.add_argument("--shape", type=int, default=48)
    ap.add_argument("--voxels", type=int, default=2000, help="sampled voxels (default 2000)")
    ap.add_argument("--counts", type=int, nargs="+", default=[16, 64, 256], help="K for nearest K")
    ap.add_argument("--device", default=None)
    ap.add_argument("--block", choices=("grown", "noise"), default="grown",
                    help="measure on the finished block (default) or on noise drawn from the exemplar's "
                         "pixels (a first sweep's worst case)")
    ap.add_argument("--temperature", type=float, default=0.0,
                    help="every neighbour's temperature t (weight 1 - t; default 0, a finished block; "
                         "a scale starts near 1)")
    ap.add_argument("--pca", type=int, nargs="+", default=[], metavar="DIMS",
                    help="also keep the K sites nearest by the distance projected on the exemplar windows' first "
                         "DIMS principal axes (the exact terms of those sites), for each DIMS")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                    help="a synthesize option, the value as JSON (repeatable), e.g. bandwidth_factor=1")
    args = ap.parse_args(argv)
    options = {k: json.loads(v) for k, v in (s.split("=", 1) for s in args.set)}
    print(f"{args.shape}^3 grown with {options or 'the defaults'}, seed 1; {args.block} block, neighbours at "
          f"t = {args.temperature}; {args.voxels} voxels sampled; per view, "
          "TV distance of the normalised LCPDF (mean, 99th percentile) and same most probable level")
    for name in args.names:
        image = name if name in ("brick", "grass", "gravel") else gallery_exemplar(name, 64)
        res = clsolid.synthesize(image, (args.shape,) * 3, rng=1, device=args.device, full_output=True, **options)
        params = MLParams.from_dict(res.params)
        model = build_scale(res.exemplar_labels, res.volume.shape, params, 0)
        vol = res.labels.astype(np.float64)  # level indices, as the engine works on them
        if args.block == "noise":
            vol = np.random.default_rng(1).choice(res.exemplar_labels.ravel(), vol.shape).astype(np.float64)
        n = model.n_sites
        if args.pca and model.mismatch:
            raise SystemExit(f"--pca needs squared differences: {name} is compared by mismatches")
        searches = {dims: ProjectedWindows.of(model, dims) for dims in args.pca}
        voxels = np.random.default_rng(0).choice(vol.size, min(args.voxels, vol.size), replace=False)
        lines = []
        for view in range(model.offsets.shape[0]):
            tv = {(k, dims): [] for dims in (None, *args.pca) for k in args.counts}
            same = {key: [] for key in tv}
            for part in np.array_split(voxels, max(1, voxels.size // 200)):  # (200, labels, sites) at a time
                a = site_terms(model, vol, part, view, args.temperature)
                p_exact = np.exp(normalise(parzen(model, a)))
                for key in tv:
                    k, dims = key
                    keep = smallest(a, k) if dims is None else searches[dims].nearest(model, vol, part, view, k)
                    p = np.exp(normalise(parzen(model, a, keep)))  # the exact terms of the sites kept
                    tv[key].append(0.5 * np.abs(p - p_exact).sum(axis=1))
                    same[key].append(p.argmax(1) == p_exact.argmax(1))
            for (k, dims), t in tv.items():
                t = np.concatenate(t)
                how = "nearest" if dims is None else f"PCA {dims:>2}, nearest"
                lines.append(f"  view {view}, {how} {k:>4}: TV {t.mean():.3f} (99 %: {np.quantile(t, 0.99):.3f}), "
                             f"same level {np.mean(np.concatenate(same[(k, dims)])):.1%}")
        print(f"{name} ({n} sites, bandwidth {model.bandwidth:.3g}):")
        print("\n".join(lines), flush=True)


if __name__ == "__main__":
    main()
