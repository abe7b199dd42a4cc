"""``clsolid validate``: grow volumes from a real 3D volume's section and compare them with it
in 3D, along every axis: a table, a JSON report and a plot of S2 per axis."""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
from typing import Any

from ..api import METHODS
from ..core.options import names, refuse_unknown
from ..errors import InputError
from .config import read_config
from .outputs import check_writable


def add_validate(sub: Any) -> argparse.ArgumentParser:
    """The ``validate`` subcommand's parser on the subparsers *sub*."""
    p = sub.add_parser("validate", help="compare generated volumes with a real 3D volume, in 3D",
                       description="Hand a generator the real volume's central front section (or its three "
                                   "sections), grow volumes, and "
                                   "compare their 3D properties (per phase: fraction, surface area, S2 per axis, "
                                   "connected fraction, tortuosity factor) with the real volume's and with its "
                                   "own spread over sub-volumes of the same size.")
    p.add_argument("real", metavar="REAL3D", help="the real 3D volume, segmented, grey or RGB (Z, Y, X[, 3]) (.npy, .tif)")
    p.add_argument("--method", default=None, choices=tuple(METHODS), help="the generator (default: ml, or the config's)")
    p.add_argument("-n", type=int, default=3, help="volumes to grow (default 3)")
    p.add_argument("--shape", type=int, nargs=3, metavar=("Z", "Y", "X"), default=None,
                   help="their shape (default: half the real volume's on each axis)")
    p.add_argument("--seed", type=int, default=0, help="the first volume's seed (default 0)")
    p.add_argument("--device", default=None, help="OpenCL device, as for synth")
    p.add_argument("--sections", default="front", choices=("front", "all"),
                   help="hand the generator the central front section (default), or all three, each its view's "
                        "own exemplar (anisotropic materials; ml)")
    p.add_argument("--classes", type=int, default=2, help="phases to cut a grey or colour real volume into (default 2)")
    p.add_argument("--config", metavar="FILE.toml", default=None, help="the method's options from a TOML file")
    p.add_argument("--no-tortuosity", action="store_true", help="skip the tortuosity factors (the slowest part)")
    p.add_argument("-o", "--output", metavar="REPORT.json", help="write the full report as JSON")
    p.add_argument("--plot", metavar="S2.png", help="plot S2 per axis, real band against generated (needs matplotlib)")
    p.add_argument("-q", "--quiet", action="store_true", help="print the table only")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    return p


def run_validate(args: argparse.Namespace) -> int:
    """Run ``clsolid validate`` with parsed arguments; errors are
    :class:`~clsolid.errors.ClsolidError` subclasses."""
    from ..report import _require_matplotlib, load_volume
    from ..validation import format_validation, plot_validation, validate

    if args.plot:
        _require_matplotlib()
    for flag, path in (("--output", args.output), ("--plot", args.plot)):
        if path is not None:
            check_writable(flag, pathlib.Path(path))
    options: dict[str, Any] = {}
    if args.config is not None:
        path = pathlib.Path(args.config)
        if path.suffix.lower() != ".toml":
            raise InputError(f"--config {path} must be a .toml file of the method's options")
        options = read_config(path)
    method = options.pop("method", None)
    method = args.method or method or "ml"
    if not isinstance(method, str) or method not in METHODS:
        raise InputError(f"method {method!r} is not available; use one of {tuple(METHODS)}")
    # only the method's options: a run's own arguments (exemplar, shape, seed) are validate's to give
    refuse_unknown(options, [n for n in names(METHODS[method]) if n != "method"], f"--config {args.config}")
    try:
        real = load_volume(args.real)
    except OSError as exc:
        raise InputError(str(exc)) from exc
    say = None if args.quiet else (lambda line: print(line, file=sys.stderr))
    report = validate(real, method=method, n=args.n, shape=tuple(args.shape) if args.shape else None,
                      seed=args.seed, device=args.device, classes=args.classes, tortuosity=not args.no_tortuosity,
                      sections=args.sections, progress=say, **options)
    report["real"]["file"] = str(args.real)
    print(format_validation(report))
    if args.output:
        with open(args.output, "w", encoding="utf-8") as fh:
            json.dump(report, fh, indent=1)
        print(f"report written to {args.output}")
    if args.plot:
        plot_validation(report, args.plot)
        print(f"plot written to {args.plot}")
    return 0
