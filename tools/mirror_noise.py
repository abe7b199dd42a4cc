"""How large a mirror correlation would a real material give? Its spread, not only its mean.

``clsolid.metrics.mirror_chance`` is the mirror correlation a material like the exemplar is
expected to give; a single block scatters about it, and the fewer independent features a
block holds, the wider. This tool measures that scatter by Monte Carlo: Gaussian random
fields on the gallery's cube (toroidal), whose correlation in every vertical section
(any plane through the y axis) is the exemplar's, symmetrised in x, the same in every
direction about y: the material a two-view synthesis (front and right views sharing y)
should grow. Each field is scored with ``clsolid.metrics.mirror_correlation`` (each y-plane's
mean subtracted first, as the gallery does), giving the mean, the standard deviation, the
90th percentile and how often the gallery's mirror target, 0.1, is passed by the material
itself.

The covariance is built from the exemplar's periodic autocorrelation: at the lag
(dz, dy, dx), that of the exemplar at (dy, sqrt(dx^2 + dz^2)), interpolated along x; the
spectrum's negative values (the construction is not always positive definite) are set to
0. Threshold a field and the spread barely moves: binary fields thresholded at their median
scatter about as much as the Gaussian formula sqrt(2 sum rho^2 / N) predicts for Gaussian
fields of the same correlation.

With ``--gallery`` a gallery.json (tools/gallery.py) is read as well, and each exemplar's
worst mirror correlation is printed beside the spread, in standard deviations above the mean.

    python tools/mirror_noise.py                                   # every gallery exemplar, 64^2, 48^3
    python tools/mirror_noise.py --names porous50 tissue --side 96 --samples 64
    python tools/mirror_noise.py --gallery out/gallery/gallery.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from clsolid.gallery import gallery_exemplar, gallery_names
from clsolid.metrics import mirror_chance, mirror_correlation
from clsolid.metrics.symmetry import periodic_autocorrelation


def section_covariance(exemplar: np.ndarray, side: int) -> np.ndarray:
    """``(side,)*3`` correlation, toroidal lags: the exemplar's at (dy, horizontal distance)."""
    acf = periodic_autocorrelation(exemplar)  # the periodic exemplar, as mirror_chance takes it
    h, w = acf.shape
    d = np.arange(side)
    lag = np.minimum(d, side - d)
    signed = np.where(d <= side // 2, lag, -lag)
    horizontal = np.hypot(lag[:, None], lag[None, :])  # (dz, dx)
    cols = np.arange(w)
    out = np.empty((side, side, side))
    for j, dy in enumerate(signed):
        row = 0.5 * (acf[dy % h] + acf[dy % h][-cols % w])  # symmetric in dx
        out[:, j, :] = np.interp(horizontal, np.arange(w // 2 + 1), row[: w // 2 + 1], right=0.0)
    return out


def mirror_spread(exemplar: np.ndarray, side: int, samples: int = 32, seed: int = 0) -> np.ndarray:
    """The mirror correlations of *samples* Gaussian fields with the exemplar's section correlation."""
    amplitude = np.sqrt(np.maximum(np.real(np.fft.fftn(section_covariance(exemplar, side))), 0.0))
    rng = np.random.default_rng(seed)
    out = np.empty(samples)
    for i in range(samples):
        field = np.real(np.fft.ifftn(np.fft.fftn(rng.standard_normal((side,) * 3)) * amplitude))
        out[i] = mirror_correlation(field)
    return out


def worst_mirrors(path: Path) -> dict[str, float]:
    """Each exemplar's largest x <-> z mirror correlation over the seeds of a gallery.json."""
    runs = json.loads(path.read_text())["runs"]
    return {name: max(run["mirror"]["zx"] for run in seeds) for name, seeds in runs.items()}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--names", nargs="+", default=list(gallery_names()), choices=gallery_names())
    ap.add_argument("--size", type=int, default=64, help="exemplar side (64 or 128)")
    ap.add_argument("--side", type=int, default=48, help="cube side (the gallery's 48)")
    ap.add_argument("--samples", type=int, default=128)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--gallery", type=Path, help="a gallery.json whose mirror correlations to place in the spread")
    args = ap.parse_args(argv)
    worst = worst_mirrors(args.gallery) if args.gallery else {}
    print(f"x <-> z mirror correlation of {args.samples} Gaussian fields per exemplar, {args.size}^2 -> {args.side}^3")
    print("| exemplar | mirror_chance | mean | sd | 90th percentile | above 0.1 | volume's worst (sd above the mean) |")
    print("|---|---|---|---|---|---|---|")
    for name in args.names:
        ex = gallery_exemplar(name, args.size)
        r = mirror_spread(ex, args.side, args.samples, args.seed)
        mean, sd = r.mean(), r.std(ddof=1)
        seen = f"{worst[name]:.2f} ({(worst[name] - mean) / sd:+.1f})" if name in worst else "–"
        print(f"| {name} | {mirror_chance(ex, args.side):.3f} | {mean:.3f} | {sd:.3f} | "
              f"{np.quantile(r, 0.9):.3f} | {np.mean(r > 0.1):.0%} | {seen} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
