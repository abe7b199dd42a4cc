"""Where a run keeps its whole-block arrays: in memory, or in memory-mapped files on disk.

A tiled run keeps the whole block's state on the host: its values, temperatures
and sources, 16 bytes a voxel with two views, and at the start of each scale the random start
and the start state beside them; the driver's trusted and visited masks and the balance's
labels, a byte a voxel each. In memory that bounds the block by the host's memory
(512^3 takes about 6 GB, 1024^3 about 48). With a scratch folder those arrays are
``numpy.memmap`` files there instead, which the operating system pages in and out: the block
is bounded by the disk, and by the memory the arrays that stay in memory take (about a byte
a voxel; docs/user-guide/large-volumes.md). The arrays are the same either way, so the volume is too. The
run's result is made there as well, in nameless files that live as long as its arrays
(:func:`kept_memmap`), and :func:`clsolid.volumeio.save_volume` writes it a plane at a time.

Every conflict-free set spreads over the whole block, so a sweep reads and writes the whole
state once per set; where the state is larger than the memory left for the page cache each
set streams it from the disk. On a CPU the compute of a sweep at such sizes outweighs that
(docs/design.md#region-order); on a fast device the disk may set the pace.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from typing import Any, Callable

import numpy as np

from ..errors import InputError
from .hostmemory import SCRATCH_BYTES_PER_VOXEL

#: Most elements :meth:`Scratch.apply` computes at once.
_RUN_ELEMENTS = 1 << 22


class Scratch:
    """Allocates a run's whole-block arrays in memory (*folder* None) or as files in a fresh
    folder made under *folder* when the first is allocated (so that a run refused before it
    allocates leaves nothing behind), removed by :meth:`close` (also on leaving a ``with``)."""

    def __init__(self, folder: str | os.PathLike | None = None) -> None:
        self.root = None if folder is None else check_folder(folder)
        self.folder: str | None = None  # made by the first empty()
        self._count = 0

    @property
    def on_disk(self) -> bool:
        """Whether the arrays are files."""
        return self.root is not None

    def empty(self, shape: Any, dtype: Any, kept: bool = False) -> np.ndarray:
        """An uninitialised array (a ``numpy.memmap`` on disk). A *kept* one outlives the
        folder (a run's result): see :func:`kept_memmap`."""
        if self.root is None:
            return np.empty(shape, dtype)
        if kept:
            return kept_memmap(self.root, shape, dtype)
        if self.folder is None:
            self.folder = tempfile.mkdtemp(prefix="clsolid-scratch-", dir=self.root)
        self._count += 1
        path = os.path.join(self.folder, f"array{self._count}.dat")
        return np.memmap(path, dtype=dtype, mode="w+", shape=tuple(np.atleast_1d(shape)))

    def full(self, shape: Any, value: float, dtype: Any) -> np.ndarray:
        """An array of *value*."""
        out = self.empty(shape, dtype)
        out[...] = value
        return out

    def copy(self, source: np.ndarray, dtype: Any) -> np.ndarray:
        """*source* as *dtype*, as ``astype`` gives it (the assignment casts in small buffers:
        no whole temporary)."""
        out = self.empty(source.shape, dtype)
        out[...] = source
        return out

    def apply(self, fn: Callable[..., np.ndarray], dtype: Any, *arrays: np.ndarray, kept: bool = False,
              trailing: tuple[int, ...] = ()) -> np.ndarray:
        """``fn(*arrays)`` as a new array of *dtype* (*kept*: as :meth:`empty`), computed a run
        of planes (first axis) at a time, so that no whole temporary of ``fn``'s is made; *fn*
        may add *trailing* axes (a colour's channels)."""
        out = self.empty(arrays[0].shape + tuple(trailing), dtype, kept)
        plane = max(1, int(np.prod(arrays[0].shape[1:])))
        run = max(1, _RUN_ELEMENTS // plane)
        for lo in range(0, arrays[0].shape[0], run):
            out[lo: lo + run] = fn(*(a[lo: lo + run] for a in arrays))
        return out

    def free(self, array: Any) -> None:
        """Give back the disk of an array of this scratch that is no longer used (its file goes
        now; the mapping, and the space, when the last reference does). In memory: nothing."""
        name = getattr(array, "filename", None)
        if self.folder is not None and name and os.path.dirname(os.path.abspath(name)) == self.folder:
            try:
                os.remove(name)
            except OSError:  # a system that keeps a mapped file: close() takes it
                pass

    def close(self) -> None:
        """Remove the folder and every file left in it."""
        if self.folder is not None:
            shutil.rmtree(self.folder, ignore_errors=True)
            self.folder = None

    def __enter__(self) -> "Scratch":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def kept_memmap(root: str, shape: Any, dtype: Any) -> np.memmap:
    """A ``numpy.memmap`` on a new temporary file in *root* that lives as long as the array
    does (the mapping holds its own handle): a result larger than memory, which the caller
    saves, or drops, when it likes. The file has no name in *root* (POSIX; on Windows it is
    deleted when the last handle closes), so even a killed process leaves nothing behind."""
    with tempfile.TemporaryFile(prefix="clsolid-result-", dir=root) as handle:
        return np.memmap(handle, dtype=dtype, mode="w+", shape=tuple(np.atleast_1d(shape)))


def check_folder(folder: str | os.PathLike) -> str:
    """*folder* as an absolute path; refuse (:class:`~clsolid.errors.InputError`) one that is
    not an existing, writable folder."""
    path = os.path.abspath(os.fspath(folder))
    if not os.path.isdir(path):
        raise InputError(f"scratch folder {path!r} does not exist; make it first, on a disk with room for the "
                         f"block's state (about {SCRATCH_BYTES_PER_VOXEL} bytes a voxel)")
    if not os.access(path, os.W_OK | os.X_OK):
        raise InputError(f"scratch folder {path!r} is not writable; choose another")
    return path
