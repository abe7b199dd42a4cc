"""``clsolid synth``: grow a volume from a 2D exemplar and write it, its sidecar and a preview.

The flags come from the options' declarations: this command's own (:class:`SynthCommand`),
each method's parameters and the back end's (:func:`clsolid.core.options.add_arguments`).
A setting comes from, in this order of precedence: a flag given, ``--config FILE``,
``--preset NAME``, the declaration's default.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import platform
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .._version import __version__
from ..api import METHODS
from ..core.options import (
    Anything,
    Check,
    Choice,
    Flag,
    Int,
    PathLike,
    add_arguments,
    declared,
    documented,
    names,
    option,
    refuse_unknown,
    validate,
)
from ..core.files import replaced_atomically, write_text_atomically
from ..core.views import VIEW_ORDER
from ..errors import InputError, OutputError
from ..ml.backends import BackendOptions
from ..ml.params import MLParams
from ..presets import PRESETS, get_preset
from ..search.params import METHODS as SEARCH_METHODS
from ..search.params import SearchParams
from .config import read_config
from .outputs import check_writable

#: The groups of ``clsolid synth --help``, in order: key -> title.
GROUPS = {
    "essentials": "essentials",
    "views": "an exemplar per view (ml), instead of EXEMPLAR",
    "method": "every method",
    "ml": "ml: maximum likelihood (Urs et al., TIP 2014)",
    "search": "wl, kopf, chen-wang: neighbourhood search (Urs thesis, ch. 3)",
    "output": "output",
    "run": "run: presets, checkpoints, tiles, Dask",
    "ml-tuning": "ml: tuning",
    "search-tuning": "wl, kopf, chen-wang: tuning",
    "device": "device tuning",
}
#: Groups that ``--help`` leaves out and ``--help-all`` shows.
ADVANCED_GROUPS = ("ml-tuning", "search-tuning", "device")
_ML, _SEARCH, _CW = ("ml",), SEARCH_METHODS, ("chen-wang",)


@dataclass(frozen=True)
class Shape(Check):
    """Three positive integers Z Y X."""

    parse = int
    nargs = 3

    def describe(self) -> str:
        return "three positive integers (Z, Y, X)"

    def valid(self, value: Any) -> bool:
        try:
            return len(value) == 3 and all(Int(1).valid(v) for v in value)
        except TypeError:
            return False

    def normalise(self, value: Any) -> tuple[int, int, int]:
        return tuple(int(v) for v in value)


@dataclass(frozen=True)
class Sizes(Check):
    """One positive number or three (Z Y X)."""

    parse = float
    nargs = "+"

    def describe(self) -> str:
        return "one number or three (Z Y X)"

    def valid(self, value: Any) -> bool:
        return isinstance(value, (list, tuple)) and len(value) in (1, 3)


def _path(what: str) -> PathLike:
    return PathLike(what, Path)


_E, _O, _R, _V = "essentials", "output", "run", "views"
_ANY_EXEMPLAR = PathLike("a file or a built-in name")


@documented
@dataclass(frozen=True)
class SynthCommand:
    """The command's own settings: what to read and write, and how to run (the method's and
    the back end's are their own classes')."""

    exemplar: str = option("brick", "image (.png, .tif, .npy) or built-in name: brick, grass, gravel", group=_E,
                           check=_ANY_EXEMPLAR, positional=True)
    output: Path | None = option(None, "volume to write: .tif (ImageJ), .ome.tif (OME-TIFF) or .npy", group=_E,
                                 check=_path("a .tif, .ome.tif or .npy file"), short="-o", required=True,
                                 metavar="FILE")
    shape: tuple[int, int, int] = option((64, 64, 64), "volume size", group=_E, check=Shape(), metavar=("Z", "Y", "X"))
    method: str = option("ml", "ml: maximum likelihood; kopf, wl, chen-wang: neighbourhood search", group=_E,
                         check=Choice(tuple(METHODS)))
    seed: int | None = option(None, "random seed", group=_E, check=Int(0), none="a fresh one, recorded in the sidecar")
    device: str | None = option(None, "OpenCL device: '0:1', a name ('pocl', 'H100'), cpu, gpu or 'reference'",
                                group=_E, check=Anything("a device"), none="$CLSOLID_DEVICE, $PYOPENCL_CTX or the best")
    preview: Path | None = option(None, "PNG of the exemplar beside a front, right and top slice, and the block "
                                  "behind them drawn as a cube", group=_E, check=_path("a .png file"),
                                  metavar="PNG", none="none")
    config: Path | None = option(None, "settings from a TOML file or a run's sidecar JSON (flags given override "
                                 "them)", group=_E, check=_path("a .toml or .json file"), metavar="FILE", none="none")
    quiet: bool = option(False, "no progress on stderr", group=_E, check=Flag(), short="-q")
    front: str | None = option(None, "the front view's exemplar: the (y, x) plane, seen along z", group=_V,
                               check=_ANY_EXEMPLAR, methods=_ML, metavar="IMAGE", none="none")
    right: str | None = option(None, "the right view's exemplar: the (y, z) plane, seen along x", group=_V,
                               check=_ANY_EXEMPLAR, methods=_ML, metavar="IMAGE", none="none")
    top: str | None = option(None, "the top view's exemplar: the (z, x) plane, seen along y", group=_V,
                             check=_ANY_EXEMPLAR, methods=_ML, metavar="IMAGE", none="none")
    indices: bool = option(False, "write level indices (0..levels-1) instead of the exemplar's values", group=_O,
                           check=Flag(), methods=_ML)
    voxel_size: list[float] | None = option(None, "voxel size for the TIFF: one value, or Z Y X", group=_O,
                                            check=Sizes(), metavar="SIZE",
                                            none="the exemplar file's pixel size, where it records one")
    unit: str | None = option(None, "unit of --voxel-size", group=_O, check=Anything("a unit"), none="um")
    track: Path | None = option(None, "JSON of the evaluation indicators after every sweep (convergence)", group=_O,
                                check=_path("a .json file"), metavar="JSON", none="none", methods=_ML)
    site_map: Path | None = option(None, "PNG of how often each exemplar pixel is matched (red: never)", group=_O,
                                   check=_path("a .png file"), metavar="PNG", none="none", methods=_SEARCH)
    source_map: Path | None = option(None, "chen-wang: .npy of the exemplar (row, column) each voxel copies",
                                     group=_O, check=_path("a .npy file"), metavar="NPY", none="none", methods=_CW)
    builtin_size: int = option(64, "side of a built-in exemplar", group=_O, check=Int(1, 256), metavar="N")
    preset: str | None = option(None, "a thesis experiment's settings: " + ", ".join(PRESETS) + " (flags given "
                                "override them)", group=_R,
                                check=Choice(tuple(PRESETS)), metavar="NAME", none="none")
    resume: Path | None = option(None, "go on with the run saved in this checkpoint folder (its exemplar, shape, "
                                 "settings and seed)", group=_R, check=_path("a checkpoint folder"), metavar="DIR",
                                 none="none", methods=_ML)
    scheduler: str | None = option(None, "with --tile: run the tiles on the workers of the Dask scheduler at "
                                   "ADDRESS (needs clsolid[dask])", group=_R, check=Anything("an address"),
                                   metavar="ADDRESS", none="none", methods=_ML)
    workers: int | None = option(None, "with --tile: as --scheduler, on N local worker processes", group=_R,
                                 check=Int(1), metavar="N", none="none", methods=_ML)
    debug: bool = option(False, "show tracebacks", group=_R, check=Flag())

    def __post_init__(self) -> None:
        validate(self)


#: Who declares the flags of ``synth``, in the order their help names them.
SOURCES: tuple[tuple[str, type], ...] = (("command", SynthCommand), ("ml", MLParams),
                                         ("wl, kopf, chen-wang", SearchParams), ("backend", BackendOptions))
#: What a checkpoint fixes: given with --resume, these are an error, not ignored.
_RESUME_FIXED = ("exemplar", *VIEW_ORDER, "shape", "method", "preset", "seed", "builtin_size", "track", "config", "checkpoint")


class _HelpAll(argparse.Action):
    """``--help-all``: the help with every group, the advanced ones too."""

    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS,
                         help="show every option, the advanced groups too, and exit")

    def __call__(self, parser, namespace, values, option_string=None):
        full = argparse.ArgumentParser(prog=parser.prog, usage=parser.usage, description=parser.description,
                                       add_help=False)
        add_synth_arguments(full, show_all=True)
        full.print_help()
        parser.exit()


def add_synth_arguments(parser: argparse.ArgumentParser, show_all: bool = False) -> None:
    """Every flag of ``synth`` on *parser* (made with ``add_help=False``); the advanced groups'
    help only with *show_all*."""
    add_arguments(parser, SOURCES, groups=GROUPS, advanced_groups=ADVANCED_GROUPS, show_all=show_all)
    essentials = next(g for g in parser._action_groups if g.title == GROUPS["essentials"])
    essentials.add_argument("-h", "--help", action="help", help="show this help and exit")
    if not show_all:
        essentials.add_argument("--help-all", action=_HelpAll)


def add_synth(sub: Any, show_all: bool = False) -> argparse.ArgumentParser:
    """The ``synth`` subcommand's parser on the subparsers *sub*."""
    p = sub.add_parser("synth", help="grow a volume from a 2D exemplar",
                       usage="%(prog)s [EXEMPLAR] -o FILE [--shape Z Y X] [--method M] [options]", add_help=False,
                       description="Grow a solid texture whose slices look like EXEMPLAR. The first group holds "
                                   "what most runs need; --help-all shows the tuning groups too.")
    add_synth_arguments(p, show_all)
    return p


def option_reference() -> str:
    """The option reference page (Markdown): every option of every declaring class, one table each."""
    from ..core.options import reference_markdown

    titles = {"command": "The command's own (`clsolid synth`)", "ml": "`ml`: `MLParams`",
              "wl, kopf, chen-wang": "`wl`, `kopf`, `chen-wang`: `SearchParams`",
              "backend": "Back end: `BackendOptions`"}
    head = ["# Option reference", "",
            "<!-- Generated at build time by docs/_ext/option_reference.py from the options' declarations; "
            "do not edit. -->", "",
            "Every option, as declared once in the code: its Python name (a keyword of `clsolid.synthesize`, or "
            "of `clsolid.BackendOptions`), its `clsolid synth` flag, the values it takes and its default. Options "
            "marked advanced appear in `clsolid synth --help-all` only.", ""]
    return "\n".join(head) + "\n" + "\n".join(reference_markdown(cls, titles[who]) for who, cls in SOURCES)


# ----------------------------------------------------------------------------- settings


@dataclass(frozen=True)
class Settings:
    """A ``synth`` run's settings, each from a flag, a config, a preset or its default."""

    command: Any  # SynthCommand
    method_options: dict[str, Any]
    backend: dict[str, Any]
    origin: dict[str, str]  # name -> how it was given ("--xi", "xi (in cfg.toml)", "xi (preset ch5_compare)")


def _said(name: str, origin: dict[str, str]) -> str:
    return origin.get(name, "--" + name.replace("_", "-"))


def _reads(name: str, method: str) -> bool:
    """Whether a run of *method* reads the setting *name*: its parameters', the back end's (ml),
    and the command's own unless it serves other methods only."""
    if name in names(METHODS[method]):
        return True
    if name in names(BackendOptions):
        return method == "ml"
    spec = next((s for f, s in declared(SynthCommand) if f.name == name), None)
    return spec is not None and (spec.methods is None or method in spec.methods)


def resolve(given: dict[str, Any]) -> Settings:
    """The settings of a run from the flags *given* (a parsed namespace's items), with
    ``--config`` and ``--preset`` read under them."""
    layers: list[tuple[dict[str, Any], str]] = []
    config_path = given.get("config")
    config = read_config(Path(config_path)) if config_path is not None else {}
    refuse_unknown(config, [n for _, cls in SOURCES for n in names(cls)], f"--config {config_path}")
    preset_name = given.get("preset", config.get("preset"))
    if preset_name is not None:
        preset = get_preset(preset_name)
        values = {"method": preset.method, "shape": preset.shape, "builtin_size": preset.exemplar_size,
                  **preset.options}
        method = given.get("method", config.get("method", preset.method))
        if method != preset.method and not (method in SEARCH_METHODS and preset.method in SEARCH_METHODS):
            kind = ", ".join(SEARCH_METHODS) if preset.method in SEARCH_METHODS else preset.method
            raise InputError(f"--preset {preset.name} is for --method {kind}, not {method}")
        layers.append((values, f"preset {preset.name}"))
    layers.append((config, f"in {config_path}"))
    layers.append((given, ""))
    merged: dict[str, Any] = {}
    origin: dict[str, str] = {}
    for values, where in layers:
        for name, value in values.items():
            merged[name] = value
            origin[name] = f"{name} ({where})" if where else "--" + name.replace("_", "-")
    method = merged.get("method", "ml")
    if not isinstance(method, str) or method not in METHODS:
        raise InputError(f"method {method!r} is not available; use one of {tuple(METHODS)}")
    cls = METHODS[method]
    unused = [_said(name, origin) for name in merged if not _reads(name, method)]
    if unused:
        more = f" and {len(unused) - 6} more" if len(unused) > 6 else ""
        raise InputError(f"{', '.join(unused[:6])}{more} not used by --method {method}")
    if merged.get("resume") is not None:
        fixed = [n for n in merged if n in _RESUME_FIXED or n in names(MLParams)]
        if fixed:
            raise InputError(f"--resume goes on with the checkpoint's own exemplar, settings and seed (and "
                             f"checkpoints there): drop {', '.join(_said(n, origin) for n in fixed)}")
    command_names, backend_names = names(SynthCommand), names(BackendOptions)
    command = SynthCommand(**{k: v for k, v in merged.items() if k in command_names})
    if command.output is None:
        raise InputError("-o/--output is required: the volume to write (.tif, .ome.tif or .npy)")
    method_options = {k: _scalar(v) for k, v in merged.items() if k in names(cls) and k != "method"}
    backend = {k: v for k, v in merged.items() if k in backend_names}
    return Settings(command, method_options, backend, origin)


def _scalar(value: Any) -> Any:
    """A one-value list (``--bandwidth-factor 0.5``) as the value: it applies at every scale."""
    return value[0] if isinstance(value, list) and len(value) == 1 else value


# ----------------------------------------------------------------------------- outputs


def _outputs(command: Any) -> list[tuple[str, Path, tuple[str, ...]]]:
    """The files a run writes: flag, path and the suffixes it may have."""
    out = Path(command.output)
    files = [("--output", out, (".tif", ".tiff", ".npy")), ("--output's sidecar", _sidecar(out), (".json",))]
    for flag, path, suffixes in (("--preview", command.preview, (".png",)), ("--site-map", command.site_map, (".png",)),
                                 ("--source-map", command.source_map, (".npy",)), ("--track", command.track, ())):
        if path is not None:
            files.append((flag, Path(path), suffixes))
    return files


def _sidecar(output: Path) -> Path:
    return output.with_suffix(".json")


def check_outputs(command: Any, backend: dict[str, Any]) -> None:
    """Refuse, before any synthesis, an output path the run could not write."""
    for flag, path, suffixes in _outputs(command):
        if suffixes and path.suffix.lower() not in suffixes:
            raise InputError(f"{flag} {path} must end in {', '.join(suffixes)}")
    for flag, path, _ in _outputs(command):
        check_writable(flag, path)
    if backend.get("checkpoint") is not None:
        check_writable("--checkpoint", Path(backend["checkpoint"]), folder=True)


def _voxel_size(command: Any) -> tuple[Any, str | None, str | None]:
    """``(voxel_size, unit, source)`` for the output: ``--voxel-size`` (with ``--unit``), else the
    exemplar file's own pixel size (a voxel is an exemplar pixel: Z and X take its width, Y its
    height), else none."""
    from ..exemplar import BUILTINS
    from ..volumeio import image_pixel_size

    if command.voxel_size is not None:
        sizes = command.voxel_size
        size = sizes[0] if len(sizes) == 1 else tuple(sizes)
        return size, command.unit or "um", "--voxel-size"
    if command.unit is not None:
        raise InputError("--unit is the unit of --voxel-size: give both (without either, the output takes "
                         "the exemplar's own pixel size, where its file records one)")
    if command.resume is not None or command.exemplar in BUILTINS:
        return None, None, None
    found = image_pixel_size(command.exemplar)
    if found is None:
        return None, None, None
    (y, x), unit = found
    print(f"voxel size (Z Y X) from the exemplar: {x:g} {y:g} {x:g} {unit}", file=sys.stderr)
    return (x, y, x), unit, "exemplar"


def _rescue(volume: Any, seed: int) -> Path:
    """Save a volume whose output failed late (a full disk) where it can go: the temporary folder
    (whole or not at all, as every output)."""
    import numpy as np

    path = Path(tempfile.gettempdir()) / f"clsolid-rescued-seed{seed}-{os.getpid()}.npy"
    with replaced_atomically(path) as tmp, open(tmp, "wb") as f:  # a file object: np.save adds no suffix
        np.save(f, volume)
    return path


def _dask_client(command: Any, backend: dict[str, Any]):
    """The Dask client of ``--scheduler`` or ``--workers`` (a context manager), or none."""
    if command.scheduler is None and command.workers is None:
        return contextlib.nullcontext()
    if command.scheduler is not None and command.workers is not None:
        raise InputError(f"--scheduler {command.scheduler} and --workers {command.workers}: give one (a running "
                         "Dask scheduler, or local worker processes for this run)")
    if backend.get("tile") is None:
        raise InputError("--scheduler and --workers run the tiles of every set on Dask workers: give --tile N too")
    from ..ml.distributed import dask_client

    return dask_client(command.scheduler, command.workers)


# ----------------------------------------------------------------------------- the run


def run_synth(given: dict[str, Any]) -> int:
    """``clsolid synth`` with the flags *given*; returns the exit status."""
    from ..api import resume, slice_plan, synthesize
    from ..core.slices import preview_depths
    from ..exemplar import each, load_exemplars
    from ..preview import save_preview, save_site_map
    from ..volumeio import check_calibration, check_rgb_output, save_volume

    settings = resolve(given)
    cmd, backend = settings.command, dict(settings.backend)
    BackendOptions(**backend)  # its checks (a folder path is a path) before check_outputs reads it
    voxel_size, unit, voxel_from = _voxel_size(cmd)
    check_calibration(voxel_size, unit or "um", Path(cmd.output))  # now, not after the run
    check_outputs(cmd, backend)
    image = None if cmd.resume is not None else load_exemplars(_exemplar_source(cmd, settings.origin),
                                                               builtin_size=cmd.builtin_size)
    for exemplar in each(image):
        check_rgb_output(cmd.output, exemplar)  # now, not after the run
    hooks = [] if cmd.quiet else [render_progress]
    records: list = []
    if cmd.track is not None:
        levels = settings.method_options.get("levels", 32)
        hooks.append(_tracker(256 if levels is None else levels, records))
    report = (lambda info: [h(info) for h in hooks]) if hooks else None
    with _dask_client(cmd, backend) as client:
        if client is not None:
            backend["client"] = client
        options = BackendOptions(**backend) if cmd.method == "ml" else None
        if cmd.resume is not None:
            result = resume(cmd.resume, device=cmd.device, backend=options, progress=report, full_output=True)
        else:
            colour = any(im.ndim == 3 for im in each(image))
            result = synthesize(image, cmd.shape, method=cmd.method, rng=cmd.seed, device=cmd.device,
                                backend=options, progress=report, full_output=True,
                                site_map=cmd.site_map is not None, channel_axis=-1 if colour else None,
                                **settings.method_options)
    kind = "indices" if cmd.indices else "values"
    volume = result.labels if cmd.indices else result.volume
    output = Path(cmd.output)
    try:
        written = save_volume(output, volume, voxel_size=voxel_size, unit=unit or "um",
                              metadata={"seed": result.seed, "written": kind, "levels": len(result.level_values)})
    except OSError as exc:  # checked writable before the run: a full disk, a vanished mount
        try:
            rescued = _rescue(volume, result.seed)
        except OSError as again:
            raise OutputError(f"--output {output} could not be written ({exc}), nor could the volume be saved in "
                              f"{tempfile.gettempdir()} ({again}); free some space and run again (the same --seed "
                              "gives the same volume)") from exc
        raise OutputError(f"--output {output} could not be written ({exc}); the volume is saved in "
                          f"{rescued}") from exc
    try:
        others = _write_the_rest(cmd, settings, result, written, voxel_size, unit, voxel_from, records,
                                 save_preview, save_site_map, slice_plan, preview_depths)
    except OSError as exc:
        raise OutputError(f"the volume is in {written}, but a file beside it could not be written ({exc})") from exc
    if not cmd.quiet:
        files = others[0] if len(others) == 1 else f"{', '.join(others[:-1])} and {others[-1]}"
        print(f"wrote {written} ({'x'.join(map(str, result.volume.shape))} {kind}, seed {result.seed}, "
              f"{result.timings['total_s']:.1f}s on {result.device}), {files}", file=sys.stderr)
    return 0


def _exemplar_source(cmd: Any, origin: dict[str, str]) -> str | dict[str, str]:
    """EXEMPLAR, or the views' own exemplars (``--front``, ``--right``, ``--top``): never both."""
    views = {v: getattr(cmd, v) for v in VIEW_ORDER if getattr(cmd, v) is not None}
    if not views:
        return cmd.exemplar
    if "exemplar" in origin:
        raise InputError(f"EXEMPLAR {cmd.exemplar!r} and {', '.join('--' + v for v in views)} both given: give one "
                         "exemplar for every view, or an exemplar per view (two or three of --front, --right, --top)")
    return views


def _write_the_rest(cmd, settings, result, written, voxel_size, unit, voxel_from, records, save_preview,
                    save_site_map, slice_plan, preview_depths) -> list[str]:
    """The sidecar, the preview and the maps; what was written, in words."""
    from ..exemplar import BUILTINS, each

    sidecar = _sidecar(written)
    source = _exemplar_source(cmd, settings.origin) if cmd.resume is None else None
    named = each(source)
    meta = {"volume": str(written), "exemplar": source if source is None or isinstance(source, dict) else str(source),
            "builtin_size": cmd.builtin_size if source is not None and any(n in BUILTINS for n in named) else None,
            "resumed_from": None if cmd.resume is None else str(cmd.resume),
            "written": "indices" if cmd.indices else "values",
            "values_exact": result.values_exact, "level_values": result.level_values.tolist(),
            "seed": result.seed, "device": result.device, "preset": cmd.preset, "params": result.params,
            "voxel_size": voxel_size, "unit": unit, "voxel_size_from": voxel_from,
            "versions": versions(), "timings": result.timings,
            "command": " ".join(sys.argv), "written_at": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    write_text_atomically(sidecar, json.dumps(meta, indent=2, default=float))
    others = [str(sidecar)]
    if cmd.preview is not None:
        plan = slice_plan(result.params)  # away from the +in (or anchor) slices, which show the exemplar
        preview = save_preview(cmd.preview, result.exemplar, result.volume, constrained=plan.view_names,
                               depths=preview_depths(result.volume.shape, plan))
        others.append(f"{preview} (slices enlarged {_enlargement(result.volume.shape)}x)"
                      if _enlargement(result.volume.shape) > 1 else str(preview))
    if cmd.site_map is not None:
        save_site_map(cmd.site_map, result.site_use)
        others.append(str(cmd.site_map))
    if cmd.source_map is not None:
        import numpy as np

        with replaced_atomically(cmd.source_map) as tmp, open(tmp, "wb") as f:
            np.save(f, result.source)
        others.append(str(cmd.source_map))
    if cmd.track is not None:
        write_text_atomically(cmd.track, json.dumps({"exemplar": meta["exemplar"], "seed": result.seed,
                                                     "records": records}, indent=2))
        others.append(str(cmd.track))
    return others


def _enlargement(shape: tuple[int, ...]) -> int:
    """How many times the preview enlarges the block's slices (nearest neighbour), as it lays them out."""
    from ..preview import PREVIEW_MIN_SIDE

    return max(1, math.ceil(PREVIEW_MIN_SIDE / max(shape)))


def _fmt_time(s: float) -> str:
    if s != s:  # NaN: not known yet
        return "?"
    return f"{s:.0f}s" if s < 120 else f"{s / 60:.1f}min"


def render_progress(info: Any) -> None:
    """One stderr line per sweep: scale, sweep, global temperature, elapsed, ETA."""
    z, y, x = info.shape
    temp = "" if math.isnan(info.temperature) else f"T={info.temperature:.0f} (stop at {info.target:.0f})  "
    print(f"scale {info.scale}/{info.n_scales} ({z}x{y}x{x})  sweep {info.sweep:>2}  "
          f"{temp}visited {info.visited}  "
          f"elapsed {_fmt_time(info.elapsed)}  ETA {_fmt_time(info.eta)}", file=sys.stderr, flush=True)


def versions() -> dict[str, str]:
    """The versions a sidecar records."""
    import numpy
    import pyopencl

    return {"clsolid": __version__, "numpy": numpy.__version__, "pyopencl": pyopencl.VERSION_TEXT,
            "python": platform.python_version(), "platform": platform.platform()}


def _tracker(levels: int, records: list):
    """A progress hook that evaluates the block after every sweep (``--track``)."""
    from .. import metrics

    def track(info: Any) -> None:
        vol = info.volume()
        ind = {}
        for view in ("front", "right"):
            ex = info.exemplar.get(view) if isinstance(info.exemplar, dict) else info.exemplar  # per view: its own
            if ex is None:
                continue
            sl = metrics.view_slices(vol, view, max_slices=8)
            ind[f"autocorrelation_{view}"] = float(metrics.autocorrelation_distance(ex, sl))
            ind[f"histogram_kl_{view}"] = float(metrics.histogram_distance(ex, sl, bins=levels, value_range=(0, levels)))
        records.append({"scale": info.scale, "sweep": info.sweep, "temperature": info.temperature,
                        "elapsed": info.elapsed, "indicators": ind})

    return track


