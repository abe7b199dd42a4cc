"""Benchmark of the ML engine: the thesis case and its 7x7 variant, end to end.

Case (a) also runs the defaults at their own window (11x11, where the thesis case fixes 9x9).
Prints per-scale and per-sweep times, the Parzen kernel's inner-loop throughput
(neighbourhood terms per second; 3 flops a term: subtract, multiply, accumulate) and,
measured in the same run, NumPy's float32 matmul FLOP rate on this machine as the
reference. Timings only: nothing here asserts on speed.

    python tools/bench_ml.py                 # both cases, default device
    python tools/bench_ml.py --case a --device pocl --shape 64 64 64
    python tools/bench_ml.py --voxels-per-item 8      # OpenCL tuning, as synthesize(backend=...) takes it
    python tools/bench_ml.py --builds composite3 composite4   # the program's build, one exemplar after another
    python tools/bench_ml.py --colour fur --max-sweeps 2 5    # the TIP paper's colour case, and on luminance

Without tuning options it measures what synthesize() does by default.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np

import clsolid
from clsolid.ml.opencl import CLBackend
from clsolid.exemplar import builtin_exemplar, level_map, quantise
from clsolid.colour import luminance
from clsolid.gallery import colour_names, gallery_exemplar
from clsolid.ml.model import build_scale
from clsolid.core.slices import inserted_depths, seam_ratio
from clsolid.ml.params import DEFAULT_BANDWIDTH_FACTOR, MLParams

CASES = {"a": ("thesis case, 9x9", 9), "b": ("7x7 variant", 7)}


def matmul_gflops(n: int = 2048, repeats: int = 5) -> float:
    """Best-of-*repeats* float32 matmul rate of NumPy on this machine."""
    a = np.random.default_rng(0).random((n, n), dtype=np.float32)
    a @ a
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        a @ a
        best = min(best, time.perf_counter() - t)
    return 2 * n**3 / best / 1e9


def kernel_rate(device, labels, shape, k: int, factor: float | None, tuning: dict,
                repeats: int = 3) -> tuple[float, float]:
    """Terms/s of the Parzen kernel alone on one batch of full-resolution voxels (warm)."""
    params = MLParams(neighborhood=k, scales=1, bandwidth_factor=factor, views=2)  # the thesis case's two views
    model = build_scale(labels, shape, params, 0)
    rng = np.random.default_rng(0)
    vol = rng.choice(model.labels, size=model.shape)
    backend = CLBackend(device, **tuning)
    backend.start_scale(model, vol, np.full(model.shape, 0.5), params)
    voxels = np.arange(0, vol.size, max(1, vol.size // 8192))[:8192]
    backend.group_log_sums(voxels)  # build and first launch at this size
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        backend.group_log_sums(voxels)
        best = min(best, time.perf_counter() - t)
    terms = voxels.size * model.offsets.shape[0] * model.n_sites * model.patches.shape[0]
    return terms / best, best


class _TimedBuild(CLBackend):
    """A back end that adds up the time it spends getting its likelihood program: building it,
    or finding it built in the device's cache."""

    build_seconds = 0.0

    def _kernels(self, *args, **kwargs):
        start = time.perf_counter()
        try:
            return super()._kernels(*args, **kwargs)
        finally:
            self.build_seconds += time.perf_counter() - start


def build_times(device, names: list[str], tuning: dict, shape=(16, 16, 16)) -> list[tuple]:
    """``(name, program, first, again, programs on the device)`` for each 64x64 gallery exemplar in
    turn, with the parameters synthesize() resolves for it, at its finest scale: the seconds spent
    getting the likelihood program, relaxing a batch of voxels the first time (the runtime compiles
    each kernel at its first launch) and the same batch again. A different exemplar with the same
    options should find the program built and its kernels compiled."""
    rows = []
    for name in names:
        image = gallery_exemplar(name, 64)
        levels = level_map(image, 32)
        params = MLParams().for_exemplar(levels.values.size, levels.exact, seam_ratio(image), image.shape)
        model = build_scale(levels.labels, shape, params, 0)
        backend = _TimedBuild(device, **tuning)
        vol = np.random.default_rng(0).choice(model.labels, size=model.shape)
        backend.start_scale(model, vol, np.ones(model.shape), params)
        batch = np.arange(0, vol.size, 3)
        times = []
        for _ in range(2):
            start = time.perf_counter()
            backend.update(batch)
            backend.volume()  # waits for the launches
            times.append(time.perf_counter() - start)
        rows.append((name, backend.build_seconds, *times, len(device.programs)))
    return rows


#: The published relaxation (thesis): ICM, no balance, aligned +in slices; the defaults' cost is compared to it.
ICM = dict(relaxation="icm", balance=0.0, slice_layout="aligned", insert_slices=4)


def run_case(device, labels, shape, k: int, seed: int, factor: float | None, tuning: dict,
             method: dict | None = None) -> dict:
    r = clsolid.synthesize(labels.astype(np.uint16), shape, neighborhood=k, levels=32, rng=seed, views=2,
                           device=device, full_output=True, bandwidth_factor=factor, backend=tuning or None,
                           **(method or {}))  # the thesis case's two views
    return r.timings


def print_timings(label: str, timings: dict) -> None:
    print(f"  {label}:")
    for s in timings["scales"]:
        sweeps = " ".join(f"{t:.2f}" for t in s["sweep_seconds"])
        print(f"    scale {'x'.join(map(str, s['shape']))}: {s['sweeps']} sweeps, {s['seconds']:.1f} s "
              f"(per sweep: {sweeps}); h = {s['bandwidth']:.2f}, {s['n_sites']} exemplar sites, "
              f"{s['n_sets']} sets")
    print(f"    end to end: {timings['total_s']:.1f} s, {sum(s['sweeps'] for s in timings['scales'])} sweeps")


def print_header(device, tuning: dict) -> float:
    """Print the device, the tuning and the reference matmul rate (GFLOP/s), measured now; return the rate."""
    ref = matmul_gflops()
    print(f"device: {device.name}; tuning: {tuning or 'engine defaults'}")
    print(f"reference: NumPy float32 matmul {ref:.1f} GFLOP/s (best of 5, 2048^2)")
    return ref


#: The TIP paper's colour case (Urs et al., TIP 2014, §V): 64^2 colour -> 64^3, an 11x11 window,
#: 3 scales, simulated annealing.
COLOUR_CASE = dict(neighborhood=11, scales=3, relaxation="annealing")


def colour_quality(result) -> str:
    """The worst view's joint colour-histogram, patch and autocorrelation scores of a colour result."""
    from clsolid import metrics

    report = metrics.evaluate(result.exemplar, result.volume, reference_repeats=3, rng=0)
    worst = {}
    for row in report["summary"]:
        if row["score"] is not None:
            worst[row["metric"]] = max(worst.get(row["metric"], -np.inf), row["score"])
    return ", ".join(f"{k} {worst[k]:.2f}" for k in ("colour_histogram_kl", "patch_sw", "autocorrelation_l2")
                     if k in worst)


def colour_case(device, name: str, shape, seed: int, sweeps: list[int]) -> None:
    """The colour case on gallery exemplar *name*, end to end at the defaults' stop rule and at
    each of *sweeps* most sweeps a scale; then the same on the exemplar's luminance (grey)."""
    rgb = gallery_exemplar(name, 64)
    grey = np.clip(np.rint(luminance(rgb)), 0, 255).astype(np.uint8)
    print(f"\n== colour case: {name} 64x64 RGB -> {shape}, 11x11, 3 scales, annealing, 32 colours (TIP 2014, §V)")
    runs = {}
    for most in [None, *sweeps]:
        extra = {} if most is None else {"max_sweeps": most}
        r = clsolid.synthesize(rgb, shape, channel_axis=-1, rng=seed, device=device, full_output=True,
                               **COLOUR_CASE, **extra)
        runs[most] = r
        label = "the stop rule" if most is None else f"at most {most} sweeps a scale"
        print_timings(f"colour, {label}", r.timings)
        print(f"    quality (worst view): {colour_quality(r)}")
    colour = runs[None]
    same = colour.params["likelihood"]
    for label, extra in (("its defaults", {}), (f"the colour run's {same} sum", {"likelihood": same})):
        g = clsolid.synthesize(grey, shape, rng=seed, device=device, full_output=True, **COLOUR_CASE, **extra)
        print_timings(f"grey, the exemplar's luminance, {label} ({g.params['likelihood']})", g.timings)
        print(f"  joint colour costs {colour.timings['total_s'] / g.timings['total_s']:.2f} x grey at {label}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", choices=["a", "b", "both"], default="both")
    ap.add_argument("--shape", nargs=3, type=int, default=(64, 64, 64))
    ap.add_argument("--device", default=None)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--bandwidth-factor", type=float, default=None,
                    help=f"times Silverman's h (default {DEFAULT_BANDWIDTH_FACTOR}; 1 = the thesis)")
    ap.add_argument("--voxels-per-item", type=int, choices=(1, 2, 4, 8), default=None,
                    help="voxel-views per work item (default: the engine's)")
    ap.add_argument("--vector-width", type=int, choices=(4, 8, 16), default=None,
                    help="exemplar sites per vector (default: the engine's)")
    ap.add_argument("--no-icm", action="store_true", help="skip the ICM run the defaults are compared with")
    ap.add_argument("--builds", nargs="+", metavar="NAME", default=None,
                    help="only time getting the likelihood program (a build, or a find in the cache) for each of "
                         "these 64x64 gallery exemplars in turn, in one process, PoCL's disk cache fresh")
    ap.add_argument("--colour", choices=colour_names(), default=None, metavar="NAME",
                    help=f"only the colour case, on this colour gallery exemplar ({', '.join(colour_names())})")
    ap.add_argument("--max-sweeps", nargs="*", type=int, default=[], metavar="N",
                    help="the colour case also with at most N sweeps a scale (quality against sweeps)")
    args = ap.parse_args(argv)
    if args.colour:
        device = clsolid.select_device(args.device)
        print_header(device, {})
        colour_case(device, args.colour, tuple(args.shape), args.seed, args.max_sweeps)
        return
    tuning = {name: value for name, value in (("voxels_per_item", args.voxels_per_item),
                                              ("vector_width", args.vector_width)) if value is not None}
    if args.builds:  # PoCL's disk cache fresh, before the runtime starts: an earlier run's build would not count
        with tempfile.TemporaryDirectory(prefix="bench-ml-pocl-") as cache:
            os.environ["POCL_CACHE_DIR"] = cache
            device = clsolid.select_device(args.device)
            print_header(device, tuning)
            print("the likelihood program, each exemplar in turn (the options synthesize() resolves for it): "
                  "seconds to build it (or find it built), to relax a batch the first time and again")
            for name, program, first, again, programs in build_times(device, args.builds, tuning):
                print(f"  {name}: build {program:.3f} s, first batch {first:.3f} s, again {again:.3f} s; "
                      f"programs on the device: {programs}")
        return
    device = clsolid.select_device(args.device)
    labels = quantise(builtin_exemplar("brick"), 32)
    factor = MLParams(bandwidth_factor=args.bandwidth_factor).bandwidth_factor[0]  # as the engine resolves it
    shape = tuple(args.shape)
    ref = print_header(device, tuning)
    for case in (["a", "b"] if args.case == "both" else [args.case]):
        title, k = CASES[case]
        rate, dt = kernel_rate(device, labels, shape, k, args.bandwidth_factor, tuning)
        gflops = 3 * rate / 1e9
        print(f"\n== case ({case}) {title}: brick 64x64, 32 levels -> {shape}, 3 scales, 1/8, "
              f"re-synthesis, h2-product, xi=-3, 95%, 2 views, trusted +in slices "
              f"(defaults: {len(inserted_depths(shape, MLParams(views=2))['front'])} a view; "
              f"ICM: {ICM['insert_slices']}), "
              f"{factor:g} x Silverman")
        print(f"Parzen kernel: {rate / 1e9:.2f} G terms/s = {gflops:.1f} GFLOP/s at 3 flops/term "
              f"= {100 * gflops / ref:.0f}% of matmul ({dt * 1e3:.0f} ms for 8192 voxels x 2 views)")
        d = MLParams()
        timings = run_case(device, labels, shape, k, args.seed, args.bandwidth_factor, tuning)
        print_timings(f"defaults ({d.relaxation}, balance {d.balance:g}, {d.slice_layout} +in)", timings)
        if not args.no_icm:
            icm = run_case(device, labels, shape, k, args.seed, args.bandwidth_factor, tuning, ICM)
            print_timings("ICM, no balance, aligned +in (the thesis's relaxation)", icm)
            print(f"  the defaults cost {timings['total_s'] / icm['total_s']:.2f} x ICM")
        if case == "a" and d.neighborhood != k:  # what synthesize() does on this case, window included
            own = run_case(device, labels, shape, d.neighborhood, args.seed, args.bandwidth_factor, tuning)
            print_timings(f"defaults, their own {d.neighborhood}x{d.neighborhood} window", own)
            if not args.no_icm:
                print(f"  they cost {own['total_s'] / icm['total_s']:.2f} x ICM at {k}x{k}")


if __name__ == "__main__":
    main()
