"""Benchmark of the search methods' exact matcher (clsolid.search.match), the brute force
that the search methods (wl, kopf, chen-wang) and their accelerated searches are measured
against.

Matches random queries (exemplar windows plus noise, as a half-synthesized volume gives)
against every complete neighbourhood of brick 64x64 at 32 grey levels, on the device and,
on a sample, with the NumPy float64 reference. Prints candidate distances per second, the
neighbourhood terms per second (3 flops a term: subtract, multiply, accumulate) and,
measured in the same run, NumPy's float32 matmul FLOP rate as the reference; then the
same search on phase codes (kopf's ``distance="weighted"``: brick at 4 levels, every square
term a weighted mismatch), as terms per second against the squared differences' rate. Timings
only: nothing here asserts on speed.

Then grows ch5_np_common (brick 64x64 at 32 levels -> 64^3, 7x7, 3 scales, 10 passes) with
each search method and each search (exact: every site; coherence: the k-coherence
candidates, clsolid.search.coherence), end to end, with the time per pass at each scale.
Their quality is compared on the gallery (tools/gallery.py --method kopf --set
search='"coherence"'), not here.

    python tools/bench_search.py                       # 7x7 (ch5_np_common), default device
    python tools/bench_search.py --neighborhood 11 --device pocl --methods kopf --searches exact
    python tools/bench_search.py --methods none        # the matcher alone
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from bench_ml import matmul_gflops

import clsolid
from clsolid.exemplar import builtin_exemplar, quantise
from clsolid.search.codes import phase_codes
from clsolid.search.match import CLMatcher, best_match_reference, exemplar_table


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--neighborhood", type=int, default=7, help="side of the square (default 7)")
    ap.add_argument("--queries", type=int, default=32768, help="queries per timed launch (default 32768)")
    ap.add_argument("--reference-queries", type=int, default=256,
                    help="queries the float64 reference times and checks (default 256)")
    ap.add_argument("--device", default=None)
    ap.add_argument("--methods", nargs="+", default=["wl", "kopf", "chen-wang"],
                    choices=["wl", "kopf", "chen-wang", "none"],
                    help="methods grown end to end (default wl kopf chen-wang; none: the matcher alone)")
    ap.add_argument("--searches", nargs="+", default=["exact", "coherence"], choices=["exact", "coherence"],
                    help="searches each method is grown with (default both)")
    ap.add_argument("--shape", type=int, default=64, help="side of the block grown end to end (default 64)")
    ap.add_argument("--iterations", type=int, default=10, help="passes per scale (default 10)")
    ap.add_argument("--exact-passes", type=int, default=None, metavar="N",
                    help="the coherence search's exhaustive first passes (default: the method's; kopf on brick 1)")
    ap.add_argument("--seed-components", type=int, default=None, metavar="N",
                    help="the principal components those passes compare (default: the method's; kopf 16; "
                         "0: every term)")
    args = ap.parse_args(argv)
    device = clsolid.select_device(args.device)
    k = args.neighborhood
    ex = quantise(builtin_exemplar("brick"), 32)
    table, _ = exemplar_table(ex, k)
    rng = np.random.default_rng(1)
    queries = table[rng.integers(0, table.shape[0], args.queries)] + rng.integers(-3, 4, (args.queries, k * k))
    ref = matmul_gflops()
    print(f"device: {device.name}")
    print(f"reference: NumPy float32 matmul {ref:.1f} GFLOP/s (best of 5, 2048^2)")
    print(f"brick 64x64, 32 levels, {k}x{k}: {table.shape[0]} candidate sites, {args.queries} queries")
    matcher = CLMatcher(device, table, max_batch=args.queries)
    best, got = _time_best(matcher, queries)
    pairs = args.queries * table.shape[0] / best
    terms = pairs * k * k
    print(f"device: {best * 1e3:.1f} ms; {pairs / 1e9:.2f} G candidate distances/s = {terms / 1e9:.2f} G terms/s "
          f"= {3 * terms / 1e9:.1f} GFLOP/s = {100 * 3 * terms / 1e9 / ref:.0f} % of matmul")
    # the same search on phase codes (kopf's distance="weighted"): brick at 4 levels, a fifth of the terms changed
    phases = quantise(builtin_exemplar("brick"), 4)
    codes = phase_codes(phases)
    coded, _ = exemplar_table(codes.encode(phases), k)
    q4 = coded[rng.integers(0, coded.shape[0], args.queries)]
    flip = rng.random(q4.shape) < 0.2
    q4[flip] = rng.choice(codes.codes, flip.sum())
    coded_s, _ = _time_best(CLMatcher(device, coded, max_batch=args.queries, mismatch=k * k), q4)
    coded_terms = args.queries * coded.shape[0] * k * k / coded_s
    print(f"phase codes (weighted mismatch, 4 phases): {coded_s * 1e3:.1f} ms; {coded_terms / 1e9:.2f} G terms/s "
          f"= {coded_terms / terms:.2f}x the squared differences' rate")
    n = min(args.reference_queries, args.queries)
    t = time.perf_counter()
    want, _ = best_match_reference(queries[:n], table)
    ref_s = time.perf_counter() - t
    print(f"float64 reference: {n * table.shape[0] / ref_s / 1e6:.1f} M candidate distances/s; "
          f"same site on {np.mean(got[:n] == want):.2%} of {n} queries")
    for method in [m for m in args.methods if m != "none"]:
        for search in args.searches:
            seeded = ({"exact_passes": args.exact_passes, "seed_components": args.seed_components}
                      if search == "coherence" else {})
            t = time.perf_counter()
            res = clsolid.synthesize("brick", (args.shape,) * 3, method=method, neighborhood=k, scales=3,
                                     iterations=args.iterations, search=search, rng=1, device=device,
                                     views=2, full_output=True, **seeded)  # the thesis's setting: two views
            total = time.perf_counter() - t
            levels = "; ".join(f"{'x'.join(map(str, lv['shape']))}: {lv['seconds'] / args.iterations:.2f} s a pass"
                               for lv in res.timings["levels"])
            terms = (f"{res.params['seed_components']} principal components" if res.params["seed_components"]
                     else "every term")
            exhaustive = (f", first {res.params['exact_passes']} pass(es) exhaustive on {terms}"
                          if search == "coherence" else "")
            print(f"{method}, {search} search{exhaustive}: brick 64x64, 32 levels -> {args.shape}^3, {k}x{k}, "
                  f"3 scales, {args.iterations} passes: {total:.1f} s end to end ({levels})", flush=True)


def _time_best(matcher: CLMatcher, queries: np.ndarray) -> tuple[float, np.ndarray]:
    """The best of three timings of ``matcher.best(queries)`` after a warm-up, and its sites."""
    matcher.best(queries[:64])  # warm: the build and first launch are not the search
    best = np.inf
    for _ in range(3):
        t = time.perf_counter()
        got, _ = matcher.best(queries)
        best = min(best, time.perf_counter() - t)
    return best, got


if __name__ == "__main__":
    main()
