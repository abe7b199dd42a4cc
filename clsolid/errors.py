"""Exception hierarchy: every message says what was wrong, with which value, and what to do."""

from __future__ import annotations


class ClsolidError(Exception):
    """Base class of every error clsolid raises on purpose.

    Each class says what it means and the command line's exit status for it
    (``exit_code``; the table of every status is :data:`EXIT_CODES`).
    """

    exit_code = 1


class InputError(ClsolidError, ValueError):
    """A parameter or an input array is not acceptable."""

    exit_code = 2


class NoDeviceError(ClsolidError, RuntimeError):
    """No usable OpenCL platform or device."""

    exit_code = 3


class DeviceMemoryError(ClsolidError, MemoryError):
    """A buffer would exceed the device's allocation limits (checked before allocating).

    *what* names the limit; *advice* says what to do (by default: a smaller shape, fewer
    grey levels or another device).
    """

    ADVICE = "use a smaller shape or fewer grey levels, or choose a device with more memory (--device)"
    exit_code = 4

    def __init__(self, buffer: str, nbytes: int, limit: int, what: str = "max_mem_alloc_size",
                 advice: str | None = None):
        self.buffer, self.nbytes, self.limit, self.what = buffer, int(nbytes), int(limit), what
        self.advice = advice
        super().__init__(
            f"buffer '{buffer}' needs {nbytes / 2**20:.1f} MiB ({nbytes} bytes) but the device's "
            f"{what} is {limit / 2**20:.1f} MiB ({limit} bytes); {advice or self.ADVICE}"
        )

    def __reduce__(self):  # rebuilt from its fields where it crosses processes (a Dask worker's)
        return type(self), (self.buffer, self.nbytes, self.limit, self.what, self.advice)

    def advised(self, advice: str) -> "DeviceMemoryError":
        """The same error with other *advice*."""
        return DeviceMemoryError(self.buffer, self.nbytes, self.limit, self.what, advice)


class HostMemoryError(ClsolidError, MemoryError):
    """A block would take more host memory than is available (checked before allocating;
    :mod:`clsolid.core.hostmemory`)."""

    exit_code = 4

    def __init__(self, shape: tuple[int, int, int], need: int, have: int, per_voxel: int, exemplar: int = 0,
                 hint: str = ""):
        self.shape, self.need, self.have, self.per_voxel = tuple(shape), int(need), int(have), int(per_voxel)
        self.exemplar, self.hint = int(exemplar), hint
        tables = (f", and {self.exemplar / 2**30:.1f} GiB of it the exemplar's windows at every scale "
                  "(a smaller exemplar needs less)") if self.exemplar else ""
        super().__init__(
            f"a {'x'.join(map(str, self.shape))} block needs about {need / 2**30:.1f} GiB of host memory "
            f"(about {per_voxel} bytes a voxel: the host keeps the whole block and its state, tiled or "
            f"not{tables}), but {have / 2**30:.1f} GiB is available; grow a smaller block, free memory{hint} or use "
            "a machine with more (CLSOLID_HOST_MEMORY=64G overrides the figure available, as with swap)"
        )

    def __reduce__(self):
        return type(self), (self.shape, self.need, self.have, self.per_voxel, self.exemplar, self.hint)


class KernelBuildError(ClsolidError, RuntimeError):
    """An OpenCL program failed to compile on the chosen device."""

    exit_code = 5


class MissingDependencyError(ClsolidError, ImportError):
    """An optional package that a feature needs is not installed (matplotlib for plots, dask for workers);
    the message says what to install."""

    exit_code = 6


class OutputError(ClsolidError, OSError):
    """A result could not be written after the run (a full disk, a vanished mount); the message
    says where the volume was saved instead."""

    exit_code = 7


class DeviceSkippedWarning(UserWarning):
    """Automatic device selection passed over a device that cannot compile kernels."""


class ExemplarWarning(UserWarning):
    """An exemplar that can be grown but will not give what its user likely wants (a constant image)."""


class LargeTiffWarning(UserWarning):
    """A TIFF above 4 GiB was written in ImageJ's large-file form, which only some readers open whole."""


#: The command line's exit statuses: status -> what it means.
EXIT_CODES: dict[int, str] = {
    0: "success",
    1: "an unexpected error: a bug in clsolid (run again with --debug for the traceback, and report it)",
    InputError.exit_code: "a usage or input error: a bad flag or value, an unreadable exemplar, an output "
                          "path that cannot be written (checked before the run)",
    NoDeviceError.exit_code: "no OpenCL device can run the kernels",
    DeviceMemoryError.exit_code: "the block does not fit the device's or the host's memory (refused before "
                                 "allocating)",
    KernelBuildError.exit_code: "a kernel failed to build on the chosen device",
    MissingDependencyError.exit_code: "an optional package is missing (matplotlib for --plot, dask for --workers)",
    OutputError.exit_code: "the run finished but its output could not be written; the volume was saved "
                           "elsewhere (the message says where)",
    130: "interrupted (Ctrl-C); a checkpointed run can be resumed",
}
