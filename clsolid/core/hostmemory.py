"""The host's memory, checked before a run allocates anything.

The host keeps the whole block while it is grown (its values, and per voxel the method's
state: temperatures, sources, matches, the driver's copies), tiled or not: tiles bound the
device's memory, not the host's. A block larger than the host's free memory would be
killed by the system, often at the finest scale, hours in; it is refused at once instead.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from ..errors import HostMemoryError, InputError
from .geometry import window_grid


@dataclass(frozen=True)
class Footprint:
    """What a run keeps on the host, as each method declares it.

    Attributes
    ----------
    per_voxel : int
        Bytes a voxel of the full-resolution block costs at the run's peak: the growth of
        peak RSS with the block, measured where device buffers are host memory, with room
        kept above it (docs/design.md#host-memory).
    per_exemplar_term : int
        Bytes each term of the exemplar's windows costs (:func:`exemplar_terms`); 0: not counted.
    advice : str
        What else the user can do when the block does not fit (a clause, ", ..." form).
    """

    per_voxel: int
    per_exemplar_term: int = 0
    advice: str = ""


#: Disk bytes a voxel of a tiled likelihood run with a scratch folder takes there at its
#: peak (:mod:`clsolid.core.scratch`): the random start (4) and the finest scale's start state
#: (4 + 8) beside the back end's state (4 + 4 + 4 a view), and the coarser scales' 1/7 more.
SCRATCH_BYTES_PER_VOXEL = 40

#: Environment variable that overrides the memory thought available (bytes, or with a
#: K, M, G or T suffix): where the system's figure is wrong for a run (swap, a cgroup).
ENV = "CLSOLID_HOST_MEMORY"


def parse_bytes(text: str) -> int:
    """``"64G"`` -> 64 * 2**30; a plain number is bytes. Refuses anything else."""
    units = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}
    t = text.strip().upper().removesuffix("B").removesuffix("I")
    unit = t[-1:] if t[-1:] in units else ""
    try:
        value = float(t[: len(t) - len(unit)])
    except ValueError:
        value = -1.0
    if not value >= 0 or not np.isfinite(value):
        raise InputError(f"{ENV}={text!r} must be a size in bytes, such as 68719476736 or 64G")
    return int(value * units[unit])


def available_bytes() -> int | None:
    """Memory a run may take: ``$CLSOLID_HOST_MEMORY`` if set, else the system's available
    memory (``MemAvailable`` of ``/proc/meminfo``, or free pages); None if unknown."""
    if os.environ.get(ENV):
        return parse_bytes(os.environ[ENV])
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def check_host_memory(shape: tuple[int, int, int], footprint: Footprint, exemplar_terms: int = 0) -> None:
    """Refuse (:class:`~clsolid.errors.HostMemoryError`) a *shape* block whose run would take
    more host memory than is available, by the method's *footprint*, counting *exemplar_terms*
    (:func:`exemplar_terms`) at its bytes a term."""
    exemplar = int(exemplar_terms) * footprint.per_exemplar_term
    need = math.prod(shape) * footprint.per_voxel + exemplar  # Python ints: a huge shape must not wrap
    have = available_bytes()
    if have is not None and need > have:
        raise HostMemoryError(shape, need, have, footprint.per_voxel, exemplar, footprint.advice)


def check_scratch_space(shape: tuple[int, int, int], folder: str) -> None:
    """Refuse (:class:`~clsolid.errors.InputError`) a scratch *folder* whose disk has less room
    than a *shape* block's state takes there (:data:`SCRATCH_BYTES_PER_VOXEL`)."""
    import shutil

    need = math.prod(shape) * SCRATCH_BYTES_PER_VOXEL
    free = shutil.disk_usage(folder).free
    if need > free:
        raise InputError(f"a {'x'.join(map(str, shape))} block keeps about {need / 2**30:.1f} GiB of state in the "
                         f"scratch folder {folder!r} (about {SCRATCH_BYTES_PER_VOXEL} bytes a voxel), but its disk "
                         f"has {free / 2**30:.1f} GiB free; free space there or choose a folder on a larger disk")


def exemplar_terms(exemplar_shape: tuple[int, int], neighborhood: int) -> int:
    """The terms of an exemplar's windows at its finest scale: its sites (every window inside
    it) times the window's neighbours (``neighborhood^2 - 1``)."""
    rows, cols = window_grid(exemplar_shape, neighborhood)
    return rows * cols * (neighborhood * neighborhood - 1)
