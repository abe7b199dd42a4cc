"""Hold the generators to the field's 3D validation on generated ground truths.

For each ground truth (clsolid.groundtruth) and method: grow N volumes from the real
volume's central front section with `clsolid.validation.validate` and summarise, per
phase, the errors against the real volume (fraction in points, surface area relative,
the largest S2 gap per axis in percent of the fraction, tortuosity relative per axis) and
which of the targets hold. Writes OUTDIR/validation.md (one table) and one JSON report per
ground truth and method.

    python tools/validate_truths.py -o results/validation                    # iso2, iso3, particles; ml and kopf
    python tools/validate_truths.py --names iso2 --methods ml --side 64 -n 2 -o results/v64
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from clsolid.groundtruth import ground_truth, ground_truth_info
from clsolid.validation import format_validation, validate

#: A side per ground truth: the particles need room for particles 20-40 voxels across.
SIDES = {"iso2": 96, "iso3": 96, "aniso2": 96, "aniso3": 96, "particles": 128}


def _cell(values: list, fmt: str, met: list | None) -> str:
    marks = [("" if m else "*") for m in (met or [True] * len(values))]
    return " / ".join(f"{v:{fmt}}{mark}" if v is not None else f"inf{mark}" for v, mark in zip(values, marks))


def _lengths(report: dict) -> str:
    """The correlation length's relative errors along z, y and x, in percent; * past 10 %."""
    errors = report.get("correlation_length", {}).get("error") or []
    return " / ".join("-" if e is None else f"{100 * e:+.0f}{'*' if abs(e) > 0.1 else ''}" for e in errors) or "-"


def summary_rows(name: str, method: str, report: dict) -> list[str]:
    """One Markdown row per phase: the errors, and * after each that misses its target."""
    rows = []
    for key, r in report["phases"].items():
        tau = r.get("tortuosity")
        rows.append(
            f"| {name} | {method} | {key} | {r['fraction']['real']:.3f} | "
            f"{100 * r['fraction']['error']:.2f}{'' if r['fraction']['met'] else '*'} | "
            f"{100 * r['surface_area']['error']:.1f}{'' if r['surface_area']['met'] else '*'} | "
            f"{_cell(r['s2']['error'], '.1f', r['s2']['met'])} | "
            f"{_cell([100 * e if e is not None else None for e in tau['error']], '.0f', tau['met']) if tau else '-'} | "
            f"{_lengths(report)} |")
    return rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--names", nargs="+", default=["iso2", "iso3", "particles"])
    p.add_argument("--methods", nargs="+", default=["ml", "kopf"])
    p.add_argument("--side", type=int, default=None, help="the real volumes' side (default: per ground truth)")
    p.add_argument("-n", type=int, default=3, help="volumes per ground truth and method (default 3)")
    p.add_argument("--seed", type=int, default=0, help="the ground truths' seed (default 0)")
    p.add_argument("--device", default=None)
    p.add_argument("--sections", default="front", choices=("front", "all"),
                   help="the central front section for every view, or each view its own (default front)")
    p.add_argument("-o", "--outdir", required=True)
    args = p.parse_args(argv)
    out = Path(args.outdir)
    out.mkdir(parents=True, exist_ok=True)
    lines = ["| truth | method | phase | fraction | fraction error (points) | surface area error (%) | "
             "S2 error z / y / x (% of fraction) | tortuosity error z / y / x (%) | "
             "correlation length error z / y / x (%) |", "|---" * 9 + "|"]
    for name in args.names:
        side = args.side or SIDES[name]
        real = ground_truth(name, side, seed=args.seed)
        for method in args.methods:
            start = time.perf_counter()
            report = validate(real, method=method, n=args.n, device=args.device, sections=args.sections,
                              progress=lambda line: print(f"  {line}", file=sys.stderr))
            report["real"]["ground_truth"] = {"name": name, "side": side, "seed": args.seed,
                                              "about": ground_truth_info(name).description}
            report["seconds"] = time.perf_counter() - start
            (out / f"{name}-{method}{'' if args.sections == 'front' else '-' + args.sections}.json").write_text(json.dumps(report, indent=1))
            print(f"{name} {side}^3, {method}, {report['seconds']:.0f} s")
            print(format_validation(report))
            lines += summary_rows(name, method, report)
    lines += ["", "A * marks an error that misses its target (fraction 1 point, surface area 5 %, S2 5 % of the "
              "fraction or inside the real band, tortuosity 10 % for phases over 25 %)."]
    (out / "validation.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
