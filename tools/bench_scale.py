"""Real sizes: the likelihood method's cost against exemplar and volume size,
with the exact and the pruned Parzen sum.

For each case (exemplar side : cube side) and likelihood, grows a gallery exemplar with the
defaults and reports the time end to end, the sweeps, and the cost per voxel visit at the
finest scale (it should stay flat as the cube grows; with the exact sum it grows with the
exemplar). A run that passes ``--budget`` seconds is stopped there, and its figures are
those of the sweeps it finished (marked "stopped"). NumPy's float32 matmul rate, measured in
the same run, is the machine's reference. Timings only: nothing here asserts on speed.
With ``--tile N`` every case runs again in tiles of N (clsolid.ml.tiled), and the table adds
its time and whether its volume is the one-piece run's (it must be). With ``--workers N`` as
well, every case runs a third time, its tiles on a Dask LocalCluster of N worker processes of
one thread each (clsolid.ml.distributed; started once, before the first case, and not timed),
and the table adds its time and whether its volume is the one-process tiled run's (it must be).

    python tools/bench_scale.py                                   # 64:64 and 128:128, both sums
    python tools/bench_scale.py --cases 256:256 --likelihoods pruned --budget 1800
    python tools/bench_scale.py --cases 50:64 --names porous50 --likelihoods pruned --tile 32
    python tools/bench_scale.py --cases 50:64 --names porous50 --likelihoods pruned --tile 32 --workers 2
    python tools/bench_scale.py --cases 64:512 --names porous50 --likelihoods pruned --tile 256 --tiled-only

``--scratch DIR`` keeps every tiled run's state in files in DIR (``scratch=``, clsolid.core.scratch).
``--tiled-only`` runs each case in tiles alone (for blocks whose one-piece run would take
as long again, or not fit the device); the table then shows the tiled run's figures.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import time

import numpy as np

import clsolid
from bench_ml import matmul_gflops
from clsolid.gallery import gallery_exemplar


class _Stop(Exception):
    """Raised from the progress callback when a run passes its budget."""


def run(image: np.ndarray, side: int, likelihood: str, budget: float, device, tile: int | None = None,
        client=None, verbose: bool = False, scratch=None, region: int = 0) -> dict:
    """Grow a *side*^3 cube (in tiles of *tile*, if given, on the workers of a Dask *client*, if
    given, their state in files in the folder *scratch*, if given, region by region if *region*);
    return the volume (None if stopped), the time, sweeps and finest-scale cost per voxel visit."""
    sweeps: list = []
    t0 = time.perf_counter()

    def progress(info) -> None:
        last = sweeps[-1]["elapsed"] if sweeps else 0.0
        sweeps.append({"scale": info.scale, "n_scales": info.n_scales, "visited": info.visited,
                       "elapsed": info.elapsed, "seconds": info.elapsed - last})
        if verbose:
            print(f"  scale {info.scale}/{info.n_scales} sweep {info.sweep}: {info.elapsed - last:.1f} s, "
                  f"{info.visited} visits, {info.elapsed:.0f} s in all, ETA {info.eta:.0f} s", file=sys.stderr, flush=True)
        if time.perf_counter() - t0 > budget:
            raise _Stop

    stopped, volume = False, None
    backend = {k: v for k, v in (("tile", tile), ("client", client), ("scratch", scratch if tile else None))
               if v is not None}
    options = {"region": region} if region else {}
    try:
        volume = clsolid.synthesize(image, (side,) * 3, rng=1, device=device, likelihood=likelihood,
                                    progress=progress, backend=backend, **options)
    except _Stop:
        stopped = True
    finest = [s for s in sweeps if s["scale"] == s["n_scales"]]
    visits = sum(s["visited"] for s in finest)
    return {"volume": volume, "seconds": time.perf_counter() - t0, "stopped": stopped, "sweeps": len(sweeps),
            "finest_sweeps": len(finest),
            "per_visit_us": 1e6 * sum(s["seconds"] for s in finest) / visits if visits else float("nan")}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", nargs="+", default=["64:64", "128:128"], metavar="EX:CUBE",
                    help="exemplar side (64-256) and cube side (default 64:64 128:128)")
    ap.add_argument("--names", nargs="+", default=["porous50", "gravel"], help="gallery exemplars")
    ap.add_argument("--likelihoods", nargs="+", default=["exact", "pruned"], choices=("exact", "pruned"))
    ap.add_argument("--budget", type=float, default=900.0, help="seconds after which a run is stopped (900)")
    ap.add_argument("--device", default=None)
    ap.add_argument("--tile", type=int, default=None, metavar="N",
                    help="also run every case in tiles of N voxels a side, and compare the volumes")
    ap.add_argument("--verbose", action="store_true", help="print every sweep (to stderr) as it ends")
    ap.add_argument("--tiled-only", action="store_true",
                    help="with --tile: run each case in tiles only, not also in one piece")
    ap.add_argument("--scratch", default=None, metavar="DIR",
                    help="with --tile: every tiled run keeps its state in files in DIR (scratch=)")
    ap.add_argument("--region", type=int, default=0, metavar="N",
                    help="every run visits the block region by region, cubes of N voxels (region=; default 0: "
                         "set by set)")
    ap.add_argument("--workers", type=int, default=None, metavar="N",
                    help="with --tile: also run every case's tiles on a Dask LocalCluster of N worker processes")
    args = ap.parse_args(argv)
    if (args.workers is not None or args.scratch is not None) and args.tile is None:
        ap.error("--workers and --scratch need --tile")
    if args.tiled_only and (args.tile is None or args.workers is not None):
        ap.error("--tiled-only needs --tile, and runs no Dask workers")
    with contextlib.ExitStack() as stack:
        client = None
        if args.workers is not None:
            from clsolid.ml.distributed import dask_client

            client = stack.enter_context(dask_client(workers=args.workers))
        table(args, client)


def seconds(r: dict) -> str:
    """A run's time, marked where its budget stopped it."""
    return f"{r['seconds']:.1f}{' (stopped)' if r['stopped'] else ''}"


def same(a, b) -> str:
    """Whether two runs' volumes are identical ("?" where one was stopped)."""
    return "?" if a["volume"] is None or b["volume"] is None else ("yes" if np.array_equal(a["volume"], b["volume"])
                                                                     else "NO")


def table(args, client) -> None:
    """Run every case (in tiles, on the *client*'s workers, as asked) and print the table."""
    device = clsolid.select_device(args.device)
    print(f"{device.name}; matmul reference {matmul_gflops():.1f} GFLOP/s (float32, NumPy, this run)")
    tiled = "" if args.tile is None or args.tiled_only else f" tiles of {args.tile}: time (s) | same volume |"
    if client is not None:
        tiled += f" the tiles on {args.workers} Dask workers: time (s) | same volume as tiled |"
    print(f"| exemplar | case | likelihood | time (s) | sweeps (finest) | finest scale, us per voxel visit |{tiled}")
    print("|---|---|---|---|---|---|" + "---|---|" * tiled.count("time (s)"))
    for case in args.cases:
        ex_side, cube = (int(v) for v in case.split(":"))
        for name in args.names:
            image = gallery_exemplar(name, ex_side)
            for likelihood in args.likelihoods:
                first = args.tile if args.tiled_only else None  # the run the row's first columns describe
                case_name = f"{ex_side}² → {cube}³" + (f", tiles of {args.tile}" if args.tiled_only else "")
                r = run(image, cube, likelihood, args.budget, device, first, verbose=args.verbose, scratch=args.scratch,
                        region=args.region)
                row = (f"| {name} | {case_name} | {likelihood} | {seconds(r)} | "
                       f"{r['sweeps']} ({r['finest_sweeps']}) | {r['per_visit_us']:.1f} |")
                if args.tile is not None and not args.tiled_only:
                    t = run(image, cube, likelihood, args.budget, device, args.tile, scratch=args.scratch, region=args.region)
                    row += f" {seconds(t)} | {same(r, t)} |"
                    if client is not None:
                        w = run(image, cube, likelihood, args.budget, device, args.tile, client, scratch=args.scratch,
                                region=args.region)
                        row += f" {seconds(w)} | {same(t, w)} |"
                print(row, flush=True)


if __name__ == "__main__":
    main()
