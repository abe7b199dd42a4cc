"""Exception hierarchy: every message says what was wrong, with which value, and what to do."""

from __future__ import annotations


class ClsolidError(Exception):
    """Base class of every error clsolid raises on purpose."""


class InputError(ClsolidError, ValueError):
    """A parameter or an input array is not acceptable."""


class NoDeviceError(ClsolidError, RuntimeError):
    """No usable OpenCL platform or device."""


class DeviceMemoryError(ClsolidError, MemoryError):
    """A buffer would exceed the device's allocation limits (checked before allocating).

    *what* names the limit; *advice* says what to do (by default: a smaller shape, fewer
    grey levels or another device).
    """

    ADVICE = "use a smaller shape or fewer grey levels, or choose a device with more memory (--device)"

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


class DeviceSkippedWarning(UserWarning):
    """Automatic device selection passed over a device that cannot compile kernels."""


class LargeTiffWarning(UserWarning):
    """A TIFF above 4 GiB was written in ImageJ's large-file form, which only some readers open whole."""
