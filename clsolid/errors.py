"""Exception hierarchy: every message says what was wrong, with which value, and what to do."""

from __future__ import annotations


class ClsolidError(Exception):
    """Base class of every error clsolid raises on purpose."""


class InputError(ClsolidError, ValueError):
    """A parameter or an input array is not acceptable."""


class NoDeviceError(ClsolidError, RuntimeError):
    """No usable OpenCL platform or device."""


class DeviceMemoryError(ClsolidError, MemoryError):
    """A buffer would exceed the device's allocation limits (checked before allocating)."""

    def __init__(self, buffer: str, nbytes: int, limit: int, what: str = "max_mem_alloc_size"):
        self.buffer, self.nbytes, self.limit = buffer, int(nbytes), int(limit)
        super().__init__(
            f"buffer '{buffer}' needs {nbytes / 2**20:.1f} MiB ({nbytes} bytes) but the device's "
            f"{what} is {limit / 2**20:.1f} MiB ({limit} bytes); use a smaller shape or fewer "
            "grey levels, or choose a device with more memory (--device)"
        )


class KernelBuildError(ClsolidError, RuntimeError):
    """An OpenCL program failed to compile on the chosen device."""


class DeviceSkippedWarning(UserWarning):
    """Automatic device selection passed over a device that cannot compile kernels."""
