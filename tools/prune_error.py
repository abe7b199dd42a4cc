"""How far is the pruned likelihood from the exact one, in a real run?

Grows each exemplar with ``likelihood="pruned"`` on an OpenCL device. Before the first
conflict-free set of every sweep, a sample of that set's voxels is read back (volume,
temperatures, sources) and their LCPDFs are computed in float64 both ways: exact (every
site) and pruned (the candidate sets and site sample the kernel uses, ``clsolid.ml.pruned``). Reported per
scale and sweep: the share of visits the pruned sum serves, and over the voxels it serves,
the total-variation distance between the two normalised combined LCPDFs (the product over
views, what Gibbs draws from: 0 the same, 1 disjoint), the largest error of the log LCPDF
on labels the exact one gives at least 1 %, and how often the most probable label is the same.

    python tools/prune_error.py                         # porous50, composite3, gravel, brick at 48^3
    python tools/prune_error.py --names hrtem --shape 32 --set prune_similar=4
    python tools/prune_error.py --names hrtem gravel --pca 24 64     # and K = 64 candidates found by PCA
    python tools/prune_error.py --names hrtem --pca 24 64 --probe 8  # ... in the 8 nearest lists of sites

The run takes the parameters ``synthesize`` would (``MLParams.for_exemplar``: the fall-off on
grey exemplars, the mismatch distances on categorical ones), with the pruned sum everywhere.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from clsolid.core.device import select_device
from clsolid.core.slices import seam_ratio
from clsolid.exemplar import builtin_exemplar, level_map
from clsolid.gallery import gallery_exemplar
from clsolid.ml import pruned
from clsolid.ml.driver import run_ml
from clsolid.ml.model import ScaleModel
from clsolid.ml.opencl import CLBackend
from clsolid.ml.params import MLParams
from clsolid.ml.reference import normalise, parzen, site_distances


class _Probe(CLBackend):
    """A back end that measures a sample of the first set of each sweep before relaxing it."""

    def __init__(self, device, sample: int, pca: tuple[int, int] | None = None, probe: int = 0):
        super().__init__(device)
        self.sample, self.rows, self.rng, self.pca, self.probe = sample, [], np.random.default_rng(0), pca, probe

    def start_scale(self, model: ScaleModel, vol, temp, params, sources=None, parent=None) -> None:
        self.sweep, self.tag = -1, None  # start_scale's own start_sweep is not a sweep
        super().start_scale(model, vol, temp, params, sources, parent)
        self.pruning = pruned.Pruning(model, params)
        self.projected = None if self.pca is None else pruned.ProjectedWindows.of(model, self.pca[0], self.probe)

    def start_sweep(self, seed, tag, t_in, bias, relaxation=None) -> None:
        super().start_sweep(seed, tag, t_in, bias, relaxation)
        self.fresh = tag != self.tag
        self.seed = seed
        if self.fresh:
            self.tag, self.sweep = tag, self.sweep + 1
            self.before = (self.exact_visits, self.pruned_visits)

    def update(self, voxels) -> None:
        if self.fresh and self.sweep > 0:
            self.fresh = False
            self.rows.append(self._measure(voxels))
        super().update(voxels)

    def _measure(self, voxels) -> dict:
        m = self.model
        vol, temp = np.array(self.volume(), np.float64), np.array(self.temperature(), np.float64)
        src = np.array(self.sources())
        part = self.rng.choice(voxels, min(self.sample, voxels.size), replace=False)
        part = part[~self.pruning.exact(temp, src, part)]
        row = {"level": m.level, "sweep": self.sweep, "measured": int(part.size)}
        if part.size == 0:
            return row
        exact, cut, projected = [], [], []
        for v in range(m.offsets.shape[0]):
            a = site_distances(m, vol, temp, part, v)
            keep = self.pruning.weights(src, self.seed, self.tag, part, v)
            exact.append(normalise(parzen(m, a)))
            cut.append(normalise(parzen(m, a, keep)))
            if self.projected is not None:  # the exact terms of the K sites nearest by projection
                projected.append(normalise(parzen(m, a, self.projected.nearest(m, vol, part, v, self.pca[1]))))
        pe, pc = (np.exp(normalise(np.sum(x, axis=0))) for x in (exact, cut))
        log_err = np.abs(np.log(np.maximum(pc, 1e-300)) - np.log(np.maximum(pe, 1e-300)))  # read where pe >= 0.01
        row.update(tv=0.5 * np.abs(pc - pe).sum(axis=1), log_err=np.where(pe >= 0.01, log_err, 0).max(axis=1),
                   same=pc.argmax(1) == pe.argmax(1))
        if projected:
            pp = np.exp(normalise(np.sum(projected, axis=0)))
            row.update(tv_pca=0.5 * np.abs(pp - pe).sum(axis=1), same_pca=pp.argmax(1) == pe.argmax(1))
        return row


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--names", nargs="+", default=["porous50", "composite3", "gravel", "brick"])
    ap.add_argument("--shape", type=int, default=48)
    ap.add_argument("--sample", type=int, default=300, help="voxels measured per sweep (default 300)")
    ap.add_argument("--device", default=None)
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                    help="an MLParams field, the value as JSON (repeatable), e.g. prune_similar=4")
    ap.add_argument("--pca", type=int, nargs=2, default=None, metavar=("DIMS", "K"),
                    help="also measure the exact terms of the K sites nearest by the distance projected on the "
                         "exemplar windows' first DIMS principal axes (grey exemplars; clsolid.ml.pruned."
                         "ProjectedWindows)")
    ap.add_argument("--probe", type=int, default=0, metavar="P",
                    help="with --pca: search only the P lists of sites whose centres are nearest (about sqrt(sites) "
                         "lists, clsolid.ml.pruned.site_lists; default 0: every site)")
    args = ap.parse_args(argv)
    options = {k: json.loads(v) for k, v in (s.split("=", 1) for s in args.set)}
    params = MLParams(**{"likelihood": "pruned", **options})
    device = select_device(args.device)
    print(f"{args.shape}^3, seed 1, likelihood='pruned', prune_similar={params.n_similar}, "
          f"prune_min_weight={params.prune_min_weight}; {device.name}")
    for name in args.names:
        image = builtin_exemplar(name) if name in ("brick", "grass", "gravel") else gallery_exemplar(name, 64)
        probe = _Probe(device, args.sample, None if args.pca is None else tuple(args.pca), args.probe)
        levels = level_map(image, params.levels)
        run_params = params.for_exemplar(levels.values.size, levels.exact, seam_ratio(image))  # as synthesize
        t = time.perf_counter()
        run_ml(levels.labels, (args.shape,) * 3, run_params, 1, probe)
        print(f"{name}: {time.perf_counter() - t:.1f} s (with the measuring), visits: "
              f"{probe.pruned_visits / max(1, probe.pruned_visits + probe.exact_visits):.0%} pruned")
        for r in probe.rows:
            if not r["measured"]:
                print(f"  scale {r['level']} sweep {r['sweep']}: every sampled voxel summed exactly")
                continue
            print(f"  scale {r['level']} sweep {r['sweep']}: {r['measured']:>3} pruned voxels, TV {r['tv'].mean():.4f} "
                  f"(99 %: {np.quantile(r['tv'], 0.99):.3f}), log error {r['log_err'].mean():.4f} "
                  f"(max {r['log_err'].max():.3f}), same mode {r['same'].mean():.1%}"
                  + (f"; PCA: TV {r['tv_pca'].mean():.4f} (99 %: {np.quantile(r['tv_pca'], 0.99):.3f}), "
                     f"same mode {r['same_pca'].mean():.1%}" if "tv_pca" in r else ""), flush=True)
        tv = np.concatenate([r["tv"] for r in probe.rows if r["measured"]] or [np.zeros(0)])
        if tv.size:
            print(f"  all sweeps: TV {tv.mean():.4f} (99 %: {np.quantile(tv, 0.99):.3f}) over {tv.size} voxels")


if __name__ == "__main__":
    main()
