"""``--config FILE``: a run's settings from a TOML file or from a finished run's sidecar JSON."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from ..api import METHODS
from ..core.tomlfile import read_toml
from ..errors import InputError
from ..exemplar import BUILTINS

#: Keys of a TOML config that document it and set nothing (a preset's source and departures).
ABOUT = "about"


def read_config(path: Path) -> dict[str, Any]:
    """The settings in *path*, by option name (the flags' names with underscores).

    A ``.toml`` file holds option names and values at its top level (a ``[about]`` table is
    documentation); a ``.json`` file is the sidecar a ``clsolid synth`` run wrote beside its
    volume, whose exemplar, seed, method, shape and effective parameters are taken, so that
    the same run can be made again (bit for bit on the same device).
    """
    suffix = path.suffix.lower()
    if suffix == ".toml":
        data = read_toml(path)
        return {k: v for k, v in data.items() if k != ABOUT}
    if suffix == ".json":
        return sidecar_settings(path)
    raise InputError(f"--config {path} must be a .toml file or a run's sidecar .json")


def sidecar_settings(path: Path) -> dict[str, Any]:
    """The settings that grow the volume a sidecar describes again."""
    try:
        meta = json.loads(path.read_text())
    except OSError as exc:
        raise InputError(f"--config {path}: cannot be read ({exc.strerror or exc})") from None
    except ValueError as exc:
        raise InputError(f"--config {path}: not valid JSON ({exc})") from None
    params = meta.get("params") if isinstance(meta, dict) else None
    if not isinstance(params, dict) or "method" not in params:
        raise InputError(f"--config {path} is not the sidecar of a clsolid synth run (no 'params' with a 'method')")
    if meta.get("exemplar") is None:
        raise InputError(f"--config {path} describes a resumed run; go on from its checkpoint with --resume")
    missing = [f"'{k}'" for k in ("seed",) if k not in meta] + [f"params '{k}'" for k in ("shape",) if k not in params]
    if meta.get("voxel_size_from") == "--voxel-size" and "voxel_size" not in meta:
        missing.append("'voxel_size'")
    if missing:
        raise InputError(f"--config {path} lacks {', '.join(missing)}: not the whole sidecar of a clsolid synth run")
    method = params["method"]
    if not isinstance(method, str) or method not in METHODS:
        raise InputError(f"--config {path}: method {method!r} is not available; use one of {tuple(METHODS)}")
    cls = METHODS[method]
    try:  # the parameters as the run took them (records older than an option read as they ran)
        recorded = cls.from_dict(params).to_dict()
    except (TypeError, InputError) as exc:
        raise InputError(f"--config {path}: its parameters are not valid ({exc})") from None
    source = meta["exemplar"]  # a path or name, or one per view
    given = source if isinstance(source, dict) else {"exemplar": source}
    settings = {**given, "method": method, "shape": params["shape"], "seed": meta["seed"],
                **{k: v for k, v in recorded.items() if k != "method"}}
    if any(isinstance(n, str) and n in BUILTINS for n in given.values()):
        settings["builtin_size"] = meta.get("builtin_size", 64)
    if meta.get("written") == "indices":
        settings["indices"] = True
    if meta.get("voxel_size_from") == "--voxel-size":
        size = meta["voxel_size"]
        settings["voxel_size"] = list(size) if isinstance(size, (list, tuple)) else [size]
        settings["unit"] = meta.get("unit")
    return settings
