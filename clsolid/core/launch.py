"""Kernel launches sized from the device's limits, never assumed.

Every kernel of clsolid takes its work item's job from its global id alone (no local memory,
no barriers, no atomics), so the work-group size changes how fast a launch runs, never what
it computes. It is asked for (a back end's ``local_size``, the matcher's :data:`LOCAL`), then
cut to what the device allows a work-group, to what the compiled kernel allows (a GPU's
limit shrinks with the registers a kernel needs), and to a power of two
(docs/design.md#gpu-shaped-launches).
"""

from __future__ import annotations

from typing import Any

from .platforms import Device


def _floor_pow2(n: int) -> int:
    return 1 << (max(int(n), 1).bit_length() - 1)


def kernel_limit(device: Device, kernel: Any) -> int:
    """The most work-items a work-group of *kernel* may hold on *device* (the device's limit,
    :attr:`Device.max_group`, and the compiled kernel's), read once per kernel."""
    key = kernel.int_ptr
    if key not in device.limits:
        import pyopencl as cl

        device.limits[key] = int(kernel.get_work_group_info(cl.kernel_work_group_info.WORK_GROUP_SIZE,
                                                            device.device))
    return min(device.limits[key], device.max_group)


def group_size(device: Device, kernel: Any, wanted: int) -> int:
    """The work-group size a launch of *kernel* takes: *wanted*, within the device's and the
    kernel's limits (:func:`kernel_limit`), rounded down to a power of two."""
    return _floor_pow2(min(int(wanted), kernel_limit(device, kernel)))


def launch(device: Device, kernel: Any, n_items: int, wanted: int, *args: Any) -> int:
    """Enqueue *kernel* over *n_items* work-items (rounded up to whole work-groups; the
    kernels return at once past their count) in work-groups of :func:`group_size`; returns
    that size."""
    local = group_size(device, kernel, wanted)
    kernel(device.queue, (-(-max(int(n_items), 1) // local) * local,), (local,), *args)
    return local
