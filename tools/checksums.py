"""Checksum every gallery volume, to show that a change leaves what clsolid computes as it was.

Grows each gallery exemplar (64^2 by default) into a small block with each method and seed,
and prints one SHA-256 (of dtype, shape and bytes) per volume as a Markdown table. Run it
before and after a change on the same device and compare the two tables; ``--compare``
does the comparison and exits 1 on any difference.

    python tools/checksums.py -o results/before.md
    python tools/checksums.py -o results/after.md --compare results/before.md
"""

from __future__ import annotations

import argparse
import hashlib
import sys
import time
from pathlib import Path

import numpy as np

import clsolid
from clsolid.gallery import gallery_exemplar, gallery_names


def checksum(volume: np.ndarray) -> str:
    """SHA-256 of a volume's dtype, shape and bytes (the first 16 hex digits)."""
    digest = hashlib.sha256(f"{volume.dtype.str}{volume.shape}".encode())
    digest.update(np.ascontiguousarray(volume).tobytes())
    return digest.hexdigest()[:16]


def read_table(path: Path) -> dict[tuple[str, str, str], str]:
    """``(exemplar, method, seed) -> checksum`` from a table this script wrote."""
    rows = {}
    for line in path.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and cells[0] not in ("exemplar", "---") and not set(cells[0]) <= {"-"}:
            rows[tuple(cells[:3])] = cells[3]
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--names", nargs="+", default=None, help="gallery exemplars (default: all)")
    parser.add_argument("--methods", nargs="+", default=["ml", "kopf"])
    parser.add_argument("--seeds", nargs="+", type=int, default=[1])
    parser.add_argument("--size", type=int, default=64, help="exemplar side (default 64)")
    parser.add_argument("--shape", type=int, default=32, help="block side (default 32)")
    parser.add_argument("--device", default=None, help="OpenCL device (default: clsolid's choice)")
    parser.add_argument("-o", "--output", type=Path, default=None, help="write the table here too")
    parser.add_argument("--compare", type=Path, default=None, help="a table to compare with; exit 1 if any differs")
    args = parser.parse_args(argv)

    device = clsolid.select_device(args.device)
    lines = [f"Checksums: gallery {args.size}^2 -> {args.shape}^3 on {device.name}", "",
             "| exemplar | method | seed | sha256[:16] |", "|---|---|---|---|"]
    found = {}
    start = time.perf_counter()
    for name in args.names or gallery_names():
        image = gallery_exemplar(name, args.size)
        for method in args.methods:
            for seed in args.seeds:
                volume = clsolid.synthesize(image, (args.shape,) * 3, method=method, rng=seed, device=device)
                found[(name, method, str(seed))] = digest = checksum(volume)
                lines.append(f"| {name} | {method} | {seed} | {digest} |")
                print(lines[-1], flush=True)
    lines += ["", f"{len(found)} volumes in {time.perf_counter() - start:.0f} s"]
    print(lines[-1])
    if args.output is not None:
        args.output.parent.mkdir(parents=True, exist_ok=True)
        args.output.write_text("\n".join(lines) + "\n")
    if args.compare is None:
        return 0
    before = read_table(args.compare)
    differ = [key for key, digest in found.items() if key in before and before[key] != digest]
    missing = [key for key in found if key not in before]
    for key in differ:
        print(f"DIFFERS: {' '.join(key)}: {before[key]} -> {found[key]}")
    print(f"{len(found) - len(differ) - len(missing)} identical, {len(differ)} differ, {len(missing)} not in "
          f"{args.compare}")
    return 1 if differ or missing else 0


if __name__ == "__main__":
    sys.exit(main())
