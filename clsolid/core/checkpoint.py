"""Checkpoint folders: a run's arrays and description, written so that a crash never leaves
a half-written checkpoint behind.

A checkpoint is a folder holding ``state.npz`` (the arrays) and ``checkpoint.json`` (what
the run is, and the SHA-256 of ``state.npz``). Both are written to temporary names and
renamed into place, the description last, so the folder always holds the last complete
checkpoint: a run stopped at any moment (Ctrl-C, a crash, a lost machine) can be resumed
from it. Reading checks the format and the digest and says plainly what is wrong.
"""

from __future__ import annotations

import hashlib
import json
import os
import zipfile
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..errors import InputError

#: Version of the folder's layout; a checkpoint of another version is refused.
FORMAT = 1
STATE = "state.npz"
META = "checkpoint.json"


class CheckpointError(InputError):
    """A checkpoint folder that is missing, corrupt, or not for this run."""


def _digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def write_checkpoint(folder: str | os.PathLike, meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> Path:
    """Write *arrays* and the JSON-able *meta* into *folder* (created), replacing what was there."""
    d = Path(folder)
    d.mkdir(parents=True, exist_ok=True)
    tmp_state, tmp_meta = d / (STATE + ".tmp"), d / (META + ".tmp")
    with open(tmp_state, "wb") as f:
        np.savez(f, **arrays)
    full = {**meta, "format": FORMAT, "state_sha256": _digest(tmp_state)}
    tmp_meta.write_text(json.dumps(full, indent=1))
    os.replace(tmp_state, d / STATE)
    os.replace(tmp_meta, d / META)
    return d


#: Bytes of an array read from ``state.npz`` at once.
_READ_BLOCK = 1 << 24


def _read_member(z: zipfile.ZipFile, name: str, empty: Callable[[tuple, np.dtype], np.ndarray]) -> np.ndarray:
    """Array *name* of ``state.npz`` (an ``.npy`` file in the zip), read into ``empty(shape, dtype)``."""
    with z.open(name) as f:
        version = np.lib.format.read_magic(f)
        read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, fortran, dtype = read_header(f)
        if fortran or dtype.hasobject:
            raise ValueError(f"{name} is not a C-ordered array of numbers")
        out = empty(shape, dtype)
        raw = out.reshape(-1).view(np.uint8)
        for lo in range(0, raw.size, _READ_BLOCK):
            part = raw[lo: lo + _READ_BLOCK]
            if f.readinto(memoryview(part)) != part.size:
                raise ValueError(f"{name} ends early")
    return out


def read_checkpoint(folder: str | os.PathLike, empty: Callable[[tuple, np.dtype], np.ndarray] = np.empty
                    ) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The meta (as given to :func:`write_checkpoint`) and arrays of a checkpoint folder,
    each read a block at a time into ``empty(shape, dtype)`` (such as a scratch folder's
    :meth:`~clsolid.core.scratch.Scratch.empty`, so that a block larger than memory resumes).

    Raises
    ------
    CheckpointError
        No checkpoint there, another format, or arrays that do not match their digest.
    """
    d = Path(folder)
    if not (d / META).is_file() or not (d / STATE).is_file():
        raise CheckpointError(f"{d} holds no checkpoint (no {META} and {STATE}); start the run with "
                              "checkpoint= (--checkpoint) to make one")
    try:
        meta = json.loads((d / META).read_text())
    except (OSError, ValueError) as exc:
        raise CheckpointError(f"{d / META} is not readable JSON ({exc}): the checkpoint is corrupt") from None
    if meta.get("format") != FORMAT:
        raise CheckpointError(f"{d} is a checkpoint of format {meta.get('format')!r}; this clsolid reads "
                              f"format {FORMAT}")
    if _digest(d / STATE) != meta.get("state_sha256"):
        raise CheckpointError(f"{d / STATE} does not match the digest in {META}: the checkpoint is corrupt "
                              "(it was changed or only partly copied)")
    try:
        with zipfile.ZipFile(d / STATE) as z:
            arrays = {name.removesuffix(".npy"): _read_member(z, name, empty) for name in z.namelist()}
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        raise CheckpointError(f"{d / STATE} cannot be read ({exc}): the checkpoint is corrupt") from None
    return {k: v for k, v in meta.items() if k not in ("format", "state_sha256")}, arrays
