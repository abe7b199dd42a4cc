"""clsolid: solid textures grown from a 2D exemplar, on OpenCL.

Importing clsolid does not touch OpenCL; a device is chosen when a synthesis runs
(:func:`select_device`, the ``device=`` argument, ``$CLSOLID_DEVICE`` or ``$PYOPENCL_CTX``).
"""

from .api import resume, synthesize
from .core.device import Device, list_devices, select_device
from .errors import (ClsolidError, DeviceMemoryError, DeviceSkippedWarning, HostMemoryError, InputError,
                     KernelBuildError, LargeTiffWarning, NoDeviceError)
from .ml.params import HEURISTICS
from .ml.driver import SweepInfo, SynthesisResult

__version__ = "0.1.0"

__all__ = [
    "synthesize", "resume", "select_device", "list_devices", "Device", "SweepInfo", "SynthesisResult",
    "HEURISTICS", "ClsolidError", "InputError", "NoDeviceError", "DeviceMemoryError", "HostMemoryError",
    "KernelBuildError", "DeviceSkippedWarning", "LargeTiffWarning", "__version__",
]
