"""The OpenCL platforms and devices as the driver lists them, and the chosen device's handles.

Nothing here touches OpenCL at import time: ``pyopencl`` is imported inside the
functions, so ``import clsolid`` works on a machine without any OpenCL driver.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..errors import NoDeviceError
from .icd import ensure_vendors

INSTALL_HINT = (
    "Install an OpenCL runtime: on a CPU-only x86-64 machine `pip install \"clsolid[cpu]\"` brings "
    "PoCL and Intel's CPU runtime (which compiles on any x86-64 CPU, AMD's included); "
    "on a GPU machine install the vendor's OpenCL driver"
)


@dataclass
class Device:
    """A chosen OpenCL device with its context and in-order queue.

    Attributes
    ----------
    device, context, queue
        The ``pyopencl`` objects.
    programs : dict
        Program cache of this context, keyed by (source, options); see ``clsolid.core.programs``.
    limits : dict
        Each kernel's work-group limit on this device, read once (:mod:`clsolid.core.launch`).
    group_cap : int or None
        A work-group limit below the device's (:attr:`max_group`).
    """

    device: Any
    context: Any
    queue: Any
    programs: dict = field(default_factory=dict, repr=False)
    limits: dict = field(default_factory=dict, repr=False)  # each kernel's work-group limit (core.launch)
    #: The most work-items clsolid puts in a work-group here, below the device's own limit
    #: (None: that limit): tests set it to the limits GPUs impose (docs/design.md#gpu-shaped-launches).
    group_cap: int | None = None

    @property
    def max_group(self) -> int:
        """The most work-items a work-group may hold: the device's limit, or :attr:`group_cap` below it."""
        own = int(self.device.max_work_group_size)
        return own if self.group_cap is None else min(own, int(self.group_cap))

    @property
    def name(self) -> str:
        return f"{self.device.platform.name.strip()} / {self.device.name.strip()}"

    @property
    def max_alloc(self) -> int:
        return int(self.device.max_mem_alloc_size)

    @property
    def global_mem(self) -> int:
        return int(self.device.global_mem_size)

    @property
    def is_cpu(self) -> bool:
        import pyopencl as cl

        return bool(self.device.type & cl.device_type.CPU)


def platforms() -> list:
    """Every OpenCL platform; :class:`~clsolid.errors.NoDeviceError` (saying what to install) if none."""
    ensure_vendors()  # before the first OpenCL call: makes a pip-installed Intel CPU runtime visible
    try:
        import pyopencl as cl
    except ImportError as exc:  # pragma: no cover - pyopencl is a hard dependency
        raise NoDeviceError(f"pyopencl cannot be imported ({exc}). {INSTALL_HINT}.") from exc
    try:
        platforms = cl.get_platforms()
    except cl.Error as exc:
        raise NoDeviceError(f"no OpenCL platform found ({exc}). {INSTALL_HINT}.") from exc
    if not platforms:
        raise NoDeviceError(f"no OpenCL platform found. {INSTALL_HINT}.")
    return platforms


def devices_of(platform: Any) -> list:
    """The devices of *platform* (none where it cannot list them)."""
    import pyopencl as cl

    try:
        return list(platform.get_devices())
    except cl.Error:
        return []
