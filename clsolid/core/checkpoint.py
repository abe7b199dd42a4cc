"""Checkpoint folders: a run's arrays and description, written so that a crash never leaves
a half-written checkpoint behind.

A checkpoint is a folder holding ``checkpoint.json`` (what the run is, and the name and
SHA-256 of the file of its arrays) and that file, ``state-<id>.npz``. Each write puts the
arrays in a new file, then renames the new description over the old one: that one atomic
rename commits the checkpoint, so the folder always holds the last complete checkpoint and a
run stopped at any moment (Ctrl-C, a kill, a crash, a lost machine) can be resumed from it.
Both files reach the disk before the rename. Reading checks the format and the digest and
says plainly what is wrong.
"""

from __future__ import annotations

import hashlib
import json
import contextlib
import os
import uuid
import zipfile
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..errors import InputError
from .files import replaced_atomically, write_text_atomically

#: Version of the folder's layout that is written.
FORMAT = 2
#: Versions read; another is refused. Format 1 kept its arrays in ``state.npz`` (:data:`STATE`).
READ_FORMATS = (1, 2)
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
    """Write *arrays* and the JSON-able *meta* into *folder* (created), replacing what was there.

    The arrays go to a file of a new name and the description naming it replaces the last
    one: never are the old description and the new arrays (or the reverse) the folder's
    checkpoint. The files of earlier checkpoints, and those of writes that were killed, are
    removed after.
    """
    d = Path(folder)
    d.mkdir(parents=True, exist_ok=True)
    state = f"state-{uuid.uuid4().hex[:12]}.npz"
    with replaced_atomically(d / state) as tmp:
        with open(tmp, "wb") as f:
            np.savez(f, **arrays)
    full = {**meta, "format": FORMAT, "state": state, "state_sha256": _digest(d / state)}
    write_text_atomically(d / META, json.dumps(full, indent=1))
    for old in [*d.glob("state*.npz"), *d.glob(".state-*.partial"), *d.glob(f".{META}.*.partial")]:
        if old.name != state:
            with contextlib.suppress(OSError):  # a file left over only costs its space
                old.unlink()
    return d


def state_file(folder: str | os.PathLike) -> Path:
    """The file of a checkpoint folder's arrays, as its description names it.

    Raises
    ------
    CheckpointError
        No checkpoint there, or one of a format this clsolid does not read.
    """
    return _state_file(Path(folder), _read_meta(Path(folder)))


def _read_meta(d: Path) -> dict[str, Any]:
    if not (d / META).is_file():
        raise CheckpointError(f"{d} holds no checkpoint (no {META}); start the run with checkpoint= "
                              "(--checkpoint) to make one")
    try:
        meta = json.loads((d / META).read_text())
    except (OSError, ValueError) as exc:
        raise CheckpointError(f"{d / META} is not readable JSON ({exc}): the checkpoint is corrupt") from None
    if not isinstance(meta, dict) or meta.get("format") not in READ_FORMATS:
        fmt = meta.get("format") if isinstance(meta, dict) else None
        raise CheckpointError(f"{d} is a checkpoint of format {fmt!r}; this clsolid reads format "
                              f"{' or '.join(map(str, READ_FORMATS))}")
    return meta


def _state_file(d: Path, meta: dict[str, Any]) -> Path:
    name = meta.get("state", STATE) if meta["format"] >= 2 else STATE
    if not isinstance(name, str) or Path(name).name != name or not (d / name).is_file():
        raise CheckpointError(f"{d}: the file of arrays {META} names ({name!r}) is missing: the checkpoint is "
                              "corrupt (it was changed or only partly copied)")
    return d / name


#: Bytes of an array read from the file of arrays at once.
_READ_BLOCK = 1 << 24


def _read_member(z: zipfile.ZipFile, name: str, empty: Callable[[tuple, np.dtype], np.ndarray]) -> np.ndarray:
    """Array *name* of the file of arrays (an ``.npy`` file in the zip), read into ``empty(shape, dtype)``."""
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
    meta = _read_meta(d)
    state = _state_file(d, meta)
    if _digest(state) != meta.get("state_sha256"):
        raise CheckpointError(f"{state} does not match the digest in {META}: the checkpoint is corrupt "
                              "(it was changed or only partly copied)")
    try:
        with zipfile.ZipFile(state) as z:
            arrays = {name.removesuffix(".npy"): _read_member(z, name, empty) for name in z.namelist()}
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        raise CheckpointError(f"{state} cannot be read ({exc}): the checkpoint is corrupt") from None
    return {k: v for k, v in meta.items() if k not in ("format", "state", "state_sha256")}, arrays
