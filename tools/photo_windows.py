"""What does the real material score? Windows of the photograph an exemplar was cut from,
or of new draws of a generated exemplar's material.

brick, grass and gravel are the top-left quarter of a scikit-image photograph (512^2),
tissue another quarter of one, area-averaged 4x to 64^2. The whole photograph at that
scale (128^2, ``clsolid.gallery.gallery_photograph``) holds more of the same wall, lawn or
tissue: windows of it, of a volume's slice size, at seeded offsets that stay inside it,
rounded as the exemplar is, are stacked like a volume's front slices and scored against
the 64^2 exemplar with
``clsolid.metrics.evaluate``, as tools/gallery.py scores a volume. Their scores are what
the material itself gets from the metrics, the level a synthesis cannot be asked to beat
(windows from the exemplar's own quarter overlap it; ``--away`` keeps them to the other
three quarters' corner, which shows how far the photograph is from stationary).

The gallery's generated exemplars (porous50 ... hrtem) have no photograph but a generator:
their windows come from ``--draws`` new draws of it (``clsolid.gallery.gallery_draw``), the
same number from each, scored against the ``--size`` exemplar. A volume's slices a few
voxels apart show the same features, so a stack of 16 of its slices holds only a few
independent pieces of material: 4 draws (the default) stands for that, 16 for slices that
are all independent.

    python tools/photo_windows.py                       # brick, grass, gravel, tissue; 48^2 and 96^2
    python tools/photo_windows.py --names brick --sides 48 --seeds 1 2 3
    python tools/photo_windows.py --names composite3 fibres --size 128 --sides 64   # new draws
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from clsolid import metrics
from clsolid.gallery import (gallery_draw, gallery_exemplar, gallery_info, gallery_names, gallery_photograph,
                             grey_levels)

#: The gallery's exemplars that have a generator to draw again.
GENERATED = tuple(n for n in gallery_names() if gallery_info(n).seed is not None)
#: The gallery's exemplars cut from a photograph.
PHOTOGRAPHED = tuple(n for n in gallery_names() if gallery_info(n).seed is None)

#: The scores printed: (key in clsolid.metrics.evaluate's summary, column title).
SCORES = (("histogram_kl", "hist"), ("patch_sw", "patch"), ("autocorrelation_l2", "autocorr"), ("s2_l2", "S2"),
          ("c2_l2", "C2"))
#: Windows of new draws stacked per score, as tools/gallery.py scores 16 slices of a view.
COUNT = 16


def windows(photo: np.ndarray, side: int, count: int, seed: int, away: bool = False) -> np.ndarray:
    """*count* ``side``-square windows of *photo* at seeded offsets inside it, stacked (count, side, side).
    With *away*, only windows whose top-left corner lies in the far half of both axes."""
    rng = np.random.default_rng(seed)
    low = [n // 2 if away else 0 for n in photo.shape]
    if any(n - side < lo for n, lo in zip(photo.shape, low)):
        raise SystemExit(f"windows of {side} do not fit in the photograph's {'far corner' if away else 'side'}")
    rows = rng.integers(low[0], photo.shape[0] - side + 1, count)
    cols = rng.integers(low[1], photo.shape[1] - side + 1, count)
    return np.stack([photo[r: r + side, c: c + side] for r, c in zip(rows, cols)])


def drawn_windows(name: str, size: int, side: int, draws: int, seed: int) -> np.ndarray:
    """:data:`COUNT` *side*-square windows of *draws* new draws of a generated exemplar's
    material at *size* (``gallery_draw``, draws numbered from ``seed * draws + 1``), as
    evenly spread over the draws as the count allows (the first draws take one more)."""
    share = np.full(draws, COUNT // draws)
    share[: COUNT % draws] += 1
    return np.concatenate([windows(gallery_draw(name, size, seed * draws + 1 + j), side, int(n), seed)
                           for j, n in enumerate(share) if n])


def scores(exemplar: np.ndarray, stack: np.ndarray) -> dict[str, float]:
    """The calibrated scores of a stack of front slices against the exemplar."""
    report = metrics.evaluate(exemplar, stack, views=["front"], constrained=["front"], rng=0)
    return {row["metric"]: row["score"] for row in report["summary"] if row["score"] is not None}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--names", nargs="+", default=list(PHOTOGRAPHED), choices=PHOTOGRAPHED + GENERATED)
    ap.add_argument("--sides", nargs="+", type=int, default=[48, 96], help="window sides (a volume's slice size)")
    ap.add_argument("--seeds", nargs="+", type=int, default=[1, 2])
    ap.add_argument("--away", action="store_true", help="windows from the quarter farthest from the exemplar")
    ap.add_argument("--size", type=int, default=64, help="the exemplar's side (64 or 128; a photograph is twice it)")
    ap.add_argument("--draws", type=int, default=4, help="generated exemplars: new draws a stack's windows come from")
    args = ap.parse_args(argv)
    if not 1 <= args.draws <= COUNT:
        ap.error(f"--draws must be 1 to {COUNT} (the windows of a stack)")
    print("| exemplar | window | seed | " + " | ".join(title for _, title in SCORES) + " |")
    print("|---|---|---|" + "---|" * len(SCORES))
    for name in args.names:
        generated = name in GENERATED
        exemplar = gallery_exemplar(name, args.size)
        if not generated:  # the whole photograph at the exemplar's scale, rounded as the exemplar is
            photo = grey_levels(gallery_photograph(name, args.size))
        for side in args.sides:
            if generated and side > args.size:
                ap.error(f"a window of {side} does not fit a draw of {args.size}")
            for seed in args.seeds:
                stack = (drawn_windows(name, args.size, side, args.draws, seed) if generated
                         else windows(photo, side, side, seed, args.away))  # as many windows as their side
                got = scores(exemplar, stack)
                cells = " | ".join("–" if key not in got else f"{got[key]:.2f}" for key, _ in SCORES)
                print(f"| {name} | {side}² | {seed} | {cells} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
