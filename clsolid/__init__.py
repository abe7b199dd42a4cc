"""clsolid: solid textures grown from a 2D exemplar, on OpenCL.

Importing clsolid does not touch OpenCL; a device is chosen when a synthesis runs
(:func:`select_device`, the ``device=`` argument, ``$CLSOLID_DEVICE`` or ``$PYOPENCL_CTX``).
"""

from ._version import __version__
from .api import resume, synthesize
from .core.device import Device, list_devices, select_device
from .core.synthesis import SweepInfo, SynthesisResult
from .errors import (
                     ClsolidError,
                     DeviceMemoryError,
                     DeviceSkippedWarning,
                     ExemplarWarning,
                     HostMemoryError,
                     InputError,
                     KernelBuildError,
                     LargeTiffWarning,
                     NoDeviceError,
)
from .ml.backends import BackendOptions
from .ml.params import HEURISTICS, MLParams
from .search.params import SearchParams

__all__ = [
    "synthesize", "resume", "MLParams", "SearchParams", "BackendOptions", "select_device", "list_devices",
    "Device", "SweepInfo", "SynthesisResult", "HEURISTICS", "ClsolidError", "InputError", "NoDeviceError",
    "DeviceMemoryError", "HostMemoryError", "KernelBuildError", "DeviceSkippedWarning", "ExemplarWarning",
    "LargeTiffWarning", "__version__",
]
