"""``clsolid evaluate``: compare a volume with its exemplar, print a table, write JSON and a PNG."""

from __future__ import annotations

import argparse
import json
import pathlib
from typing import Any

from ..errors import InputError
from ..metrics import VIEWS, evaluate
from .outputs import check_writable


def add_evaluate(sub: Any) -> argparse.ArgumentParser:
    """The ``evaluate`` subcommand's parser on the subparsers *sub*."""
    p = sub.add_parser("evaluate", help="compare a volume's slices with an exemplar",
                       description="Objective statistics between a 2D exemplar and the slices of a volume.")
    p.add_argument("exemplar", nargs="?", metavar="EXEMPLAR", help="2D exemplar image (.npy, .tif/.tiff, .png)")
    p.add_argument("volume", nargs="?", metavar="VOLUME", help="3D (Z, Y, X) volume (.npy, .tif/.tiff)")
    for view, plane in (("front", "(y, x)"), ("right", "(y, z)"), ("top", "(z, x)")):
        p.add_argument(f"--{view}", metavar="IMAGE", default=None,
                       help=f"the {view} view's own exemplar, the {plane} plane: with an exemplar per view, give "
                            "VOLUME alone and each view is compared with its own")
    p.add_argument("--views", nargs="+", choices=VIEWS, default=list(VIEWS),
                   help="views to report (default: all three)")
    p.add_argument("--constrained", nargs="*", choices=VIEWS, default=None,
                   help="views the synthesis constrained, for labelling (default: as VOLUME's sidecar records; "
                        "without one, the views with an exemplar of their own, else all three)")
    p.add_argument("--levels", type=int, default=None,
                   help="quantise both into this many grey levels before the histogram statistics (default: as "
                        "`clsolid synth` made VOLUME, read from its JSON sidecar; without one, the grey levels "
                        "as they are)")
    p.add_argument("-o", "--output", metavar="REPORT.json", help="write the full report as JSON")
    p.add_argument("--plot", metavar="REPORT.png", help="draw the report as a PNG (needs matplotlib)")
    p.add_argument("--track", metavar="TRACK.json", help="a convergence track to summarise (and plot with --plot)")
    p.add_argument("--max-slices", type=int, default=16, help="slices per view, evenly spaced (default 16; 0 = all)")
    p.add_argument("--keep-inserted", action="store_true",
                   help="measure the +in (or anchor) slices too; by default those of a `clsolid synth` volume, "
                        "read from its JSON sidecar, are left out: they start as exemplar copies and would "
                        "flatter their view's scores")
    p.add_argument("--repeats", type=int, default=5, help="random halves and shuffles per reference (default 5; "
                                                          "0 = none)")
    p.add_argument("--seed", type=int, default=0, help="seed of the references (default 0)")
    p.add_argument("--non-periodic", action="store_true", help="the volume does not wrap around (default: it does)")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    return p


def run_evaluate(args: argparse.Namespace) -> int:
    """Run ``clsolid evaluate`` with parsed arguments; its errors are :class:`~clsolid.errors.ClsolidError`
    subclasses (their exit statuses: :data:`clsolid.errors.EXIT_CODES`)."""
    from ..report import _require_matplotlib

    if args.plot:
        _require_matplotlib()
    for flag, path in (("--output", args.output), ("--plot", args.plot)):
        if path is not None:
            check_writable(flag, pathlib.Path(path))
    try:
        if args.exemplar is not None or args.volume is not None or args.track is None:
            _run_evaluation(args)
        if args.track is not None:
            _run_track(args)
    except OSError as exc:  # a file that vanished or cannot be read: the user's to fix
        raise InputError(str(exc)) from exc
    return 0


def _run_evaluation(args: argparse.Namespace) -> None:
    from ..report import (
        format_table,
        inserted_from_sidecar,
        like_with_like,
        load_exemplar,
        load_volume,
        plot_report,
        read_sidecar,
    )

    per_view = {v: getattr(args, v) for v in VIEWS if getattr(args, v) is not None}
    if per_view:
        if args.volume is not None:
            raise InputError(f"EXEMPLAR {args.exemplar!r} and {', '.join('--' + v for v in per_view)} both given: "
                             "with an exemplar per view give VOLUME alone")
        args.volume, args.exemplar = args.exemplar, None
        if args.volume is None:
            raise InputError("VOLUME is required")
    elif args.exemplar is None or args.volume is None:
        raise InputError("EXEMPLAR and VOLUME are both required (or give only --track FILE.json)")
    if args.max_slices is not None and args.max_slices < 0:
        raise InputError(f"--max-slices={args.max_slices} must be >= 0 (0 = all slices)")
    exemplar = ({v: load_exemplar(path) for v, path in per_view.items()} if per_view
                else load_exemplar(args.exemplar))
    volume = load_volume(args.volume)
    sidecar, meta = read_sidecar(args.volume)
    levels = args.levels
    if levels is None:
        exemplar, levels, note = like_with_like(exemplar, sidecar, meta)
        if note:
            print(note)
    exclude: dict = {}
    if not args.keep_inserted:
        exclude, note = inserted_from_sidecar(sidecar, meta, volume.shape)
        if note:
            print(note)
    constrained = args.constrained
    if constrained is None:
        constrained = _constrained(meta, per_view)
    report = evaluate(exemplar, volume, views=args.views, constrained=constrained,
                      levels=levels, max_slices=args.max_slices or None, rng=args.seed,
                      reference_repeats=args.repeats, periodic=not args.non_periodic, exclude=exclude)
    report["files"] = {"exemplar": ({v: str(p) for v, p in per_view.items()} if per_view else str(args.exemplar)),
                       "volume": str(args.volume)}
    print(format_table(report))
    if args.output:
        with open(args.output, "w", encoding="utf-8") as fh:
            json.dump(report, fh, indent=1, allow_nan=False)
        print(f"report written to {args.output}")
    if args.plot:
        plot_report(report, args.plot)
        print(f"plot written to {args.plot}")


def _constrained(meta: dict | None, per_view: dict) -> tuple[str, ...]:
    """The views a synthesis constrained: as its sidecar records them, else those with an
    exemplar of their own, else all three (``clsolid synth``'s default)."""
    from ..core.views import view_set

    recorded = view_set((meta or {}).get("params", {}).get("views")) if isinstance(meta, dict) else None
    return recorded or tuple(per_view) or VIEWS


def _run_track(args: argparse.Namespace) -> None:
    from ..report import format_track, load_track, plot_track

    track = load_track(args.track)
    print(format_track(track))
    if args.plot:
        path = pathlib.Path(args.plot)
        if args.exemplar is not None:  # the report took --plot: the track goes next to it
            path = path.with_name(f"{path.stem}_track{path.suffix or '.png'}")
        plot_track(track, path)
        print(f"track plot written to {path}")
