"""Command-line runner: ``clsolid devices``, ``clsolid synth``, ``clsolid evaluate``.

Exit codes: 0 success, 2 usage or input error, 3 no OpenCL device, 4 device out of
memory, 5 kernel build failure, 1 anything unexpected (traceback with ``--debug``).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

from .errors import ClsolidError, DeviceMemoryError, HostMemoryError, InputError, KernelBuildError, NoDeviceError
from .ml.params import (DEFAULT_BANDWIDTH_FACTOR, DISTANCES, HEURISTICS, INHERITED, PYRAMIDS, LIKELIHOODS,
                        RELAXATIONS, SHARED_PROFILES, SLICE_LAYOUTS, UPSAMPLING, MLParams)
from .presets import PRESETS, Preset, get_preset
from .search.params import DEFAULT_CANDIDATES, HISTOGRAMS, ORDERS_ALL, RULES, SEARCHES
from .search.params import METHODS as SEARCH_METHODS

EXIT_OK, EXIT_FAIL, EXIT_USAGE, EXIT_NO_DEVICE, EXIT_MEMORY, EXIT_BUILD = 0, 1, 2, 3, 4, 5
_EXIT_OF = ((InputError, EXIT_USAGE), (NoDeviceError, EXIT_NO_DEVICE),
            (DeviceMemoryError, EXIT_MEMORY), (HostMemoryError, EXIT_MEMORY), (KernelBuildError, EXIT_BUILD))


#: The synth subcommand's defaults, filled in when its parser is built (for _check_method_flags).
SYNTH_DEFAULTS: dict = {}
#: The synth subcommand's parser, kept so that a preset can become its defaults.
_SYNTH_PARSER: list = []


def _levels(text: str) -> int | None:
    if text.lower() in ("all", "none"):
        return None
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--levels must be an integer or 'all', not {text!r}") from None


def _add_synth(sub) -> None:
    p = sub.add_parser("synth", help="grow a volume from a 2D exemplar",
                       description="Grow a solid texture whose slices look like EXEMPLAR (NP-MRF maximum likelihood).")
    p.add_argument("exemplar", nargs="?", default="brick",
                   help="image (.png/.tif/.npy) or built-in name: brick, grass, gravel (default: brick)")
    p.add_argument("-o", "--output", required=True, type=Path,
                   help="volume to write: .tif (ImageJ, ZYX), .ome.tif (OME-TIFF, BigTIFF above 4 GiB) or .npy")
    p.add_argument("--shape", nargs=3, type=int, default=(64, 64, 64), metavar=("Z", "Y", "X"),
                   help="volume size (default 64 64 64)")
    p.add_argument("--preset", choices=tuple(PRESETS), default=None,
                   help="a thesis experiment's settings (README, Presets); flags given explicitly override them")
    p.add_argument("--method", default="ml", choices=("ml",) + SEARCH_METHODS,
                   help="ml: NP-MRF maximum likelihood (default); wl: Wei-Levoy search and average; "
                        "kopf: Kopf et al. weights and histogram re-weighting; chen-wang: candidate sets, "
                        "index and position histograms, exemplar pixels copied "
                        "(options --iterations, --inner, --no-parent, --init, --order, --causal, --site-map; "
                        "wl, kopf: --[no-]specify; kopf: --rule, --histogram; chen-wang: --candidates, --source-map)")
    d = MLParams()  # one source for the defaults; argparse shows them with %(default)s
    p.add_argument("--heuristic", default=d.heuristic,
                   help=f"view combination: {', '.join(HEURISTICS)} or a thesis/paper tag (default %(default)s)")
    p.add_argument("--neighborhood", type=int, default=None,
                   help=f"odd window size per view (default {d.neighborhood} for ml; 7 for wl, kopf and chen-wang)")
    p.add_argument("--iterations", type=int, default=10, help="wl: passes per scale (default %(default)s)")
    p.add_argument("--inner", type=int, default=4,
                   help="wl: most searches per voxel and pass, the centre included after the first "
                        "(default %(default)s)")
    p.add_argument("--no-parent", action="store_true",
                   help="wl: match the k x k square alone, without the coarser scale's 3 x 3")
    p.add_argument("--parent-weight", type=float, default=None,
                   help="each of the coarser scale's 3 x 3 parent terms' weight in the distance against 1 for "
                        "the square's (default: 4 for kopf, 1 for wl and chen-wang; ml: 4 on segmented "
                        "exemplars, 0 on grey ones; 0 = none, the thesis)")
    p.add_argument("--parent-min-side", type=int, default=d.parent_min_side, metavar="N",
                   help="ml: parent terms only at scales whose coarser exemplar is at least N pixels on its "
                        "shorter side (default %(default)s; 0: every scale below the coarsest)")
    p.add_argument("--init", choices=("upsample", "noise"), default="upsample",
                   help="wl: a finer scale starts from the coarser result up-sampled (default) or from noise")
    p.add_argument("--rule", choices=RULES, default="centres",
                   help="kopf: a voxel's value from each view's matched centre (the thesis, default) or from "
                        "every overlapping matched square (Kopf et al.)")
    p.add_argument("--order", choices=ORDERS_ALL, default="sets",
                   help="search methods: conflict-free sets in parallel (default), or one voxel at a time in raster, "
                        "random, Morton or Hilbert order (small blocks)")
    p.add_argument("--histogram", choices=HISTOGRAMS, default="global",
                   help="kopf: re-weight by the whole block's histogram (default) or by the voxel's slice's")
    p.add_argument("--specify", action=argparse.BooleanOptionalAction, default=None,
                   help="wl, kopf: after every pass, map the block's grey levels rank for rank onto the "
                        "exemplar's histogram (categorical exemplars' phases are left alone; default: on for "
                        "kopf, off for wl; --no-specify is the thesis's kopf)")
    p.add_argument("--causal", action="store_true",
                   help="search methods: match the L-shaped causal neighbourhood instead of the full square")
    p.add_argument("--search", choices=SEARCHES, default=None,
                   help="search methods: each view's best match over every exemplar site (the reference) or among "
                        "the k-coherence candidates of the voxel's neighbours' matches (faster; default: coherence "
                        "for kopf, exact for wl and chen-wang)")
    p.add_argument("--exact-passes", type=int, default=None, metavar="N",
                   help="search methods, --search coherence: the first N passes of every level search every "
                        "site, seeding the candidates of the passes after (default: 1 for kopf on a grey "
                        "exemplar, else 0)")
    p.add_argument("--seed-components", type=int, default=None, metavar="N",
                   help="search methods, --search coherence: the exact passes compare the sites on the N leading "
                        "principal components of the neighbourhoods, each site found then measured on every term "
                        "(0: every term; default: 16 for kopf, else 0; phase codes always every term)")
    p.add_argument("--coherence-levels", type=int, default=None, metavar="N",
                   help="search methods, --search coherence: how many of the finest levels search among the "
                        "candidates; the coarser ones search every site (default: 1 for kopf, every level for "
                        "the others)")
    p.add_argument("--index-histogram", action=argparse.BooleanOptionalAction, default=None,
                   help="wl, kopf, --search coherence: rank the candidates by Chen & Wang's index histogram too "
                        "(how often each exemplar site is matched; default: on for wl, and for kopf on grey "
                        "exemplars)")
    p.add_argument("--candidates", type=int, default=DEFAULT_CANDIDATES,
                   help="chen-wang: candidate set size per exemplar pixel, itself included (default %(default)s)")
    p.add_argument("--site-map", type=Path, default=None,
                   help="search methods: PNG of the position histogram (how often each exemplar pixel is the "
                        "best match of a voxel, for chen-wang its source; red: never, blue: no complete "
                        "neighbourhood)")
    p.add_argument("--source-map", type=Path, default=None,
                   help="chen-wang: .npy of the exemplar (row, column) each voxel copies, (Z, Y, X, 2) int64")
    p.add_argument("--scales", type=int, default=d.scales, help="decimation scales (default %(default)s)")
    p.add_argument("--pyramid", choices=PYRAMIDS, default=d.pyramid,
                   help="coarser exemplars: [1 2 1]/4 low-pass then 2:1 decimation, or plain decimation "
                        "as in the thesis (default %(default)s)")
    p.add_argument("--views", type=int, default=d.views, choices=(2, 3), help="constrained views (default %(default)s)")
    p.add_argument("--levels", type=_levels, default=d.levels, help="grey levels, or 'all' for 8-bit (default %(default)s)")
    p.add_argument("--xi", type=float, default=d.xi, help="cooling parameter xi < 0 (default %(default)s)")
    p.add_argument("--stop-fraction", type=float, default=d.stop_fraction,
                   help="stop a scale when the global temperature fell by this fraction (default %(default)s)")
    p.add_argument("--max-sweeps", type=int, default=d.max_sweeps, help="most sweeps per scale (default %(default)s)")
    p.add_argument("--upsampling", choices=UPSAMPLING, default=None,
                   help="coarse-to-fine copy (default 1/8; 8/8 under --relaxation annealing, as TIP14)")
    p.add_argument("--inherited", choices=INHERITED, default=d.inherited,
                   help="voxels from the coarser scale: re-synthesised with t=0, or fixed (default %(default)s)")
    p.add_argument("--insert-spacing", type=float, default=d.insert_spacing,
                   help="+in: an exemplar slice, trusted, about every this many voxels of each constrained "
                        "view's depth (default: 5 for categorical exemplars, 6 for grey ones); the search "
                        "methods' anchor slices (kopf: 6 by default; wl, chen-wang: none unless given; 0 = none)")
    p.add_argument("--insert-slices", type=int, default=d.insert_slices,
                   help="+in: this many slices per constrained view instead of --insert-spacing; 0 = noise only (-in)")
    p.add_argument("--insert-piece", type=int, default=d.insert_piece,
                   help="+in slices as mosaics of N x N pieces, each from its own seeded exemplar window "
                        "(a multiple of 2^(scales-1)); 0 = one window a slice, as the thesis "
                        "(default %(default)s)")
    p.add_argument("--seam-gap", type=int, default=d.seam_gap,
                   help="pixels of a +in slice left unwritten on each side of a seam where it tiles the exemplar "
                        "across its edge; 0 = write the seam (default: 2 where the exemplar's seam shows, else 0)")
    p.add_argument("--slice-layout", choices=SLICE_LAYOUTS, default=d.slice_layout,
                   help="+in slices at the same depths and tiling in every view, or staggered between "
                        "views with seeded shifts (default %(default)s)")
    p.add_argument("--initial-temperature", type=float, default=d.initial_temperature,
                   help="temperature of non-trusted voxels at the start of a scale (default %(default)s, the thesis)")
    p.add_argument("--bandwidth", type=float, nargs="+", default=None,
                   help="Parzen bandwidth: one value, or one per scale finest first "
                        "(default: --bandwidth-factor x Silverman per scale)")
    p.add_argument("--bandwidth-factor", type=float, nargs="+", default=None,
                   help="multiply Silverman's bandwidth: one factor, or one per scale finest first "
                        f"(default {DEFAULT_BANDWIDTH_FACTOR}; 1 = the thesis)")
    p.add_argument("--relaxation", choices=RELAXATIONS, default=d.relaxation,
                   help="argmax (icm, the thesis), a draw from the LCPDF (gibbs), or TIP14's simulated "
                        "annealing (default %(default)s)")
    p.add_argument("--anneal-start", type=float, default=d.anneal_start,
                   help="annealing: initial global temperature t_in of every scale (default %(default)s)")
    p.add_argument("--anneal-cooling", type=float, default=d.anneal_cooling,
                   help="annealing: t_in is multiplied by this after every sweep (default %(default)s)")
    p.add_argument("--sweeps", type=int, default=d.sweeps,
                   help="exactly this many sweeps per scale (default: stop on the temperature rule)")
    p.add_argument("--balance", type=float, default=d.balance,
                   help="label-histogram balance in [0, 1] (ml, and kopf's phases): each sweep (kopf: each set's "
                        "vote) aims that far from the unbiased fractions towards the exemplar's (default "
                        "%(default)s = exactly; 0 = off, the thesis)")
    p.add_argument("--likelihood", choices=LIKELIHOODS, default=d.likelihood,
                   help="the Parzen sum over every exemplar site (exact, the thesis) or over k-coherence "
                        "candidates plus a sample of the other sites (pruned); auto (default): pruned for "
                        "categorical exemplars (at most 8 values, kept) and grey ones of at least 10,000 sites "
                        "(with --prune-projected 24), exact for smaller grey ones")
    p.add_argument("--distance", choices=DISTANCES, default=d.distance,
                   help="how neighbourhoods differ: squared grey-level differences (squared, the thesis), the "
                        "count of differing levels (mismatch: phases are names, not numbers), or that count with "
                        "a mismatch between phases a and b costing 1/(2 f_a) + 1/(2 f_b) (weighted; f: fractions); "
                        "auto (default): weighted for categorical exemplars (at most 8 values, kept; mismatch, the "
                        "same, on two), squared for grey ones; the search methods take auto, squared or weighted "
                        "(their finest scale's squares; auto: weighted on 3 to 8 phases for kopf)")
    p.add_argument("--prune-similar", type=int, default=d.prune_similar,
                   help="pruned: windows taken per source, itself included (default: 1 with projected "
                        "candidates, else 8)")
    p.add_argument("--prune-sample", type=int, default=d.prune_sample,
                   help="pruned: sites sampled to estimate the rest of the sum (default: 32 with projected "
                        "candidates, else 64)")
    p.add_argument("--prune-projected", type=int, default=d.prune_projected, metavar="AXES",
                   help="pruned, grey exemplars: also take each voxel's nearest sites by the distance projected "
                        "on the exemplar windows' first AXES principal axes (0: off; default: 24 where auto prunes "
                        "a grey exemplar of at least 10,000 sites, else off)")
    p.add_argument("--prune-projected-k", type=int, default=d.prune_projected_k, metavar="K",
                   help="pruned: the projected candidates a voxel and view takes (default %(default)s)")
    p.add_argument("--prune-projected-probe", type=int, default=d.prune_projected_probe, metavar="P",
                   help="pruned: search only the P lists of sites (about sqrt(sites) lists) whose centres are "
                        "nearest to the voxel's projection (default %(default)s; 0: every site)")
    p.add_argument("--prune-projected-sweeps", type=int, default=d.prune_projected_sweeps, metavar="N",
                   help="pruned: search projected candidates in the first N sweeps of each scale only "
                        "(default %(default)s; 0: every sweep)")
    p.add_argument("--prune-min-weight", type=float, default=d.prune_min_weight,
                   help="pruned: a neighbourhood whose mean (1 - t)^2 is below this gets the exact sum "
                        "(default %(default)s: never)")
    p.add_argument("--falloff", type=float, default=d.falloff,
                   help="Gaussian weight of each neighbourhood term by its distance from the centre, this "
                        "sigma in pixels of each scale (default: 3 for grey exemplars, 0 for categorical "
                        "ones); 0 = every term alike, the thesis")
    p.add_argument("--shared-weight", type=float, default=d.shared_weight, metavar="W",
                   help="weight of the window terms on the axis the constrained views share (the voxels above "
                        "and below, in both views' windows; default: 0 for categorical exemplars with 2 views, "
                        "else 1); 1 = every term alike, the thesis")
    p.add_argument("--shared-profile", choices=SHARED_PROFILES, default=d.shared_profile,
                   help="with --shared-weight W below 1, which terms it weighs: 'direction' (default) every term "
                        "1 - (1 - W) cos^2 of its angle to the shared axis, 'line' only the terms on that axis "
                        "(W; the rest 1; thin networks such as cracks stay more connected)")
    p.add_argument("--region", type=int, default=d.region, metavar="N",
                   help="ml: visit the block region by region, cubes of at most N voxels, every set of one before "
                        "the next (another visiting order; README, Using it): with --scratch and --tile N, each "
                        "region's state is read from the disk once a sweep (default 0: set by set, whole block)")
    p.add_argument("--checkpoint", type=Path, default=None,
                   help="ml: save the run's state in this folder after every sweep (see --checkpoint-every), "
                        "so that --resume can go on after a crash or Ctrl-C")
    p.add_argument("--checkpoint-every", type=float, default=0.0,
                   help="seconds between checkpoints (default 0: after every sweep; always at the end of a scale)")
    p.add_argument("--tile", type=int, default=None, metavar="N",
                   help="ml: synthesize the block in tiles of at most N voxels on a side, each with a halo, for "
                        "blocks larger than the device holds; the same volume as in one piece, more slowly "
                        "(default: one piece)")
    p.add_argument("--scratch", type=Path, default=None, metavar="DIR",
                   help="ml, with --tile: keep the block's state in memory-mapped files in a folder made in DIR "
                        "(removed at the end), for blocks larger than the host's memory: a few bytes a voxel stay "
                        "in memory and about 40 go to the disk; the same volume, written to --output a plane at "
                        "a time")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="ml, with --tile: run the tiles of every set on the workers of the Dask scheduler at ADDRESS "
                        "(each worker uses its own OpenCL device, --device naming it); needs clsolid[dask]")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="ml, with --tile: as --scheduler, on N local worker processes started for this run")
    p.add_argument("--resume", type=Path, default=None,
                   help="go on with the run saved in this checkpoint folder (its exemplar, shape, settings and "
                        "seed; give only -o and output options) and keep checkpointing there")
    p.add_argument("--builtin-size", type=int, default=64, help="side of a built-in exemplar (default 64)")
    p.add_argument("--seed", type=int, default=None, help="random seed (default: fresh, recorded in the sidecar)")
    p.add_argument("--device", default=None,
                   help="OpenCL device: PYOPENCL_CTX syntax ('0:1'), a name ('pocl', 'H100'), cpu/gpu, or 'reference'")
    p.add_argument("--voxel-size", type=float, nargs="+", default=None, metavar="SIZE",
                   help="voxel size for the TIFF (one value, or Z Y X; default: the exemplar file's own pixel "
                        "size, where it records one)")
    p.add_argument("--unit", default=None, help="unit of --voxel-size (default um)")
    p.add_argument("--indices", action="store_true",
                   help="write level indices (0..levels-1) instead of the exemplar's own values")
    p.add_argument("--preview", type=Path, default=None,
                   help="PNG: the exemplar beside a front, right and top slice, labelled")
    p.add_argument("--track", type=Path, default=None,
                   help="JSON recording the evaluation indicators after every sweep (convergence curves)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    SYNTH_DEFAULTS.update({a.dest: a.default for a in p._actions})
    _SYNTH_PARSER[:] = [p]


def _preset_defaults(preset: Preset) -> dict:
    """A preset as the synth subcommand's defaults (its option names are the flags' names)."""
    values = {"method": preset.method, "shape": preset.shape, "builtin_size": preset.exemplar_size}
    for name, value in preset.options.items():
        if name in ("bandwidth", "bandwidth_factor"):
            value = [value] if isinstance(value, (int, float)) else list(value)
        elif name == "parent":
            name, value = "no_parent", not value
        values[name] = value
    return values


def _parse(parser: argparse.ArgumentParser, argv: list[str] | None) -> argparse.Namespace:
    """Parse; with ``synth --preset``, parse again with the preset as the defaults."""
    args = parser.parse_args(argv)
    if args.command != "synth" or args.preset is None:
        return args
    preset = get_preset(args.preset)
    _SYNTH_PARSER[0].set_defaults(**_preset_defaults(preset))
    args = parser.parse_args(argv)
    # The search presets are the thesis's common settings of every fixed-neighbourhood method.
    searches = preset.method in SEARCH_METHODS and args.method in SEARCH_METHODS
    if args.method != preset.method and not searches:
        kind = f"{', '.join(SEARCH_METHODS)}" if preset.method in SEARCH_METHODS else preset.method
        parser.error(f"--preset {preset.name} is for --method {kind}, not {args.method}")
    return args


def _add_devices(sub) -> None:
    sub.add_parser("devices", help="list OpenCL devices", description="List every OpenCL device clsolid can use.")


def _add_evaluate(sub) -> None:
    from .report import add_evaluate_arguments

    p = sub.add_parser("evaluate", help="compare a volume's slices with an exemplar",
                       description="Objective statistics between a 2D exemplar and the slices of a volume.")
    add_evaluate_arguments(p)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="clsolid", description="Solid textures from a 2D exemplar, on OpenCL.")
    sub = parser.add_subparsers(dest="command", required=True)
    _add_synth(sub)
    _add_devices(sub)
    _add_evaluate(sub)
    return parser


def _fmt_time(s: float) -> str:
    if s != s:  # NaN: not known yet
        return "?"
    return f"{s:.0f}s" if s < 120 else f"{s / 60:.1f}min"


def render_progress(info) -> None:
    """One stderr line per sweep: scale, sweep, global temperature, elapsed, ETA."""
    z, y, x = info.shape
    temp = "" if math.isnan(info.temperature) else f"T={info.temperature:.0f} (stop at {info.target:.0f})  "
    print(f"scale {info.scale}/{info.n_scales} ({z}x{y}x{x})  sweep {info.sweep:>2}  "
          f"{temp}visited {info.visited}  "
          f"elapsed {_fmt_time(info.elapsed)}  ETA {_fmt_time(info.eta)}", file=sys.stderr, flush=True)


def versions() -> dict:
    import numpy
    import pyopencl

    from . import __version__

    return {"clsolid": __version__, "numpy": numpy.__version__, "pyopencl": pyopencl.VERSION_TEXT,
            "python": platform.python_version(), "platform": platform.platform()}


def _tracker(levels: int, records: list):
    """A progress hook that evaluates the block after every sweep (``--track``)."""
    from . import metrics

    def track(info) -> None:
        vol = info.volume()
        ind = {}
        for view in ("front", "right"):
            sl = metrics.view_slices(vol, view, max_slices=8)
            ind[f"autocorrelation_{view}"] = float(metrics.autocorrelation_distance(info.exemplar, sl))
            ind[f"histogram_kl_{view}"] = float(metrics.histogram_distance(
                info.exemplar, sl, bins=levels, value_range=(0, levels)))
        records.append({"scale": info.scale, "sweep": info.sweep, "temperature": info.temperature,
                        "elapsed": info.elapsed, "indicators": ind})

    return track


#: Flags that only one method reads: given to the other, they are an error, not ignored.
_ML_ONLY = ("heuristic", "pyramid", "xi", "stop_fraction", "max_sweeps", "upsampling", "inherited",
            "insert_slices", "insert_spacing", "insert_piece", "seam_gap", "slice_layout", "initial_temperature",
            "bandwidth", "bandwidth_factor",
            "relaxation", "anneal_start", "anneal_cooling", "sweeps", "balance", "likelihood", "distance",
            "prune_similar", "prune_sample", "prune_min_weight", "prune_projected", "prune_projected_k",
            "prune_projected_probe", "prune_projected_sweeps", "falloff", "shared_weight", "shared_profile",
            "parent_min_side", "region", "tile",
            "scratch", "scheduler", "workers", "indices", "track")
_WL_ONLY = ("iterations", "inner", "no_parent", "init", "rule", "order", "causal", "histogram",
            "candidates", "specify", "search", "exact_passes", "seed_components", "coherence_levels", "index_histogram",
            "site_map", "source_map")


#: What a checkpoint fixes: given with --resume, these flags are an error, not ignored.
_RESUME_FIXED = ("exemplar", "shape", "method", "preset", "heuristic", "neighborhood", "scales", "views", "levels",
                 "seed", "builtin_size", "checkpoint", "track", "parent_weight") + _WL_ONLY + tuple(
                     n for n in _ML_ONLY if n not in ("indices", "track", "tile", "scratch", "scheduler", "workers"))


def _given(args, names) -> str:
    """Those of *names* set away from the synth defaults, as the user wrote them ('' if none)."""
    given = [name for name in names if getattr(args, name) != SYNTH_DEFAULTS[name]]
    return ", ".join(name if name == "exemplar" else "--" + name.replace("_", "-") for name in given)


def _check_resume_flags(args) -> None:
    flags = _given(args, _RESUME_FIXED)
    if flags:
        raise InputError(f"--resume goes on with the checkpoint's own exemplar, settings and seed (and "
                         f"checkpoints there): drop {flags}")


def _voxel_size(args) -> tuple[object, str | None, str | None]:
    """``(voxel_size, unit, source)`` for the output: ``--voxel-size`` (with ``--unit``), else the
    exemplar file's own pixel size (a voxel is an exemplar pixel: Z and X take its width, Y its
    height), else none."""
    from .exemplar import BUILTINS
    from .volumeio import image_pixel_size

    if args.voxel_size is not None:
        if len(args.voxel_size) not in (1, 3):
            raise InputError(f"--voxel-size takes one value or three (Z Y X), not {len(args.voxel_size)}")
        size = args.voxel_size[0] if len(args.voxel_size) == 1 else tuple(args.voxel_size)
        return size, args.unit or "um", "--voxel-size"
    if args.unit is not None:
        raise InputError("--unit is the unit of --voxel-size: give both (without either, the output takes "
                         "the exemplar's own pixel size, where its file records one)")
    if args.resume is not None or args.exemplar in BUILTINS:
        return None, None, None
    found = image_pixel_size(args.exemplar)
    if found is None:
        return None, None, None
    (y, x), unit = found
    print(f"voxel size (Z Y X) from the exemplar: {x:g} {y:g} {x:g} {unit}", file=sys.stderr)
    return (x, y, x), unit, "exemplar"


def _check_method_flags(args) -> None:
    """Refuse a flag the chosen method would not read (set away from its default)."""
    # kopf balances its phases and anchors slices too; the search parameters say which method does not
    shared = ("balance", "insert_spacing", "distance")
    flags = _given(args, _WL_ONLY if args.method == "ml" else tuple(n for n in _ML_ONLY if n not in shared))
    if flags:
        raise InputError(f"{flags} not used by --method {args.method}")


def _ml_options(args) -> dict:
    """The ``synthesize`` options of ``--method ml`` from the command line."""
    options = dict(pyramid=args.pyramid, xi=args.xi, stop_fraction=args.stop_fraction, max_sweeps=args.max_sweeps,
                   upsampling=args.upsampling, inherited=args.inherited, insert_slices=args.insert_slices,
                   insert_spacing=args.insert_spacing, insert_piece=args.insert_piece, seam_gap=args.seam_gap,
                   slice_layout=args.slice_layout,
                   initial_temperature=args.initial_temperature, builtin_size=args.builtin_size,
                   relaxation=args.relaxation, anneal_start=args.anneal_start, anneal_cooling=args.anneal_cooling,
                   sweeps=args.sweeps, balance=args.balance, likelihood=args.likelihood,
                   distance=args.distance, prune_similar=args.prune_similar, prune_sample=args.prune_sample,
                   prune_min_weight=args.prune_min_weight, prune_projected=args.prune_projected,
                   prune_projected_k=args.prune_projected_k, prune_projected_probe=args.prune_projected_probe,
                   prune_projected_sweeps=args.prune_projected_sweeps,
                   falloff=args.falloff, shared_weight=args.shared_weight, shared_profile=args.shared_profile,
                   parent_min_side=args.parent_min_side, region=args.region)
    if args.parent_weight is not None:
        options["parent_weight"] = args.parent_weight
    if args.tile is not None:
        options["tile"] = args.tile
    if args.scratch is not None:
        options["scratch"] = args.scratch
    for name in ("bandwidth", "bandwidth_factor"):  # one value applies to every scale
        values = getattr(args, name)
        if values is not None:
            options[name] = values[0] if len(values) == 1 else tuple(values)
    return options


def _dask_client(args):
    """The Dask client of ``--scheduler`` or ``--workers`` (a context manager), or none."""
    if args.scheduler is None and args.workers is None:
        return contextlib.nullcontext()
    if args.scheduler is not None and args.workers is not None:
        raise InputError(f"--scheduler {args.scheduler} and --workers {args.workers}: give one (a running Dask "
                         "scheduler, or local worker processes for this run)")
    if args.tile is None:
        raise InputError("--scheduler and --workers run the tiles of every set on Dask workers: give --tile N too")
    from .ml.distributed import dask_client

    return dask_client(args.scheduler, args.workers)


def _outputs(args) -> list[tuple[str, Path]]:
    """The files a ``synth`` run writes, with their flags."""
    flags = (("--output", args.output), ("--preview", args.preview), ("--site-map", args.site_map),
             ("--source-map", args.source_map), ("--track", args.track))
    return [(flag, Path(path)) for flag, path in flags if path is not None]


def _check_writable(args) -> None:
    """Every file the run writes can be written: its folder (the ``--checkpoint`` folder
    itself) exists or can be made and takes files (a path is otherwise first met after the
    whole run, or the first sweep, and the run is lost)."""
    folders = []
    for flag, path in _outputs(args):
        if path.is_dir():
            raise InputError(f"{flag} {path} is a folder; give a file name")
        folders.append((flag, path, path.parent))
    if getattr(args, "checkpoint", None) is not None:
        folders.append(("--checkpoint", Path(args.checkpoint), Path(args.checkpoint)))
    for flag, path, folder in folders:
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f"{flag} {path}: its folder cannot be made ({exc.strerror}); choose a writable "
                             "folder") from exc
        if not os.access(folder, os.W_OK):
            raise InputError(f"{flag} {path}: the folder {folder} does not take new files; choose another")


def _rescue(volume, seed: int) -> Path:
    """Save a volume whose output failed late (a full disk) where it can go: the temporary folder."""
    import tempfile

    import numpy as np

    path = Path(tempfile.gettempdir()) / f"clsolid-rescued-seed{seed}-{os.getpid()}.npy"
    np.save(path, volume)
    return path


def cmd_synth(args) -> int:
    from .api import resume, slice_plan, synthesize
    from .preview import save_preview, save_site_map
    from .core.slices import preview_depths
    from .volumeio import check_calibration, save_volume

    suffix = args.output.suffix.lower()
    if suffix not in (".tif", ".tiff", ".npy"):
        raise InputError(f"--output {args.output} must end in .tif, .tiff or .npy")
    if args.preview is not None and args.preview.suffix.lower() != ".png":
        raise InputError(f"--preview {args.preview} must end in .png")
    voxel_size, unit, voxel_from = _voxel_size(args)
    check_calibration(voxel_size, unit or "um", args.output)  # now, not after the run
    _check_method_flags(args)
    if args.resume is not None:
        _check_resume_flags(args)
    elif args.checkpoint is not None and args.method != "ml":
        raise InputError(f"--checkpoint is for --method ml; {args.method} runs are not checkpointed yet")
    _check_writable(args)  # after the flags' checks, which make no folders
    if args.method != "ml":
        options = dict(iterations=args.iterations, inner=args.inner, parent=not args.no_parent,
                       parent_weight=args.parent_weight, distance=args.distance, init=args.init, rule=args.rule,
                       order=args.order, causal=args.causal, histogram=args.histogram, candidates=args.candidates,
                       search=args.search,
                       exact_passes=args.exact_passes, seed_components=args.seed_components,
                       coherence_levels=args.coherence_levels,
                       index_histogram=args.index_histogram, specify=args.specify,
                       builtin_size=args.builtin_size)
        for name in ("balance", "insert_spacing"):  # kopf's defaults are the flags' (ml's); the others' are off
            if args.method == "kopf" or getattr(args, name) != SYNTH_DEFAULTS[name]:
                options[name] = getattr(args, name)
        if args.site_map is not None:
            if args.site_map.suffix.lower() != ".png":
                raise InputError(f"--site-map {args.site_map} must end in .png")
            options["site_map"] = True
        if args.source_map is not None:
            if args.method != "chen-wang":
                raise InputError(f"--source-map is chen-wang's (it copies exemplar pixels); --method {args.method} "
                                 "blends them")
            if args.source_map.suffix.lower() != ".npy":
                raise InputError(f"--source-map {args.source_map} must end in .npy")
    else:
        options = _ml_options(args)
    hooks = [] if args.quiet else [render_progress]
    records: list = []
    if args.track is not None:
        hooks.append(_tracker(256 if args.levels is None else args.levels, records))
    heuristic = args.heuristic if args.method == "ml" else None
    report = (lambda info: [h(info) for h in hooks]) if hooks else None
    with _dask_client(args) as client:
        if args.resume is not None:
            result = resume(args.resume, device=args.device, progress=report, full_output=True,
                            checkpoint_every=args.checkpoint_every, tile=args.tile, client=client,
                            scratch=args.scratch)
        else:
            if args.checkpoint is not None:
                options.update(checkpoint=args.checkpoint, checkpoint_every=args.checkpoint_every)
            if client is not None:
                options["client"] = client
            result = synthesize(args.exemplar, tuple(args.shape), method=args.method, heuristic=heuristic,
                                neighborhood=args.neighborhood, scales=args.scales, views=args.views,
                                levels=args.levels, rng=args.seed, device=args.device, progress=report,
                                full_output=True, **options)
    written_kind = "indices" if args.indices else "values"
    volume = result.labels if args.indices else result.volume
    try:
        written = save_volume(args.output, volume, voxel_size=voxel_size, unit=unit or "um",
                              metadata={"seed": result.seed, "written": written_kind,
                                        "levels": int(result.level_values.size)})
    except OSError as exc:  # checked writable before the run: a full disk, a vanished mount
        raise ClsolidError(f"--output {args.output} could not be written ({exc}); the volume is saved in "
                           f"{_rescue(volume, result.seed)}") from exc
    sidecar = written.with_suffix(".json")
    meta = {"volume": str(written), "exemplar": str(args.exemplar) if args.resume is None else None,
            "resumed_from": None if args.resume is None else str(args.resume), "written": written_kind,
            "values_exact": result.values_exact, "level_values": result.level_values.tolist(),
            "seed": result.seed, "device": result.device, "preset": args.preset, "params": result.params,
            "voxel_size": voxel_size, "unit": unit, "voxel_size_from": voxel_from,
            "versions": versions(), "timings": result.timings,
            "command": " ".join(sys.argv), "written_at": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    sidecar.write_text(json.dumps(meta, indent=2, default=float))
    if args.preview is not None:
        plan = slice_plan(result.params)  # away from the +in (or anchor) slices, which show the exemplar
        save_preview(args.preview, result.exemplar, result.volume, constrained=plan.view_names,
                     depths=preview_depths(result.volume.shape, plan))
    if args.site_map is not None:
        save_site_map(args.site_map, result.site_use)
    if args.source_map is not None:
        import numpy as np

        np.save(args.source_map, result.source)
    if args.track is not None:
        args.track.write_text(json.dumps({"exemplar": str(args.exemplar), "seed": result.seed,
                                          "records": records}, indent=2))
    if not args.quiet:
        others = [str(p) for p in (sidecar, args.preview, args.site_map, args.source_map, args.track) if p is not None]
        files = others[0] if len(others) == 1 else f"{', '.join(others[:-1])} and {others[-1]}"
        print(f"wrote {written} ({'x'.join(map(str, result.volume.shape))} {written_kind}, seed {result.seed}, "
              f"{result.timings['total_s']:.1f}s on {result.device}), {files}", file=sys.stderr)
    return EXIT_OK


def cmd_devices(args) -> int:
    from .core.device import list_devices

    devices = list_devices()
    print(f"{'index':<6} {'type':<11} {'compiles':<8} {'vec':>3} {'CUs':>4} {'memory':>10} {'max buffer':>11} {'fp64':<4}  "
          f"{'OpenCL C':<10} {'driver':<24} platform / name")
    for d in devices:
        opencl_c = d["opencl_c"].removeprefix("OpenCL C").split()[0] if d["opencl_c"] else "?"
        print(f"{d['index']:<6} {d['type']:<11} {'yes' if d['compiles'] else 'NO':<8} "
              f"{d['vector_width'] or '-':>3} {d['compute_units']:>4} "
              f"{d['global_mem'] / 2**30:>8.1f}Gi {d['max_alloc'] / 2**30:>9.2f}Gi {'yes' if d['fp64'] else 'no':<4}  "
              f"{opencl_c:<10} {d['driver'][:24]:<24} {d['platform']} / {d['name']}")
    for d in devices:
        if not d["compiles"]:
            print(f"{d['index']}: cannot compile kernels: {d['probe_message']}")
    if not any(d["compiles"] for d in devices):
        from .core.device import INSTALL_HINT

        print(f"No device compiles. {INSTALL_HINT}.")
    return EXIT_OK


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``clsolid`` command; returns the exit code."""
    parser = build_parser()
    args = _parse(parser, argv)
    if args.command == "evaluate":
        from .report import main_evaluate

        return main_evaluate(args)
    command = {"synth": cmd_synth, "devices": cmd_devices}[args.command]
    try:
        return command(args)
    except ClsolidError as exc:
        if getattr(args, "debug", False):
            raise
        print(f"clsolid: error: {exc}", file=sys.stderr)
        return next((code for cls, code in _EXIT_OF if isinstance(exc, cls)), EXIT_FAIL)
    except KeyboardInterrupt:
        folder = getattr(args, "resume", None) or getattr(args, "checkpoint", None)
        hint = f"; the last checkpoint is in {folder}: go on with --resume {folder}" if folder else ""
        print(f"clsolid: interrupted{hint}", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
